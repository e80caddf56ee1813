//! The planner with the shared hands' kinematics (issue 6 §2–§3): plans on the dissertation's YCB
//! views come back with joints inside the limits, per-contact IK residuals, and the final
//! configuration clear of the support plane; unreachable contact sets are never feasible.

use graspd_core::hand::kinematics::KinematicHand;
use graspd_core::planning::{
    GraspPlan, KinematicModel, PlanHints, PlanInput, PlannerOptions, plan,
};
use graspd_testkit::view::standard_view;
use graspd_testkit::ycb::Object;
use std::sync::Arc;

const SHARED_HANDS: [&str; 4] = [
    "shadow_hand/right_hand.xml",
    "wonik_allegro/right_hand.xml",
    "robotiq_2f85/2f85.xml",
    "barrett/wam_barrett_gripper.xml",
];

fn model(file: &str) -> Arc<KinematicModel> {
    let path = graspd_testkit::testdata_dir().join("hands").join(file);
    let hand =
        KinematicHand::from_mjcf_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Arc::new(KinematicModel::new(hand).unwrap())
}

fn plan_with(model: &Arc<KinematicModel>, object: Object, seed: u64) -> GraspPlan {
    let v = standard_view(object, 2000, seed);
    plan(PlanInput {
        cloud: v.object_cloud(),
        hand: model.describe().unwrap(),
        hints: PlanHints {
            support_plane: Some(v.support_plane),
            viewpoint: Some(v.viewpoint),
            ..Default::default()
        },
        options: PlannerOptions {
            seed,
            ..Default::default()
        },
        kinematics: Some(model.clone()),
    })
    .unwrap()
}

/// Each shared hand on the Table 5.2 objects: every joint of the model named once and inside its
/// limits, a residual for every finger contact, feasible plans reach their contacts within 5 mm
/// and their final configuration is clear of the support plane and the object; at least one
/// feasible plan per hand (IK and collisions are hard constraints: most optima of the
/// multi-finger hands are rejected; see the printed table).
#[test]
fn shared_hands_plan_reachable_grasps_on_ycb_views() {
    let mut low = Vec::new();
    for file in SHARED_HANDS {
        let m = model(file);
        let mut feasible = 0;
        let mut total = 0;
        for object in Object::TABLE_5_2 {
            let p = plan_with(&m, object, 1);
            total += 1;
            println!(
                "{file:34} {:22} {:10} feasible={} S={:.2} R={:.2} res={:?} plane={:?} pts={} t={:.1}ms fin={:.1}ms {:?} {:?}",
                object.id(),
                p.grasp_type.name(),
                p.feasible,
                p.quality.gii,
                p.quality.reachability,
                p.contacts
                    .iter()
                    .map(|c| c.ik_residual.map(|r| (r * 1e4).round() / 10.0))
                    .collect::<Vec<_>>(),
                p.collision
                    .final_plane_clearance
                    .map(|c| (c * 1e4).round() / 10.0),
                p.collision.final_points_in_collision,
                p.timings.total * 1e3,
                p.timings.finalize * 1e3,
                p.infeasible_reason,
                p.warnings,
            );
            assert_eq!(p.joints.len(), m.hand.tree.joints.len(), "{file}");
            for ((name, angle), joint) in p.joints.iter().zip(&m.hand.tree.joints) {
                assert_eq!(name, &joint.name);
                let (lo, hi) = joint.limits();
                assert!(
                    *angle >= lo - 1e-12 && *angle <= hi + 1e-12,
                    "{file} {object:?}: {name} = {angle} outside [{lo}, {hi}]"
                );
            }
            for c in &p.contacts {
                assert_eq!(c.ik_residual.is_some(), c.finger != "palm", "{file}");
            }
            // root_pose: mounting the model there at the planned joints puts its hand frame on
            // hand_pose (what a simulator or an arm does with the plan).
            let q: Vec<f64> = p.joints.iter().map(|(_, v)| *v).collect();
            let posed = p.root_pose.expect("root_pose with kinematics").isometry()
                * m.hand.hand_frame_in_root(&q).unwrap();
            let want = p.hand_pose.isometry();
            assert!(
                (posed.translation.vector - want.translation.vector).norm() < 1e-9
                    && posed.rotation.angle_to(&want.rotation) < 1e-9,
                "{file} {object:?}: root_pose does not realise hand_pose"
            );
            if p.feasible {
                feasible += 1;
                for c in &p.contacts {
                    if let Some(r) = c.ik_residual {
                        assert!(r <= 0.005, "{file} {object:?}: residual {r}");
                    }
                }
                let clearance = p.collision.final_plane_clearance.unwrap();
                assert!(
                    clearance >= -0.001,
                    "{file} {object:?}: final configuration {clearance} m through the table"
                );
                assert!(
                    p.collision.final_points_in_collision < 3,
                    "{file} {object:?}: final configuration inside the object"
                );
            } else {
                assert!(p.infeasible_reason.is_some());
            }
        }
        if feasible < 1 {
            low.push(format!("{file}: only {feasible} of {total} plans feasible"));
        }
    }
    assert!(low.is_empty(), "{low:?}");
}

/// Same input and seed, same plan (joints included).
#[test]
fn kinematic_plans_are_deterministic() {
    let m = model(SHARED_HANDS[1]);
    let a = plan_with(&m, Object::TABLE_5_2[0], 3);
    let b = plan_with(&m, Object::TABLE_5_2[0], 3);
    assert_eq!(a.joints, b.joints);
    assert_eq!(a.contacts, b.contacts);
    assert_eq!(a.hand_pose, b.hand_pose);
}
