//! Posture synergies of the shared hands (issue 19 part 1, dissertation §7.3): fitted to the
//! planner's own grasp postures over the generated objects, they span every posture (Eq 7.3
//! reconstructs each from its amplitudes), order the variance, give a grasp type that uses
//! other fingers its own region, and come out the same for the same seed.

use graspd_core::GraspType;
use graspd_core::hand::PostureSynergies;
use graspd_core::hand::kinematics::KinematicHand;
use graspd_core::planning::KinematicModel;
use graspd_core::planning::synergy_postures::{OBJECTS, synergy_postures};
use std::sync::Arc;
use std::time::Instant;

fn model(file: &str) -> Arc<KinematicModel> {
    let path = graspd_testkit::testdata_dir().join("hands").join(file);
    let hand =
        KinematicHand::from_mjcf_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Arc::new(KinematicModel::new(hand).unwrap())
}

#[test]
fn the_shadow_hands_synergies_span_its_planned_postures() {
    let m = model("shadow_hand/right_hand.xml");
    let t = Instant::now();
    let (names, postures, plans) = synergy_postures(&m, 0).unwrap();
    let took = t.elapsed();
    let s = PostureSynergies::fit(names.clone(), &postures).unwrap();
    let types = m.describe().unwrap().realisable_types();
    println!(
        "shadow: {} postures of {plans} plans in {took:.1?}; explained {:?}; centres {:?}",
        postures.len(),
        s.components
            .iter()
            .take(4)
            .map(|c| (c.explained * 1000.0).round() / 1000.0)
            .collect::<Vec<_>>(),
        s.centres
            .iter()
            .map(|c| (c.grasp_type.name(), c.postures, c.amplitudes[..2].to_vec()))
            .collect::<Vec<_>>()
    );
    assert_eq!(plans, OBJECTS.len() * types.len());
    // Every joint of the model, named once.
    assert_eq!(names.len(), m.hand.tree.joints.len());
    // 27 of 54 today; at least 40 %.
    assert!(
        postures.len() * 5 >= plans * 2,
        "{} feasible of {plans}",
        postures.len()
    );
    // Falling variance; the shares sum to one.
    for w in s.components.windows(2) {
        assert!(w[0].variance >= w[1].variance);
    }
    let total: f64 = s.components.iter().map(|c| c.explained).sum();
    assert!((total - 1.0).abs() < 1e-9, "{total}");
    // Eq 7.3 with every component gives each posture back.
    for p in &postures {
        let back = s.posture(&s.amplitudes(&p.joints, s.components.len()));
        for (a, b) in back.iter().zip(&p.joints) {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
    }
    // Two components carry most of the variance (human grasps: over 80 %, Santello et al.).
    let two = s.components[0].explained + s.components[1].explained;
    assert!(two >= 0.6, "{two}");
    // The tripod, which leaves the ring and little fingers out, has its own region of the
    // (a₁, a₂) plane: each tripod posture lies nearer its centre than any other type's.
    let tripods: Vec<_> = postures
        .iter()
        .filter(|p| p.grasp_type == GraspType::Tripod)
        .collect();
    assert!(tripods.len() >= 3, "{} tripod postures", tripods.len());
    for p in tripods {
        let own = s.hand_distance(&p.joints, GraspType::Tripod).unwrap();
        for c in s
            .centres
            .iter()
            .filter(|c| c.grasp_type != GraspType::Tripod)
        {
            let other = s.hand_distance(&p.joints, c.grasp_type).unwrap();
            assert!(
                own < other,
                "{own} from the tripod centre, {other} from {:?}'s",
                c.grasp_type
            );
        }
    }
    // The same seed, the same space.
    let (_, again, _) = synergy_postures(&m, 0).unwrap();
    assert_eq!(PostureSynergies::fit(names, &again).unwrap(), s);
}
