//! Reach-to-grasp in clutter (issue 18 part 5; the dissertation's §3.4 experiment, Table 3.1):
//! "pick up the apple" from a table with several objects, through graspd's public API only.
//!
//! One trial:
//! 1. the target and 2–5 other shared YCB objects (seeded draw) are placed apart on the table
//!    (each at any yaw, within ±[`CLUTTER_RANGE`], at least [`GAP_M`] between footprints) and
//!    settle;
//! 2. the camera renders the scene and PlanGrasp plans with `hints.object` = the target's name
//!    (re-plans as the standard trial, [`crate::trial`]);
//! 3. **detection**: the object under the plan's attention pixel (else the one nearest its
//!    attention point) is the target;
//! 4. PlanReach from the hand's home pose ([`HOME`], the grasp's orientation) to the plan's
//!    grasp, with the frame as its scene (graspd makes the other objects obstacles); when
//!    graspd refuses the reach (the plan's pre-grasp point or approach too near another
//!    object), PlanGrasp is asked for [`CANDIDATES`] ranked plans and the reach to each is
//!    tried in turn, feasible plans first, as a robot stack falls back;
//! 5. the hand, pre-shaped, follows the reach and its approach to the grasp
//!    ([`Motion::Path`]); **collision-free reaching**: no hand body touches another object on
//!    the reach, up to the pre-grasp point (touches on the approach onto the grasp, which the
//!    grasp planner chose without the other objects, are counted apart);
//! 6. **grasping**: the standard close, lift, hold and shake of the target
//!    ([`grasp_and_lift`]).
//!
//! The table counts each over all trials, as the dissertation's Table 3.1 does.

use crate::SimError;
use crate::bench::{in_parallel, trials_bar};
use crate::camera::RgbdImage;
use crate::hand::SimHand;
use crate::object::SimObject;
use crate::record::{Outcome, TrialRecord};
use crate::scene::{Scene, on_table};
use crate::service::{PlanAsk, PlanResult, Service};
use crate::trial::{
    APPROACH_S, Motion, Trial, TrialOptions, grasp_and_lift, pre_grasp_and_approach, take_candidate,
};
use graspd_api::convert::pose_from_proto;
use nalgebra::{Isometry3, Point3, Translation3};
use rand::{RngExt, SeedableRng};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Mutex;

/// Half-width of the square the objects are placed in, m.
pub const CLUTTER_RANGE: f64 = 0.16;
/// Least gap between two objects' footprint circles, m.
pub const GAP_M: f64 = 0.02;
/// Ranked plans asked of PlanGrasp when the reach to its best is refused, tried in turn until
/// graspd plans a reach to one.
pub const CANDIDATES: u32 = 5;
/// The hand frame's home position (world, m): above the table's centre, out of the objects'
/// way, where a robot arm would hold it between tasks.
pub const HOME: [f64; 3] = [0.0, 0.0, 0.40];

/// What one clutter trial did.
#[derive(Debug, Clone, Serialize)]
pub struct ClutterRecord {
    pub target: String,
    /// The other objects on the table.
    pub others: Vec<String>,
    /// The object graspd planned for (`None`: no plan, e.g. not found).
    pub chosen: Option<String>,
    pub detected: bool,
    /// PlanReach: whether it answered for one of the plans, how many it was asked for, the
    /// least clearance it reports to the obstacles graspd made of the frame's other objects,
    /// and its server time.
    pub reach_planned: bool,
    pub reach_attempts: usize,
    /// Why graspd refused the reach to the first candidate, when it did.
    pub reach_refused: Option<String>,
    pub reach_clearance_mm: Option<f64>,
    pub reach_server_ms: Option<f64>,
    /// No hand body touched another object on the reach, up to the pre-grasp point (None: no
    /// reach executed), and none on the approach onto the grasp either.
    pub collision_free: Option<bool>,
    pub approach_clear: Option<bool>,
    /// Round trips of every PlanGrasp (re-plans and the ranked plans of a fall-back included)
    /// and every PlanReach of the trial, ms: the whole request, frame → object → grasp →
    /// trajectory, as the robot stack waited for it.
    pub plan_ms: Option<f64>,
    pub reach_ms: Option<f64>,
    /// The first PlanGrasp and the first PlanReach round trips, ms: one request of each.
    pub first_plan_ms: Option<f64>,
    pub first_reach_ms: Option<f64>,
    /// graspd's own time in PlanGrasp: perception (decode, saliency, segmentation, the
    /// recogniser, grasp type) and planning, ms.
    pub perception_ms: Option<f64>,
    pub planning_ms: Option<f64>,
    /// Perception's steps, ms: decode, saliency, segmentation (the recogniser included),
    /// recognition, ROI, grasp type.
    pub perception_steps_ms: Option<[f64; 6]>,
    pub grasped: bool,
    /// The grasp trial's record (placement = the target's).
    pub trial: TrialRecord,
}

