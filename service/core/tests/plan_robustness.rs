//! The planner never panics: random and degenerate clouds (coincident, collinear, coplanar,
//! duplicated points) give a plan — feasible or explicitly not — or a field error.

use graspd_core::cloud::{Plane, PointCloud};
use graspd_core::planning::{PlanHints, PlanInput, PlannerOptions, plan};
use graspd_core::{GraspType, HandCatalog, PlanError};
use nalgebra::{Point3, Vector3};
use proptest::prelude::*;

fn run(points: Vec<Point3<f64>>, hand: &str, seed: u64, plane: bool, forced: Option<GraspType>) {
    let input = PlanInput {
        cloud: PointCloud::new(points),
        hand: HandCatalog::builtin().get(hand).unwrap().clone(),
        hints: PlanHints {
            support_plane: plane
                .then(|| Plane::through(&Point3::new(0.0, 0.0, -0.3), Vector3::z())),
            grasp_type: forced,
            ..Default::default()
        },
        options: PlannerOptions {
            seed,
            max_iterations: 200,
            ..Default::default()
        },
        kinematics: None,
        grasp_quality: None,
    };
    match plan(input) {
        Ok(p) => {
            assert!(p.feasible || p.infeasible_reason.is_some());
            assert!(p.quality.gii.is_finite() && p.quality.objective.is_finite());
            assert!(p.hand_pose.position.coords.iter().all(|v| v.is_finite()));
        }
        Err(PlanError::InvalidInput(e)) => assert!(!e.field.is_empty()),
        Err(e) => panic!("unexpected error {e}"),
    }
}

const HANDS: [&str; 3] = ["parallel_gripper", "barrett", "shadow"];

#[test]
fn degenerate_clouds() {
    let same = vec![Point3::new(0.01, 0.02, 0.03); 64];
    let line: Vec<_> = (0..64)
        .map(|i| Point3::new(i as f64 * 0.001, 0.0, 0.0))
        .collect();
    let square: Vec<_> = (0..100)
        .map(|i| Point3::new((i % 10) as f64 * 0.005, (i / 10) as f64 * 0.005, 0.0))
        .collect();
    let mut doubled = square.clone();
    doubled.extend(square.iter().copied());
    for hand in HANDS {
        for pts in [&same, &line, &square, &doubled] {
            for plane in [false, true] {
                run(pts.clone(), hand, 1, plane, None);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn random_clouds_never_panic(
        pts in prop::collection::vec((-0.1f64..0.1, -0.1f64..0.1, -0.1f64..0.1), 32..160),
        hand in 0usize..3,
        seed in any::<u64>(),
        plane in any::<bool>(),
        forced in prop::option::of(0usize..6),
    ) {
        let points = pts.into_iter().map(|(x, y, z)| Point3::new(x, y, z)).collect();
        let forced = forced.and_then(GraspType::from_index);
        // A forced type the hand cannot realise is a field error, also fine.
        run(points, HANDS[hand], seed, plane, forced);
    }
}
