//! ROS layouts (`ros.proto`): `sensor_msgs/PointCloud2` in, `moveit_msgs/Grasp` out — the rules
//! live in core (`cloud::io::pointcloud2`, `planning::moveit_layout`); this maps the messages.

use super::values::*;
use crate::error::ServiceError;
use crate::limits::Limits;
use graspd_core::FieldError;
use graspd_core::cloud::PointCloud;
use graspd_core::cloud::io::{PointCloud2Layout, PointField, read_pointcloud2, write_pointcloud2};
use graspd_core::planning::Pose;
use graspd_core::planning::moveit_grasp::{
    GripperTranslation, JointTrajectory, JointTrajectoryPoint, MoveItGrasp, ros_duration,
};
use graspd_proto::v1 as pb;

/// The layout of a PointCloud2 message (its bytes stay in the message).
fn layout_from_proto(c: &pb::PointCloud2) -> PointCloud2Layout {
    PointCloud2Layout {
        height: c.height,
        width: c.width,
        fields: c
            .fields
            .iter()
            .map(|f| PointField {
                name: f.name.clone(),
                offset: f.offset,
                datatype: f.datatype,
                count: f.count,
            })
            .collect(),
        is_bigendian: c.is_bigendian,
        point_step: c.point_step,
        row_step: c.row_step,
        is_dense: c.is_dense,
    }
}

/// Decodes a PointCloud2 (`field` its name in the request), refusing more points than the
/// limit before reading them.
pub fn cloud2_from_proto(
    c: &pb::PointCloud2,
    field: &str,
    limits: &Limits,
) -> Result<PointCloud, ServiceError> {
    let layout = layout_from_proto(c);
    limits.check_points(
        layout.points().unwrap_or(u64::MAX),
        &format!("{field}.width"),
    )?;
    Ok(read_pointcloud2(&layout, &c.data, field)?)
}

/// Encodes a cloud as a one-row float32 PointCloud2 (clients, tests).
pub fn cloud2_to_proto(cloud: &PointCloud, frame_id: &str) -> pb::PointCloud2 {
    let (layout, data) = write_pointcloud2(cloud);
    pb::PointCloud2 {
        height: layout.height,
        width: layout.width,
        fields: layout
            .fields
            .into_iter()
            .map(|f| pb::PointField {
                name: f.name,
                offset: f.offset,
                datatype: f.datatype,
                count: f.count,
            })
            .collect(),
        is_bigendian: layout.is_bigendian,
        point_step: layout.point_step,
        row_step: layout.row_step,
        data,
        is_dense: layout.is_dense,
        frame_id: frame_id.to_string(),
    }
}

fn header(frame_id: &str) -> Option<pb::Header> {
    Some(pb::Header {
        frame_id: frame_id.to_string(),
    })
}

fn frame_of(h: &Option<pb::Header>) -> String {
    h.as_ref().map(|h| h.frame_id.clone()).unwrap_or_default()
}

fn duration(seconds: f64) -> Option<pb::Duration> {
    let (sec, nanosec) = ros_duration(seconds);
    Some(pb::Duration { sec, nanosec })
}

fn trajectory_to_proto(t: &JointTrajectory, frame_id: &str) -> pb::JointTrajectory {
    pb::JointTrajectory {
        header: header(frame_id),
        joint_names: t.joint_names.clone(),
        points: t
            .points
            .iter()
            .map(|p| pb::JointTrajectoryPoint {
                positions: p.positions.clone(),
                time_from_start: duration(p.time_from_start),
            })
            .collect(),
    }
}

fn trajectory_from_proto(t: Option<pb::JointTrajectory>) -> JointTrajectory {
    let t = t.unwrap_or_default();
    JointTrajectory {
        joint_names: t.joint_names,
        points: t
            .points
            .into_iter()
            .map(|p| {
                let d = p.time_from_start.unwrap_or_default();
                JointTrajectoryPoint {
                    positions: p.positions,
                    time_from_start: d.sec as f64 + d.nanosec as f64 * 1e-9,
                }
            })
            .collect(),
    }
}

fn translation_to_proto(t: &GripperTranslation) -> pb::GripperTranslation {
    pb::GripperTranslation {
        direction: Some(pb::Vector3Stamped {
            header: header(&t.frame_id),
            vector: Some(vec3_to_proto(&t.direction)),
        }),
        desired_distance: t.desired_distance,
        min_distance: t.min_distance,
    }
}

fn translation_from_proto(
    t: Option<pb::GripperTranslation>,
    field: &str,
) -> Result<GripperTranslation, FieldError> {
    let t = required(&t, field)?;
    let d = required(&t.direction, &format!("{field}.direction"))?;
    Ok(GripperTranslation {
        frame_id: frame_of(&d.header),
        direction: vec3_from_proto(required(&d.vector, &format!("{field}.direction.vector"))?),
        desired_distance: t.desired_distance,
        min_distance: t.min_distance,
    })
}

/// A MoveIt grasp in `moveit_msgs/Grasp`'s nesting.
pub fn moveit_grasp_to_proto(g: &MoveItGrasp) -> pb::MoveItGrasp {
    pb::MoveItGrasp {
        id: g.id.clone(),
        pre_grasp_posture: Some(trajectory_to_proto(&g.pre_grasp_posture, &g.frame_id)),
        grasp_posture: Some(trajectory_to_proto(&g.grasp_posture, &g.frame_id)),
        grasp_pose: Some(pb::PoseStamped {
            header: header(&g.frame_id),
            pose: Some(pose_to_proto(&Pose::from_isometry(&g.grasp_pose))),
        }),
        grasp_quality: g.grasp_quality,
        pre_grasp_approach: Some(translation_to_proto(&g.pre_grasp_approach)),
        post_grasp_retreat: Some(translation_to_proto(&g.post_grasp_retreat)),
        post_place_retreat: Some(translation_to_proto(&g.post_place_retreat)),
        max_contact_force: g.max_contact_force,
        allowed_touch_objects: g.allowed_touch_objects.clone(),
    }
}

/// Decodes a MoveIt grasp as the server sent it (clients); `field` names it in errors.
pub fn moveit_grasp_from_proto(g: pb::MoveItGrasp, field: &str) -> Result<MoveItGrasp, FieldError> {
    let at = |f: &str| format!("{field}.{f}");
    let pose = required(&g.grasp_pose, &at("grasp_pose"))?;
    Ok(MoveItGrasp {
        frame_id: frame_of(&pose.header),
        grasp_pose: pose_from_proto(&pose.pose, &at("grasp_pose.pose"))?.isometry(),
        pre_grasp_approach: translation_from_proto(
            g.pre_grasp_approach,
            &at("pre_grasp_approach"),
        )?,
        post_grasp_retreat: translation_from_proto(
            g.post_grasp_retreat,
            &at("post_grasp_retreat"),
        )?,
        post_place_retreat: translation_from_proto(
            g.post_place_retreat,
            &at("post_place_retreat"),
        )?,
        id: g.id,
        pre_grasp_posture: trajectory_from_proto(g.pre_grasp_posture),
        grasp_posture: trajectory_from_proto(g.grasp_posture),
        grasp_quality: g.grasp_quality,
        max_contact_force: g.max_contact_force,
        allowed_touch_objects: g.allowed_touch_objects,
    })
}