/// Trial `seed`'s objects (indices into `pool`, the target first: `target`, then 2–5 others)
/// and their placements (x, y, yaw); `radius[i]` is object i's footprint radius.
pub fn layout(seed: u64, target: usize, radius: &[f64]) -> (Vec<usize>, Vec<[f64; 3]>) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5851_f42d_4c95_7f2d);
    let others = rng.random_range(2..=5usize);
    let mut pool: Vec<usize> = (0..radius.len()).filter(|&i| i != target).collect();
    let mut chosen = vec![target];
    for _ in 0..others.min(pool.len()) {
        chosen.push(pool.swap_remove(rng.random_range(0..pool.len())));
    }
    let mut kept = Vec::new();
    let mut places: Vec<[f64; 3]> = Vec::new();
    for &i in &chosen {
        let spot = (0..200).find_map(|_| {
            let (x, y) = (
                rng.random_range(-CLUTTER_RANGE..CLUTTER_RANGE),
                rng.random_range(-CLUTTER_RANGE..CLUTTER_RANGE),
            );
            let apart = kept
                .iter()
                .zip(&places)
                .all(|(&j, p): (&usize, &[f64; 3])| {
                    ((x - p[0]).powi(2) + (y - p[1]).powi(2)).sqrt() > radius[i] + radius[j] + GAP_M
                });
            apart.then_some((x, y))
        });
        // The target always finds room (it goes first); another that does not is left out.
        if let Some((x, y)) = spot {
            kept.push(i);
            places.push([
                x,
                y,
                rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
            ]);
        }
    }
    (kept, places)
}

/// The object (index into the scene's objects) under the plan's attention pixel, else the one
/// whose centre is nearest its attention point.
fn chosen_object(trial: &Trial, image: &RgbdImage, plan: &PlanResult) -> Option<usize> {
    let bodies = &trial.scene.object_bodies;
    let at = plan.response.attention.as_ref()?;
    if let Some(px) = &at.pixel {
        let w = image.intrinsics.width as usize;
        let (u, v) = (px.u as usize, px.v as usize);
        if let Some(Some(g)) = image.geoms.get(v * w + u) {
            let b = trial.scene.model.geom_bodyid()[*g] as usize;
            if let Some(k) = bodies.iter().position(|&o| o == b) {
                return Some(k);
            }
        }
    }
    let p = at.position.as_ref()?;
    let p = Point3::new(p.x, p.y, p.z);
    (0..bodies.len()).min_by(|&a, &b| {
        let d = |k: usize| (Point3::from(trial.data.xipos()[bodies[k]]) - p).norm();
        d(a).total_cmp(&d(b))
    })
}

/// A clutter trial's settings: the standard trial's, and the hand's radius for PlanReach.
#[derive(Debug, Clone, Copy)]
pub struct ClutterOptions {
    pub trial: TrialOptions,
    /// The sphere that stands for the hand in PlanReach, m (None: graspd's default).
    pub hand_radius: Option<f64>,
}

