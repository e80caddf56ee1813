//! The scene a plan is made in (Algorithm 4, first steps): the support plane separated from
//! the object's points (given, detected, or none), and a single view's unseen side completed.

use super::grasp_plan::*;
use super::request::*;
use crate::cloud::{
    MIN_POINTS, Orientation, Plane, PointCloud, RansacParams, detect_support_plane,
    symmetric_completion,
};
use crate::error::FieldError;
use nalgebra::{Point3, Vector3};

/// Points closer than this to the support plane belong to the table (sensor noise band), m.
pub(crate) const PLANE_BAND: f64 = 0.004;

/// The support plane and the object's points above it.
pub(super) struct Scene {
    pub(super) plane: Option<Plane>,
    pub(super) source: PlaneSource,
    pub(super) points: Vec<Point3<f64>>,
    pub(super) normals: Option<Vec<Vector3<f64>>>,
    /// Index of each kept point in the request's cloud (for a completed point: the one it
    /// completes).
    pub(super) original: Vec<usize>,
    /// How many of `points` were seen (the rest complete the unseen side).
    pub(super) visible: usize,
}

pub(super) fn separate_support_plane(
    cloud: &PointCloud,
    hints: &PlanHints,
    options: &PlannerOptions,
) -> Result<Scene, FieldError> {
    let (plane, source, keep): (Option<Plane>, PlaneSource, Vec<bool>) =
        if let Some(pl) = hints.support_plane {
            let keep = cloud
                .points
                .iter()
                .map(|p| pl.distance(p) >= PLANE_BAND)
                .collect();
            (Some(pl), PlaneSource::Request, keep)
        } else if let Some(fit) = options
            .detect_support_plane
            .then(|| {
                detect_support_plane(
                    &cloud.points,
                    RansacParams::default(),
                    options.seed,
                    MIN_POINTS,
                )
            })
            .flatten()
        {
            let keep = fit.removed.iter().map(|r| !r).collect();
            (Some(fit.plane), PlaneSource::Detected, keep)
        } else {
            (None, PlaneSource::None, vec![true; cloud.points.len()])
        };
    // Exact duplicates carry no information (and a k-d tree cannot split a bucket of identical
    // points): keep the first of each.
    let mut seen = std::collections::HashSet::with_capacity(cloud.points.len());
    let original: Vec<usize> = (0..cloud.points.len())
        .filter(|&i| keep[i] && seen.insert(cloud.points[i].coords.map(f64::to_bits)))
        .collect();
    if original.len() < MIN_POINTS {
        return Err(FieldError::new(
            if source == PlaneSource::Request {
                "hints.support_plane"
            } else {
                "cloud"
            },
            format!(
                "only {} of {} points are distinct and above the support plane; the planner needs at least {MIN_POINTS} object points",
                original.len(),
                cloud.points.len()
            ),
        ));
    }
    Ok(Scene {
        plane,
        source,
        points: original.iter().map(|&i| cloud.points[i]).collect(),
        normals: cloud
            .normals
            .as_ref()
            .map(|n| original.iter().map(|&i| n[i]).collect()),
        visible: original.len(),
        original,
    })
}

/// Adds the unseen side (`cloud::completion`) to the scene; returns the normals' orientation.
/// A fused cloud (`seen_from`) is not completed: each point's normal faces its own camera.
pub(super) fn complete_unseen(
    scene: &mut Scene,
    viewpoint: Option<Point3<f64>>,
    seen_from: &[(usize, Point3<f64>)],
    up: Option<Vector3<f64>>,
    enabled: bool,
) -> Orientation {
    if !seen_from.is_empty() {
        return Orientation::seen_from(seen_from, &scene.original);
    }
    let plain = match viewpoint {
        Some(v) => Orientation::TowardViewpoint(v),
        None => Orientation::AwayFromCentroid,
    };
    let (Some(v), Some(u), true) = (viewpoint, up, enabled) else {
        return plain;
    };
    let Some(c) = symmetric_completion(&scene.points, &v, &u, scene.plane.as_ref()) else {
        return plain;
    };
    if let Some(n) = &mut scene.normals {
        let mirrored: Vec<Vector3<f64>> = c
            .source
            .iter()
            .enumerate()
            .map(|(k, &i)| c.map_vector(k, &n[i]))
            .collect();
        n.extend(mirrored);
    }
    let more: Vec<usize> = c.source.iter().map(|&i| scene.original[i]).collect();
    scene.original.extend(more);
    let orient = c.orientation(v);
    scene.points = c.points;
    orient
}
