//! The planner on single-view clouds of the dissertation's YCB objects (Table 5.2's set), for each
//! built-in hand: what the end-to-end tests assert, checked here without a transport.

use graspd_core::cloud::PointCloud;
use graspd_core::planning::{PlanHints, PlanInput, PlannerOptions, plan};
use graspd_core::{GraspPlan, HandCatalog};
use graspd_testkit::view::standard_view;
use graspd_testkit::ycb::Object;

const OBJECTS: [Object; 8] = Object::TABLE_5_2;

fn plan_view(object: Object, hand: &str, seed: u64) -> (GraspPlan, PointCloud) {
    let v = standard_view(object, 2000, seed);
    let cloud = v.object_cloud();
    let p = plan(PlanInput {
        cloud: cloud.clone(),
        hand: HandCatalog::builtin().get(hand).unwrap().clone(),
        hints: PlanHints {
            support_plane: Some(v.support_plane),
            viewpoint: Some(v.viewpoint),
            ..Default::default()
        },
        options: PlannerOptions {
            seed,
            ..Default::default()
        },
        kinematics: None,
        grasp_quality: None,
    })
    .unwrap();
    (p, cloud)
}

use graspd_testkit::ycb::MAX_INFERRED_OFF;

/// Every plan on every object and hand: seen contacts on the cloud, inferred ones near the
/// object's true surface, the hand's contact count, opposed
/// opposition normals, S ≥ ε or an explicit infeasibility, hand above the table.
#[test]
fn dissertation_objects_with_every_builtin_hand() {
    let catalog = HandCatalog::builtin();
    let mut infeasible = Vec::new();
    for hand in ["parallel_gripper", "barrett", "shadow"] {
        for object in OBJECTS {
            let (p, cloud) = plan_view(object, hand, 1);
            println!(
                "{hand:16} {:22} {:10} feasible={} S={:.2} R={:.2} G={:.2} eps={:.3} it=({},{}) best_at=({},{}) t={:.1}ms {:?}",
                object.id(),
                p.grasp_type.name(),
                p.feasible,
                p.quality.gii,
                p.quality.reachability,
                p.quality.attention,
                p.quality.epsilon,
                p.stage1.iterations,
                p.stage2.iterations,
                p.stage1.best_iteration,
                p.stage2.best_iteration,
                p.timings.total * 1e3,
                p.infeasible_reason
            );
            let m = catalog
                .get(hand)
                .unwrap()
                .resolve_forced(p.grasp_type)
                .unwrap()
                .contact_count();
            assert_eq!(p.contacts.len(), m, "{hand} {object:?}");
            for c in &p.contacts {
                if c.inferred {
                    // On the completed, unseen side: near the true surface.
                    let d = graspd_testkit::ycb::surface_distance(object, &c.position);
                    assert!(
                        d <= MAX_INFERRED_OFF,
                        "{hand} {object:?}: an inferred contact lies {d} m off the object"
                    );
                    continue;
                }
                let d = cloud
                    .points
                    .iter()
                    .map(|q| (q - c.position).norm())
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    d <= 0.003,
                    "{hand} {object:?}: contact {d} m from the cloud"
                );
                assert_eq!(cloud.points[c.point_index], c.position);
            }
            if p.feasible {
                let [n1, n2] = p.opposition.normals;
                assert!(
                    n1.angle(&n2).to_degrees() > 120.0,
                    "{hand} {object:?}: opposition normals"
                );
                assert!(p.quality.gii >= 0.7, "{hand} {object:?}");
                assert!(p.collision.clear, "{hand} {object:?}: {:?}", p.collision);
                assert!(p.collision.min_plane_clearance.unwrap() >= -0.001);
            } else {
                assert!(p.infeasible_reason.is_some());
                infeasible.push((hand, object));
            }
        }
    }
    // Measured with seed 1: 21 of 24 feasible. The misses (Barrett and Shadow on the banana, which
    // lies 37 mm high and curved; Shadow's five-contact precision grasp on the flat tuna can, whose
    // far wall a view from 40° above never sees) each carry their reason. Fewer than 20 fails.
    assert!(infeasible.len() <= 4, "infeasible: {infeasible:?}");
}