/// One trial with `objects[target]` as the target (module docs).
pub fn run_clutter_trial(
    hand: &SimHand,
    objects: &[SimObject],
    target: usize,
    service: &Service,
    seed: u64,
    opts: &ClutterOptions,
) -> Result<ClutterRecord, SimError> {
    let (copts, opts) = (opts, &opts.trial);
    let radius: Vec<f64> = objects
        .iter()
        .map(|o| 0.5 * (o.extents.x.powi(2) + o.extents.y.powi(2)).sqrt())
        .collect();
    let (chosen, places) = layout(seed, target, &radius);
    let placed: Vec<(&SimObject, Isometry3<f64>)> = chosen
        .iter()
        .zip(&places)
        .map(|(&i, p)| (&objects[i], on_table(p[0], p[1], p[2])))
        .collect();
    let scene = Scene::build(hand, &placed)?;
    let name = objects[target].name.clone();
    let mut rec = ClutterRecord {
        target: name.clone(),
        others: chosen[1..]
            .iter()
            .map(|&i| objects[i].name.clone())
            .collect(),
        chosen: None,
        detected: false,
        reach_planned: false,
        reach_attempts: 0,
        reach_refused: None,
        reach_clearance_mm: None,
        reach_server_ms: None,
        collision_free: None,
        approach_clear: None,
        plan_ms: None,
        reach_ms: None,
        first_plan_ms: None,
        first_reach_ms: None,
        perception_ms: None,
        planning_ms: None,
        perception_steps_ms: None,
        grasped: false,
        trial: TrialRecord::empty(hand, &name, seed, places[0]),
    };
    let mut trial = Trial::with_placements(&scene, &places);
    let start = trial.object_position();
    let image = trial.render(opts.intrinsics, opts.camera);
    let mut ask = PlanAsk {
        object: Some(name.clone()),
        mode: opts.mode,
        ..PlanAsk::default()
    };
    let mut plan_s = 0.0;
    let mut first_plan_s = None;
    let mut timed = |seed: u64, ask: &PlanAsk| {
        let t0 = std::time::Instant::now();
        let p = service.plan(hand, &image, &[], None, seed, ask);
        let s = t0.elapsed().as_secs_f64();
        plan_s += s;
        first_plan_s.get_or_insert(s);
        p
    };
    let mut plan = timed(seed, &ask);
    let mut attempts = 1;
    let mut plan_seed = seed;
    while attempts <= opts.replans && matches!(&plan, Ok(p) if !p.response.feasible) {
        let s = seed + 1000 * attempts as u64;
        let again = timed(s, &ask);
        attempts += 1;
        if matches!(&again, Ok(p) if p.response.feasible) {
            plan = again;
            plan_seed = s;
        }
    }
    rec.trial.plan_attempts = attempts;
    let plan = match plan {
        Ok(p) => p,
        Err(s) => {
            rec.trial.detail = format!("{}: {}", s.code(), s.message());
            return Ok(rec);
        }
    };
    let k = chosen_object(&trial, &image, &plan);
    rec.chosen = k.map(|k| objects[chosen[k]].name.clone());
    rec.detected = k == Some(0);
    // The reach from home, the hand already turned as the grasp needs.
    let mut try_reach = |candidate: PlanResult| -> Result<_, SimError> {
        rec.reach_attempts += 1;
        let goal = pose_from_proto(&candidate.response.hand_pose, "hand_pose")
            .map_err(|e| SimError::Service(format!("PlanGrasp: {e}")))?
            .isometry();
        let home =
            Isometry3::from_parts(Translation3::new(HOME[0], HOME[1], HOME[2]), goal.rotation);
        let t0 = std::time::Instant::now();
        // The approach as the standard trial's.
        let answer = service.reach(
            &home,
            &candidate.response,
            &image,
            copts.hand_radius,
            APPROACH_S,
        );
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        *rec.reach_ms.get_or_insert(0.0) += ms;
        rec.first_reach_ms.get_or_insert(ms);
        Ok(match answer {
            Ok(r) => Some((candidate, r)),
            Err(s) => {
                if rec.reach_refused.is_none() {
                    rec.reach_refused = Some(s.message().to_string());
                }
                None
            }
        })
    };
    let mut reached = try_reach(plan.clone())?;
    if reached.is_none() {
        // Refused: the ranked plans, feasible ones first, the one just refused left out.
        ask.candidates = CANDIDATES;
        if let Ok(more) = timed(plan_seed, &ask) {
            let ranked = &more.response.candidates;
            let refused = &plan.response.hand_pose;
            let mut order: Vec<usize> = (0..ranked.len()).filter(|&i| ranked[i].feasible).collect();
            order.extend((0..ranked.len()).filter(|&i| !ranked[i].feasible));
            for c in order {
                if ranked[c].hand_pose == *refused {
                    continue;
                }
                let mut candidate = more.clone();
                take_candidate(&mut candidate.response, c);
                reached = try_reach(candidate)?;
                if reached.is_some() {
                    break;
                }
            }
        }
    }
    let Some((plan, reach)) = reached else {
        rec.trial.detail = format!(
            "PlanReach refused all {} candidates; the first: {}",
            rec.reach_attempts,
            rec.reach_refused.clone().unwrap_or_default()
        );
        return Ok(rec);
    };
    rec.reach_planned = true;
    rec.plan_ms = Some(plan_s * 1e3);
    rec.first_plan_ms = first_plan_s.map(|s| s * 1e3);
    rec.perception_ms = plan
        .response
        .perception
        .as_ref()
        .and_then(|p| p.timings.as_ref())
        .map(|t| t.total * 1e3);
    rec.planning_ms = plan.response.timings.as_ref().map(|t| t.total * 1e3);
    rec.perception_steps_ms = plan
        .response
        .perception
        .as_ref()
        .and_then(|p| p.timings.as_ref())
        .map(|t| {
            [
                t.decode,
                t.saliency,
                t.segmentation,
                t.recognition,
                t.roi,
                t.grasp_type,
            ]
            .map(|s| s * 1e3)
        });
    rec.reach_clearance_mm = reach.obstacle_clearance.map(|c| c * 1e3);
    rec.reach_server_ms = Some(reach.server_ms);
    let path: Vec<(f64, Isometry3<f64>)> = reach
        .samples
        .iter()
        .filter_map(|s| {
            let p = pose_from_proto(&s.pose, "pose").ok()?;
            Some((s.time, p.isometry()))
        })
        .collect();
    let motion = Motion::Path {
        path: &path,
        approach_s: APPROACH_S,
    };
    let approached = pre_grasp_and_approach(&mut trial, &plan, start, motion, &mut rec.trial);
    rec.collision_free = Some(rec.trial.touched_in_reach.is_empty());
    rec.approach_clear = Some(rec.trial.touched_others.is_empty());
    rec.trial.outcome = match approached {
        Ok(a) => grasp_and_lift(&mut trial, a, opts, &mut rec.trial),
        Err(o) => o,
    };
    rec.grasped = rec.trial.outcome == Outcome::Success;
    Ok(rec)
}

