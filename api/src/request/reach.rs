//! A PlanReach request as either transport sends it, before its defaults: [`ReachWire`], and
//! the one place that fills the defaults in and turns the wire's poses, boxes and plane into
//! the domain's [`ReachRequest`] ([`reach_request`]); with the scene's frame, if any, that is
//! the facade's [`ReachCall`].

use graspd_core::FieldError;
use graspd_core::cloud::Plane;
use graspd_core::perception::{RgbdFrame, camera_pose};
use graspd_core::reaching::forcing_term::Demonstration;
use graspd_core::reaching::{
    DEFAULT_HAND_RADIUS, DEFAULT_PREGRASP_DISTANCE, Obstacle, ReachOptions, ReachRequest, Scene,
};
use nalgebra::{Point3, Quaternion, UnitQuaternion, Vector3};

/// A pose as sent: position and quaternion (w, x, y, z), not yet normalised.
pub type WirePose = (Point3<f64>, Quaternion<f64>);

/// An obstacle as sent: centre, half extents, orientation (None: axis-aligned).
pub type WireObstacle = (Point3<f64>, Vector3<f64>, Option<Quaternion<f64>>);

/// A reach as the facade takes it: the request, and the scene's RGB-D frame whose other objects
/// become obstacles.
#[derive(Debug, Clone)]
pub struct ReachCall {
    pub reach: ReachRequest,
    pub scene: Option<RgbdFrame>,
}

/// The request's fields as sent; `None` and 0 take the defaults.
#[derive(Debug, Clone, Default)]
pub struct ReachWire {
    pub start: Option<WirePose>,
    pub goal: Option<WirePose>,
    pub approach: Option<Vector3<f64>>,
    pub pregrasp_distance: Option<f64>,
    pub obstacles: Vec<WireObstacle>,
    pub support_plane: Option<(Vector3<f64>, f64)>,
    pub hand_radius: Option<f64>,
    pub reach_duration: f64,
    pub approach_duration: f64,
    pub time_step: f64,
    pub horizon: u32,
    pub min_clearance: Option<f64>,
    /// (dt, positions) per demonstration.
    pub demonstrations: Vec<(f64, Vec<Vector3<f64>>)>,
}

/// The domain request: defaults filled in, quaternions normalised (a zero one refused), the
/// approach defaulting to the goal frame's +z. The domain checks the rest
/// (`graspd_core::reaching::plan_reach`).
pub fn reach_request(w: ReachWire) -> Result<ReachRequest, FieldError> {
    let pose = |p: Option<WirePose>, field: &str| {
        let (position, q) = p.ok_or_else(|| FieldError::new(field, "is required"))?;
        camera_pose(position, q, field)
    };
    let start = pose(w.start, "start")?;
    let goal = pose(w.goal, "goal")?;
    let obstacles = w
        .obstacles
        .into_iter()
        .enumerate()
        .map(|(i, (centre, half_extents, q))| {
            let orientation = match q {
                Some(q) => camera_pose(centre, q, &format!("obstacles[{i}]"))?.rotation,
                None => UnitQuaternion::identity(),
            };
            Ok(Obstacle {
                centre,
                half_extents,
                orientation,
            })
        })
        .collect::<Result<Vec<_>, FieldError>>()?;
    let table = w
        .support_plane
        .map(|(n, offset)| Plane::checked(n, offset, "support_plane"))
        .transpose()?;
    let d = ReachOptions::default();
    let or = |v: f64, default: f64| if v == 0.0 { default } else { v };
    Ok(ReachRequest {
        start,
        approach: w.approach.unwrap_or(goal.rotation * Vector3::z()),
        goal,
        pregrasp_distance: w.pregrasp_distance.unwrap_or(DEFAULT_PREGRASP_DISTANCE),
        scene: Scene {
            obstacles,
            table,
            hand_radius: w.hand_radius.unwrap_or(DEFAULT_HAND_RADIUS),
        },
        demonstrations: w
            .demonstrations
            .into_iter()
            .map(|(dt, positions)| Demonstration { dt, positions })
            .collect(),
        options: ReachOptions {
            reach_duration: or(w.reach_duration, d.reach_duration),
            approach_duration: or(w.approach_duration, d.approach_duration),
            time_step: or(w.time_step, d.time_step),
            horizon: if w.horizon == 0 {
                d.horizon
            } else {
                w.horizon as usize
            },
            min_clearance: w.min_clearance.unwrap_or(d.min_clearance),
        },
    })
}
