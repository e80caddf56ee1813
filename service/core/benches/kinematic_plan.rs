//! The added cost of a hand's kinematics per plan (issue 6): for each shared hand
//! (../shared/testdata/hands), plans on 2,000-point single views of the Table 5.2 YCB objects,
//! once with the description derived from the model only (the parametric planner) and once with
//! the kinematics (stage 1, then the final-configuration search with the model in the loop:
//! placement, closing sweep, squeeze, pre-grasp; docs/final-configuration.md). "final joints" is
//! the time of that search (`timings.finalize`). One thread; medians over objects × seeds.
//! `cargo bench -p graspd-core --bench kinematic_plan` (`-- --quick`: 2 seeds; `-- --hand NAME`:
//! that hand only; `-- --why`: why each infeasible plan is). The digest of
//! each hand's kinematic plans (poses, joints, contacts, quality, feasibility; a hash of their
//! exact values; comparable between builds of one toolchain) shows whether a change meant to be
//! faster changed any plan.

use graspd_core::hand::kinematics::KinematicHand;
use graspd_core::planning::{KinematicModel, PlanHints, PlanInput, PlannerOptions, plan};
use graspd_testkit::view::standard_view;
use graspd_testkit::ycb::Object;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::sync::Arc;
use std::time::Instant;

const HANDS: [(&str, &str); 4] = [
    ("shadow", "shadow_hand/right_hand.xml"),
    ("allegro", "wonik_allegro/right_hand.xml"),
    ("robotiq_2f85", "robotiq_2f85/2f85.xml"),
    ("barrett", "barrett/wam_barrett_gripper.xml"),
];

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seeds: u64 = if args.iter().any(|a| a == "--quick") {
        2
    } else {
        5
    };
    // `--why`: each infeasible kinematic plan's object, seed and reason.
    let why = args.iter().any(|a| a == "--why");
    // `--hand NAME` (repeatable): only those hands (their digests are the same as in a full run).
    let only: Vec<&str> = args
        .windows(2)
        .filter(|w| w[0] == "--hand")
        .map(|w| w[1].as_str())
        .collect();
    if let Some(unknown) = only.iter().find(|h| !HANDS.iter().any(|(n, _)| n == *h)) {
        let known: Vec<&str> = HANDS.iter().map(|(n, _)| *n).collect();
        panic!("--hand {unknown}: not one of {known:?}");
    }
    let dir = graspd_testkit::testdata_dir().join("hands");
    println!(
        "hand          plans  median ms (parametric | kinematic | added)  final joints ms  p90 kinematic ms  feasible (parametric | kinematic)"
    );
    for (name, file) in HANDS {
        if !only.is_empty() && !only.contains(&name) {
            continue;
        }
        let t = Instant::now();
        let hand = KinematicHand::from_mjcf_file(dir.join(file)).unwrap();
        let model = Arc::new(KinematicModel::new(hand).unwrap());
        let description = model.describe().unwrap();
        let load_ms = t.elapsed().as_secs_f64() * 1e3;
        let (mut base, mut kin, mut fin) = (Vec::new(), Vec::new(), Vec::new());
        let (mut base_ok, mut kin_ok) = (0, 0);
        let mut digest = DefaultHasher::new();
        for object in Object::TABLE_5_2 {
            for seed in 1..=seeds {
                let view = standard_view(object, 2000, seed);
                let input = |kinematics: Option<Arc<KinematicModel>>| PlanInput {
                    cloud: view.object_cloud(),
                    hand: description.clone(),
                    hints: PlanHints {
                        support_plane: Some(view.support_plane),
                        viewpoint: Some(view.viewpoint),
                        ..Default::default()
                    },
                    options: PlannerOptions {
                        seed,
                        ..Default::default()
                    },
                    kinematics,
                    grasp_quality: None,
                };
                let p = plan(input(None)).unwrap();
                base.push(p.timings.total * 1e3);
                base_ok += usize::from(p.feasible);
                let p = plan(input(Some(model.clone()))).unwrap();
                kin.push(p.timings.total * 1e3);
                fin.push(p.timings.finalize * 1e3);
                kin_ok += usize::from(p.feasible);
                if why && !p.feasible {
                    println!(
                        "  {name} {object:?} seed {seed}: {} ({:?}, {} contacts, robustness {:.2})",
                        p.infeasible_reason.as_deref().unwrap_or("?"),
                        p.grasp_type,
                        p.contacts.len(),
                        p.quality.robustness
                    );
                }
                // Debug prints floats exactly (shortest round trip).
                format!(
                    "{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}",
                    p.hand_pose,
                    p.joints,
                    p.pregrasp_joints,
                    p.squeeze_joints,
                    p.contacts,
                    p.quality,
                    p.feasible,
                    p.infeasible_reason
                )
                .hash(&mut digest);
            }
        }
        let n = base.len();
        let (mb, mk) = (median(&mut base), median(&mut kin));
        let p90 = kin[(0.9 * (n - 1) as f64).round() as usize];
        println!(
            "{name:13} {n:5}  {mb:8.2} | {mk:8.2} | {:+7.2}            {:8.2}         {p90:8.2}          {base_ok:2}/{n} | {kin_ok:2}/{n}   (model load + description {load_ms:.0} ms)  plans digest {:016x}",
            mk - mb,
            median(&mut fin),
            digest.finish(),
        );
    }
}