/// The clutter benchmark's settings.
pub struct ClutterConfig {
    pub hand: String,
    /// Target objects (each in turn); the others are drawn from the same list.
    pub objects: Vec<String>,
    /// Trials per target object.
    pub trials: usize,
    pub seed: u64,
    pub jobs: usize,
    pub out: PathBuf,
    pub hands_dir: PathBuf,
    pub objects_dir: PathBuf,
    pub options: ClutterOptions,
}

/// The benchmark's result (`results.json`) and its Table 3.1 (`table.md`).
#[derive(Debug, Serialize)]
pub struct ClutterReport {
    pub hand: String,
    pub trials: usize,
    pub detected: usize,
    pub grasped: usize,
    /// Reaches executed, those that touched no other object up to the pre-grasp point, and
    /// those that touched none before the close.
    pub reaches: usize,
    pub collision_free: usize,
    pub approaches_clear: usize,
    /// Medians of the first PlanGrasp + PlanReach round trips (one whole request) and of all
    /// of a trial's (with its re-plans and fall-backs), ms.
    pub request_ms_p50: Option<f64>,
    pub trial_calls_ms_p50: Option<f64>,
    pub wall_s: f64,
    pub records: Vec<ClutterRecord>,
    #[serde(skip)]
    pub markdown: String,
}

