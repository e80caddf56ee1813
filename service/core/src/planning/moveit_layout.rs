//! A plan in the layout of ROS 2's `moveit_msgs/msg/Grasp`, so that a MoveIt pick pipeline
//! takes graspd's plans without repacking (issue 20): one per ranked candidate, best first.
//!
//! How each field is filled (field names as in the ROS 2 messages):
//! - `id`: `graspd-<seed>-<rank>`;
//! - `pre_grasp_posture`: one point, the pre-grasp opening (`pregrasp_joints`) at t = 0;
//! - `grasp_posture`: the touching joints (`joints`) at [`TOUCH_TIME_S`], then the squeeze
//!   (`squeeze_joints`, when planned) at [`SQUEEZE_TIME_S`] — the closing trajectory that
//!   MoveIt sends to the hand's controller;
//! - `grasp_pose`: the model's root frame (`root_pose`, where the hand's root link goes) when
//!   the hand's kinematics are known, else the hand frame (`hand_pose`);
//! - `grasp_quality`: the robustness (force resisted at the centre of mass per unit grip) for a
//!   plan with kinematics, else the objective Q (Eq 5.2) — what graspd ranked the candidates by;
//! - `pre_grasp_approach`: the approach direction (unit, the plan's frame), desired distance
//!   the pre-grasp's distance from the grasp, minimum half of it;
//! - `post_grasp_retreat`: away from the support plane (its normal), else back along the
//!   approach; desired [`RETREAT_M`], minimum half of it;
//! - `post_place_retreat`: back along the approach, the approach's distances;
//! - `max_contact_force` 0 (not limited) and `allowed_touch_objects` empty: the caller's
//!   planning scene knows the object's name.
//!
//! Every header carries `frame_id`, the frame the plan's outputs are in (the input's frame).
//! Joint trajectories list only joints the hand model has (empty for a parametric hand).

use super::grasp_plan::{GraspCandidate, GraspPlan};
use super::moveit_grasp::{GripperTranslation, JointTrajectory, JointTrajectoryPoint, MoveItGrasp};
use nalgebra::Vector3;

/// When the grasp posture reaches the touching joints, s from the start of the close.
pub const TOUCH_TIME_S: f64 = 1.0;
/// When it reaches the squeeze, s.
pub const SQUEEZE_TIME_S: f64 = 1.5;
/// How far the hand lifts the object after the grasp, m.
pub const RETREAT_M: f64 = 0.10;

/// The plan's ranked candidates (the plan itself when it has none) as MoveIt grasps.
pub fn moveit_grasps(plan: &GraspPlan, frame_id: &str) -> Vec<MoveItGrasp> {
    let one = [GraspCandidate::of(plan)];
    let candidates = if plan.candidates.is_empty() {
        &one[..]
    } else {
        &plan.candidates[..]
    };
    let up = plan.support_plane.map(|p| p.normal);
    candidates
        .iter()
        .enumerate()
        .map(|(rank, c)| moveit_grasp(c, format!("graspd-{}-{rank}", plan.seed), frame_id, up))
        .collect()
}

fn moveit_grasp(
    c: &GraspCandidate,
    id: String,
    frame_id: &str,
    up: Option<Vector3<f64>>,
) -> MoveItGrasp {
    let approach = c
        .approach
        .or_else(|| (c.hand_pose.position - c.pregrasp_pose.position).try_normalize(1e-9))
        .unwrap_or_else(Vector3::zeros);
    let distance = (c.hand_pose.position - c.pregrasp_pose.position).norm();
    let translation = |direction: Vector3<f64>, desired: f64| GripperTranslation {
        frame_id: frame_id.to_string(),
        direction,
        desired_distance: desired,
        min_distance: 0.5 * desired,
    };
    let trajectory = |points: &[(&[(String, f64)], f64)]| {
        let joint_names: Vec<String> = points
            .first()
            .map(|(j, _)| j.iter().map(|(n, _)| n.clone()).collect())
            .unwrap_or_default();
        JointTrajectory {
            points: points
                .iter()
                .filter(|(j, _)| !j.is_empty())
                .map(|(j, t)| JointTrajectoryPoint {
                    // The same joints in the same order as the first point (the plan lists every
                    // joint of the model in each of its configurations).
                    positions: joint_names
                        .iter()
                        .map(|n| j.iter().find(|(m, _)| m == n).map_or(0.0, |(_, a)| *a))
                        .collect(),
                    time_from_start: *t,
                })
                .collect(),
            joint_names,
        }
    };
    let grasp_points: Vec<(&[(String, f64)], f64)> = if c.squeeze_joints.is_empty() {
        vec![(&c.joints, TOUCH_TIME_S)]
    } else {
        vec![
            (&c.joints, TOUCH_TIME_S),
            (&c.squeeze_joints, SQUEEZE_TIME_S),
        ]
    };
    MoveItGrasp {
        id,
        pre_grasp_posture: trajectory(&[(&c.pregrasp_joints, 0.0)]),
        grasp_posture: trajectory(&grasp_points),
        frame_id: frame_id.to_string(),
        grasp_pose: c.root_pose.unwrap_or(c.hand_pose).isometry(),
        grasp_quality: if c.root_pose.is_some() {
            c.quality.robustness
        } else {
            c.quality.objective
        },
        pre_grasp_approach: translation(approach, distance),
        post_grasp_retreat: translation(up.unwrap_or(-approach), RETREAT_M),
        post_place_retreat: translation(-approach, distance),
        max_contact_force: 0.0,
        allowed_touch_objects: Vec::new(),
    }
}
