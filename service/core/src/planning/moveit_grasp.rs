//! ROS 2's `moveit_msgs/msg/Grasp` and the messages inside it, as plain data (issue 20): what
//! [`super::moveit_layout`] fills from a plan and the transports write in ROS's nesting.

use nalgebra::{Isometry3, Vector3};
use serde::{Deserialize, Serialize};

/// `trajectory_msgs/JointTrajectoryPoint` (positions and time only).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointTrajectoryPoint {
    pub positions: Vec<f64>,
    /// Seconds from the trajectory's start (ROS `time_from_start`).
    pub time_from_start: f64,
}

/// `trajectory_msgs/JointTrajectory` (its header's frame is not used by MoveIt).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointTrajectory {
    pub joint_names: Vec<String>,
    pub points: Vec<JointTrajectoryPoint>,
}

/// `moveit_msgs/GripperTranslation`: a direction in `frame_id` and how far to move along it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GripperTranslation {
    pub frame_id: String,
    pub direction: Vector3<f64>,
    pub desired_distance: f64,
    pub min_distance: f64,
}

/// `moveit_msgs/Grasp` (module rules).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MoveItGrasp {
    pub id: String,
    pub pre_grasp_posture: JointTrajectory,
    pub grasp_posture: JointTrajectory,
    /// `grasp_pose.header.frame_id`.
    pub frame_id: String,
    /// `grasp_pose.pose`.
    pub grasp_pose: Isometry3<f64>,
    pub grasp_quality: f64,
    pub pre_grasp_approach: GripperTranslation,
    pub post_grasp_retreat: GripperTranslation,
    pub post_place_retreat: GripperTranslation,
    pub max_contact_force: f64,
    pub allowed_touch_objects: Vec<String>,
}

/// Seconds as a ROS 2 `builtin_interfaces/Duration` (sec, nanosec); negative times are 0.
pub fn ros_duration(seconds: f64) -> (i32, u32) {
    let s = seconds.max(0.0);
    (
        s.trunc() as i32,
        ((s.fract() * 1e9).round() as u32).min(999_999_999),
    )
}
