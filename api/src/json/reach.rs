//! `POST /v1/reach`: the PlanReach request and response in JSON (the proto's fields in
//! snake_case; positions as `{x, y, z}` or `[x, y, z]`).

use super::plan::{RgbdJson, rgbd_from_json};
use super::values::{PlaneJson, PoseJson, QuaternionJson, Vec3Json};
use crate::request::{ReachCall, ReachWire, WirePose, reach_request};
use crate::schemas::Vec3InputDoc;
use graspd_core::FieldError;
use graspd_core::planning::Pose;
use graspd_core::reaching::Trajectory;
use nalgebra::Quaternion;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// An oriented box (orientation unset: axis-aligned).
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ObstacleJson {
    #[schema(value_type = Vec3InputDoc)]
    pub centre: Vec3Json,
    #[schema(value_type = Vec3InputDoc)]
    pub half_extents: Vec3Json,
    #[serde(default)]
    pub orientation: Option<QuaternionJson>,
}

/// Settings; unset or 0 takes the default (the proto's ReachOptions).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ReachOptionsJson {
    #[serde(default)]
    pub reach_duration: f64,
    #[serde(default)]
    pub approach_duration: f64,
    #[serde(default)]
    pub time_step: f64,
    #[serde(default)]
    pub horizon: u32,
    #[serde(default)]
    pub min_clearance: Option<f64>,
}

/// A demonstrated reach: positions every `dt` seconds, start to goal.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct DemonstrationJson {
    pub dt: f64,
    #[schema(value_type = Vec<Vec3InputDoc>)]
    pub positions: Vec<Vec3Json>,
}

/// The proto's PlanReachRequest.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ReachRequestJson {
    pub start: PoseJson,
    pub goal: PoseJson,
    #[serde(default)]
    #[schema(value_type = Option<Vec3InputDoc>)]
    pub approach: Option<Vec3Json>,
    #[serde(default)]
    pub pregrasp_distance: Option<f64>,
    #[serde(default)]
    pub obstacles: Vec<ObstacleJson>,
    #[serde(default)]
    pub support_plane: Option<PlaneJson>,
    #[serde(default)]
    pub hand_radius: Option<f64>,
    #[serde(default)]
    pub options: ReachOptionsJson,
    #[serde(default)]
    pub demonstrations: Vec<DemonstrationJson>,
    /// The scene as an RGB-D frame (images in base64): its objects but the grasp's become
    /// obstacles (the proto's `scene`).
    #[serde(default)]
    pub scene: Option<RgbdJson>,
}

fn quaternion(q: &QuaternionJson) -> Quaternion<f64> {
    Quaternion::new(q.w, q.x, q.y, q.z)
}

fn wire_pose(p: &PoseJson) -> WirePose {
    (p.position.point(), quaternion(&p.orientation))
}

/// The request in domain terms, with the scene's frame.
pub fn reach_request_from_json(r: ReachRequestJson) -> Result<ReachCall, FieldError> {
    let scene = r
        .scene
        .map(|f| rgbd_from_json(f, Default::default(), "scene"))
        .transpose()?;
    let reach = reach_request(ReachWire {
        start: Some(wire_pose(&r.start)),
        goal: Some(wire_pose(&r.goal)),
        approach: r.approach.map(|a| a.vector()),
        pregrasp_distance: r.pregrasp_distance,
        obstacles: r
            .obstacles
            .iter()
            .map(|b| {
                (
                    b.centre.point(),
                    b.half_extents.vector(),
                    b.orientation.as_ref().map(quaternion),
                )
            })
            .collect(),
        support_plane: r.support_plane.map(|p| (p.normal.vector(), p.offset)),
        hand_radius: r.hand_radius,
        reach_duration: r.options.reach_duration,
        approach_duration: r.options.approach_duration,
        time_step: r.options.time_step,
        horizon: r.options.horizon,
        min_clearance: r.options.min_clearance,
        demonstrations: r
            .demonstrations
            .into_iter()
            .map(|d| (d.dt, d.positions.iter().map(|p| p.vector()).collect()))
            .collect(),
    })?;
    Ok(ReachCall { reach, scene })
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct TrajectorySampleJson {
    /// Seconds from the start.
    pub time: f64,
    pub pose: PoseJson,
    /// Linear velocity of the hand frame, m/s.
    pub velocity: Vec3Json,
}

/// The proto's PlanReachResponse.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ReachResponseJson {
    pub samples: Vec<TrajectorySampleJson>,
    /// Least clearance of the hand's sphere to an obstacle, m (absent without obstacles).
    pub obstacle_clearance: Option<f64>,
    pub closest_obstacle: Option<u32>,
    /// Least height of the hand frame's origin above the support plane, m.
    pub table_clearance: Option<f64>,
    /// How far the reach ends from the pre-grasp point, m.
    pub reach_error: f64,
    pub server_ms: f64,
}

/// The trajectory as sent, with the server's time.
pub fn trajectory_to_json(t: &Trajectory, server_ms: f64) -> ReachResponseJson {
    ReachResponseJson {
        samples: t
            .samples
            .iter()
            .map(|s| TrajectorySampleJson {
                time: s.time,
                pose: (&Pose::from_isometry(&s.pose)).into(),
                velocity: (&s.velocity).into(),
            })
            .collect(),
        obstacle_clearance: t.obstacle_clearance.map(|(c, _)| c),
        closest_obstacle: t.obstacle_clearance.map(|(_, i)| i as u32),
        table_clearance: t.table_clearance,
        reach_error: t.reach_error,
        server_ms,
    }
}