/// Runs every target object `trials` times (seeds `seed..seed + trials`).
pub fn run_clutter_bench(
    config: &ClutterConfig,
    service: &Service,
) -> Result<ClutterReport, SimError> {
    let hand = SimHand::load(&config.hand, &config.hands_dir)?;
    service.ensure_hand(&hand)?;
    let objects: Vec<SimObject> = config
        .objects
        .iter()
        .map(|o| SimObject::load(&config.objects_dir, o))
        .collect::<Result<_, _>>()?;
    let work: Vec<(usize, u64)> = (0..objects.len())
        .flat_map(|o| (0..config.trials).map(move |i| (o, config.seed + i as u64)))
        .collect();
    let bar = trials_bar(work.len() as u64);
    let results: Mutex<Vec<ClutterRecord>> = Mutex::new(Vec::new());
    let errors: Mutex<Vec<SimError>> = Mutex::new(Vec::new());
    let t0 = std::time::Instant::now();
    in_parallel(config.jobs, &work, |&(o, seed)| {
        // Each trial its own seed, so that the draw of the others differs per target too.
        let seed = seed * 100 + o as u64;
        match run_clutter_trial(&hand, &objects, o, service, seed, &config.options) {
            Ok(r) => {
                bar.set_message(format!("{} {}", r.target, r.trial.outcome.name()));
                results.lock().expect("results").push(r);
            }
            Err(e) => errors.lock().expect("errors").push(e),
        }
        bar.inc(1);
    });
    bar.finish_and_clear();
    if let Some(e) = errors.into_inner().expect("errors").into_iter().next() {
        return Err(e);
    }
    let mut records = results.into_inner().expect("results");
    records.sort_by(|a, b| (&a.target, a.trial.seed).cmp(&(&b.target, b.trial.seed)));
    let count = |f: &dyn Fn(&ClutterRecord) -> bool| records.iter().filter(|r| f(r)).count();
    let mut report = ClutterReport {
        hand: hand.name.clone(),
        trials: records.len(),
        detected: count(&|r| r.detected),
        grasped: count(&|r| r.grasped),
        reaches: count(&|r| r.collision_free.is_some()),
        collision_free: count(&|r| r.collision_free == Some(true)),
        approaches_clear: count(&|r| r.approach_clear == Some(true)),
        request_ms_p50: median(
            records
                .iter()
                .filter_map(|r| Some(r.first_plan_ms? + r.first_reach_ms?))
                .collect(),
        ),
        trial_calls_ms_p50: median(
            records
                .iter()
                .filter_map(|r| Some(r.plan_ms? + r.reach_ms?))
                .collect(),
        ),
        wall_s: t0.elapsed().as_secs_f64(),
        records,
        markdown: String::new(),
    };
    report.markdown = markdown(&report);
    std::fs::create_dir_all(&config.out)
        .map_err(|e| SimError::Input(format!("--out {}: {e}", config.out.display())))?;
    let write = |name: &str, text: &str| {
        std::fs::write(config.out.join(name), text)
            .map_err(|e| SimError::Input(format!("--out {}: {e}", config.out.display())))
    };
    write(
        "results.json",
        &(serde_json::to_string_pretty(&report).unwrap_or_default() + "\n"),
    )?;
    write("table.md", &report.markdown)?;
    Ok(report)
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

fn pct(n: usize, d: usize) -> String {
    if d == 0 {
        "–".into()
    } else {
        format!("{:.1} % ({n}/{d})", 100.0 * n as f64 / d as f64)
    }
}

/// Table 3.1's layout, then one row per target object.
pub fn markdown(r: &ClutterReport) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "| | graspd, {} in MuJoCo (this run) | dissertation, KUKA + WSG 50 (Table 3.1) |\n|---|---|---|\n",
        r.hand
    ));
    s.push_str(&format!(
        "| detection | {} | 95.8 % (46/48) |\n",
        pct(r.detected, r.trials)
    ));
    s.push_str(&format!(
        "| grasping | {} | 81.2 % (39/48) |\n",
        pct(r.grasped, r.trials)
    ));
    s.push_str(&format!(
        "| collision-free reaching | {} of the reaches executed ({} of {} trials got one) | 100 % (48/48) |\n",
        pct(r.collision_free, r.reaches),
        r.reaches,
        r.trials
    ));
    s.push_str(&format!(
        "| ... and the approach onto the grasp too | {} | – |\n",
        pct(r.approaches_clear, r.reaches)
    ));
    if let (Some(one), Some(all)) = (r.request_ms_p50, r.trial_calls_ms_p50) {
        s.push_str(&format!(
            "| frame → object → grasp → trajectory: one PlanGrasp + PlanReach round trip, p50 (all of a trial's, re-plans and fall-backs included) | {one:.0} ms ({all:.0} ms) | – |\n"
        ));
    }
    s.push_str("\n| target | trials | detected | grasped | reach collision-free | approach clear | failures |\n|---|---|---|---|---|---|---|\n");
    let mut targets: Vec<&str> = r.records.iter().map(|x| x.target.as_str()).collect();
    targets.dedup();
    for t in targets {
        let rs: Vec<&ClutterRecord> = r.records.iter().filter(|x| x.target == t).collect();
        let mut fails: Vec<String> = Vec::new();
        for o in Outcome::ALL.iter().filter(|o| **o != Outcome::Success) {
            let n = rs.iter().filter(|x| x.trial.outcome == *o).count();
            if n > 0 {
                fails.push(format!("{} {n}", o.name()));
            }
        }
        s.push_str(&format!(
            "| {t} | {} | {} | {} | {} | {} | {} |\n",
            rs.len(),
            rs.iter().filter(|x| x.detected).count(),
            rs.iter().filter(|x| x.grasped).count(),
            rs.iter().filter(|x| x.collision_free == Some(true)).count(),
            rs.iter().filter(|x| x.approach_clear == Some(true)).count(),
            fails.join(", ")
        ));
    }
    s.push_str(&format!("\n{} trials, {:.0} s wall.\n", r.trials, r.wall_s));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The target comes first, 3–6 objects in all, none overlapping, all within the range; the
    /// same seed gives the same layout.
    #[test]
    fn layouts_place_the_target_first_and_apart() {
        let radius = vec![
            0.04, 0.06, 0.03, 0.05, 0.08, 0.035, 0.045, 0.05, 0.03, 0.06, 0.04, 0.04,
        ];
        for seed in 0..50 {
            let (objs, places) = layout(seed, seed as usize % 12, &radius);
            assert_eq!(objs[0], seed as usize % 12);
            assert!((3..=6).contains(&objs.len()), "{objs:?}");
            assert_eq!(objs.len(), places.len());
            for (a, pa) in objs.iter().zip(&places) {
                assert!(pa[0].abs() <= CLUTTER_RANGE && pa[1].abs() <= CLUTTER_RANGE);
                for (b, pb) in objs.iter().zip(&places) {
                    if a != b {
                        let d = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
                        assert!(d > radius[*a] + radius[*b] + GAP_M - 1e-12);
                    }
                }
            }
            assert_eq!(layout(seed, seed as usize % 12, &radius), (objs, places));
        }
    }
}
