//! PlanReach: the request into [`ReachWire`] (its defaults and checks are
//! [`crate::request::reach_request`]'s and the domain's), the trajectory back.

use super::plan::rgbd_from_proto;
use super::values::{point_from_proto, pose_to_proto, required, vec3_from_proto, vec3_to_proto};
use crate::request::{ReachCall, ReachWire, WirePose, reach_request};
use graspd_core::FieldError;
use graspd_core::planning::Pose;
use graspd_core::reaching::Trajectory;
use graspd_proto::v1 as pb;
use nalgebra::Quaternion;

fn quaternion(q: &pb::Quaternion) -> Quaternion<f64> {
    Quaternion::new(q.w, q.x, q.y, q.z)
}

fn wire_pose(p: &Option<pb::Pose>, field: &str) -> Result<Option<WirePose>, FieldError> {
    let Some(p) = p else {
        return Ok(None);
    };
    let position = point_from_proto(required(&p.position, &format!("{field}.position"))?);
    let q = required(&p.orientation, &format!("{field}.orientation"))?;
    Ok(Some((position, quaternion(q))))
}

/// The request in domain terms, with the scene's frame.
pub fn reach_request_from_proto(r: pb::PlanReachRequest) -> Result<ReachCall, FieldError> {
    let scene = r
        .scene
        .clone()
        .map(|f| rgbd_from_proto(f, "scene"))
        .transpose()?;
    let o = r.options.unwrap_or_default();
    let obstacles = r
        .obstacles
        .iter()
        .enumerate()
        .map(|(i, b)| {
            Ok((
                point_from_proto(required(&b.centre, &format!("obstacles[{i}].centre"))?),
                vec3_from_proto(required(
                    &b.half_extents,
                    &format!("obstacles[{i}].half_extents"),
                )?),
                b.orientation.as_ref().map(quaternion),
            ))
        })
        .collect::<Result<Vec<_>, FieldError>>()?;
    let reach = reach_request(ReachWire {
        start: wire_pose(&r.start, "start")?,
        goal: wire_pose(&r.goal, "goal")?,
        approach: r.approach.as_ref().map(vec3_from_proto),
        pregrasp_distance: r.pregrasp_distance,
        obstacles,
        support_plane: r
            .support_plane
            .as_ref()
            .map(|p| {
                required(&p.normal, "support_plane.normal").map(|n| (vec3_from_proto(n), p.offset))
            })
            .transpose()?,
        hand_radius: r.hand_radius,
        reach_duration: o.reach_duration,
        approach_duration: o.approach_duration,
        time_step: o.time_step,
        horizon: o.horizon,
        min_clearance: o.min_clearance,
        demonstrations: r
            .demonstrations
            .iter()
            .map(|d| (d.dt, d.positions.iter().map(vec3_from_proto).collect()))
            .collect(),
    })?;
    Ok(ReachCall { reach, scene })
}

/// The trajectory as sent, with the server's time.
pub fn trajectory_to_proto(t: &Trajectory, server_ms: f64) -> pb::PlanReachResponse {
    pb::PlanReachResponse {
        samples: t
            .samples
            .iter()
            .map(|s| pb::TrajectorySample {
                time: s.time,
                pose: Some(pose_to_proto(&Pose::from_isometry(&s.pose))),
                velocity: Some(vec3_to_proto(&s.velocity)),
            })
            .collect(),
        obstacle_clearance: t.obstacle_clearance.map(|(c, _)| c),
        closest_obstacle: t.obstacle_clearance.map(|(_, i)| i as u32),
        table_clearance: t.table_clearance,
        reach_error: t.reach_error,
        server_ms,
    }
}
