//! Several views of one object (issue 15): a robot with a wrist camera, or a cell with more than
//! one camera, sees the object from more sides than one frame does — the side a single view
//! leaves to completion ([`crate::cloud::completion`]) is then measured.
//!
//! The first frame drives perception (saliency, grasp type, attention point, the object's
//! segment and the support plane, [`super::information`]). Every further frame, with its
//! camera-to-world transform, adds the points it sees of that object: its depth image
//! back-projected into the world, the support's points dropped (within
//! [`SegmentationParams::plane_margin`] of the plane, or below it), and kept what connects to
//! the object — those in one Euclidean cluster with it ([`euclidean_clusters`] at
//! [`SegmentationParams::cluster_radius`], as one view's segmentation clusters), and
//! inside the object's bounds widened by [`MAX_GROWTH`] so that a neighbour touching it is not
//! swallowed whole. A point within [`DUPLICATE`] of one already in the cloud adds nothing.

use super::depth_to_cloud::{CloudFrame, depth_to_cloud};
use super::rgbd::DecodedFrame;
use super::segmentation::{SegmentationParams, euclidean_clusters};
use crate::cloud::{CloudIndex, Plane, PointCloud};
use crate::error::FieldError;
use nalgebra::Point3;

/// How far beyond the first view's object bounds fused points may lie, m: the unseen side of
/// a 10–20 cm object lies within it.
pub const MAX_GROWTH: f64 = 0.12;
/// A fused point this close to one already in the cloud is a duplicate, m.
pub const DUPLICATE: f64 = 0.002;

/// What the fusion did, for the response.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FusionReport {
    /// Further views fused.
    pub views: usize,
    /// Points they added to the object.
    pub added_points: usize,
    /// Where the added points were seen from: (end index in the fused cloud, camera position)
    /// per view that added any, in order (`PlanHints::seen_from`, after the first view's).
    pub seen_from: Vec<(usize, Point3<f64>)>,
}

/// Adds to `object` (world frame, from the first view) what `views` see of it. Every view needs
/// its camera-to-world transform (`field[i].camera_to_world` is named when one lacks it).
pub fn fuse_views(
    object: &PointCloud,
    plane: Option<&Plane>,
    views: &[DecodedFrame],
    params: &SegmentationParams,
    field: &str,
) -> Result<(PointCloud, FusionReport), FieldError> {
    let mut points = object.points.clone();
    if points.is_empty() || views.is_empty() {
        return Ok((PointCloud::new(points), FusionReport::default()));
    }
    let (mut lo, mut hi) = (points[0], points[0]);
    for p in &points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let grow = nalgebra::Vector3::repeat(MAX_GROWTH);
    let (lo, hi) = (lo - grow, hi + grow);
    let inside = |p: &Point3<f64>| (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k]);
    let mut added = 0;
    let mut seen_from = Vec::new();
    for (i, view) in views.iter().enumerate() {
        let Some(camera) = view.camera_to_world else {
            return Err(FieldError::new(
                format!("{field}[{i}].camera_to_world"),
                "is required: a further view is fused in the world frame",
            ));
        };
        let seen = depth_to_cloud(view, CloudFrame::World).cloud.points;
        let candidates: Vec<Point3<f64>> = seen
            .into_iter()
            .filter(|p| inside(p))
            .filter(|p| plane.is_none_or(|pl| pl.distance(p) > params.plane_margin))
            .collect();
        if candidates.is_empty() {
            continue;
        }
        // The Euclidean clusters of the object and the candidates together (those of one
        // view's segmentation): the candidates in a cluster with the object connect to it.
        let n = points.len();
        let all: Vec<Point3<f64>> = points.iter().chain(&candidates).copied().collect();
        let idx: Vec<usize> = (0..all.len()).collect();
        let mut taken = vec![false; candidates.len()];
        for cluster in euclidean_clusters(&all, &idx, params.cluster_radius, 1) {
            if cluster.iter().any(|&i| i < n) {
                for &i in cluster.iter().filter(|&&i| i >= n) {
                    taken[i - n] = true;
                }
            }
        }
        let known = CloudIndex::new(&points);
        let fresh: Vec<Point3<f64>> = candidates
            .iter()
            .zip(&taken)
            .filter(|(p, t)| **t && known.nearest_one(p).1 > DUPLICATE)
            .map(|(p, _)| *p)
            .collect();
        added += fresh.len();
        points.extend(fresh);
        if points.len() > n {
            seen_from.push((points.len(), Point3::from(camera.translation.vector)));
        }
    }
    Ok((
        PointCloud::new(points),
        FusionReport {
            views: views.len(),
            added_points: added,
            seen_from,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::rgbd::CameraIntrinsics;
    use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

    /// A depth image of a sphere (radius r at `centre`, world) and a table z = 0, seen from a
    /// camera at `eye` looking at the centre.
    fn view_of_sphere(eye: Point3<f64>, centre: Point3<f64>, r: f64) -> DecodedFrame {
        let (w, h) = (80usize, 60usize);
        let k = CameraIntrinsics {
            fx: 80.0,
            fy: 80.0,
            cx: 39.5,
            cy: 29.5,
        };
        let z = (centre - eye).normalize();
        let x = z.cross(&Vector3::z()).normalize();
        let y = z.cross(&x);
        let rot = nalgebra::Rotation3::from_basis_unchecked(&[x, y, z]);
        let pose = Isometry3::from_parts(
            Translation3::from(eye.coords),
            UnitQuaternion::from_rotation_matrix(&rot),
        );
        let mut depth = vec![0.0f32; w * h];
        for v in 0..h {
            for u in 0..w {
                let dir_cam = Vector3::new((u as f64 - k.cx) / k.fx, (v as f64 - k.cy) / k.fy, 1.0);
                let d = pose.rotation * dir_cam;
                // Sphere hit (nearest root), else the table.
                let oc = eye - centre;
                let (a, b, c) = (d.dot(&d), 2.0 * oc.dot(&d), oc.dot(&oc) - r * r);
                let disc = b * b - 4.0 * a * c;
                let t = if disc >= 0.0 {
                    Some((-b - disc.sqrt()) / (2.0 * a))
                } else if d.z < 0.0 {
                    Some(-eye.z / d.z)
                } else {
                    None
                };
                if let Some(t) = t {
                    depth[v * w + u] = t as f32; // along the optical axis: dir_cam.z = 1
                }
            }
        }
        DecodedFrame {
            width: w,
            height: h,
            rgb: vec![0; 3 * w * h],
            valid_depth: depth.iter().filter(|d| **d > 0.0).count(),
            depth,
            intrinsics: k,
            camera_to_world: Some(pose),
        }
    }

    /// The far side of a sphere, seen by a second camera opposite the first, joins the object;
    /// the table does not; a view without its pose is refused naming the field.
    #[test]
    fn a_second_view_adds_the_far_side_and_not_the_table() {
        let centre = Point3::new(0.0, 0.0, 0.05);
        let r = 0.04;
        let front = view_of_sphere(Point3::new(-0.5, 0.0, 0.3), centre, r);
        let back = view_of_sphere(Point3::new(0.5, 0.0, 0.3), centre, r);
        let table = Plane {
            normal: Vector3::z(),
            offset: 0.0,
        };
        let params = SegmentationParams::default();
        let seen: Vec<Point3<f64>> = depth_to_cloud(&front, CloudFrame::World)
            .cloud
            .points
            .into_iter()
            .filter(|p| table.distance(p) > params.plane_margin)
            .collect();
        let max_x = seen.iter().map(|p| p.x).fold(f64::MIN, f64::max);
        assert!(max_x < 0.02, "one view sees the near side: x up to {max_x}");
        let object = PointCloud::new(seen.clone());
        let (fused, report) = fuse_views(
            &object,
            Some(&table),
            std::slice::from_ref(&back),
            &params,
            "extra_views",
        )
        .unwrap();
        assert_eq!(report.views, 1);
        assert!(report.added_points > 50, "{report:?}");
        assert_eq!(fused.points.len(), seen.len() + report.added_points);
        // The added points were seen from the second camera: their normals will face it.
        assert_eq!(report.seen_from.len(), 1);
        let (end, eye) = report.seen_from[0];
        assert_eq!(end, fused.points.len());
        assert!((eye - Point3::new(0.5, 0.0, 0.3)).norm() < 1e-9, "{eye}");
        let far = fused.points.iter().filter(|p| p.x > 0.02).count();
        assert!(far > 50, "the far side joined: {far}");
        for p in &fused.points {
            let off = ((p - centre).norm() - r).abs();
            assert!(
                off < 0.003,
                "{p} is not on the sphere (table or stray): {off}"
            );
        }
        let mut blind = back;
        blind.camera_to_world = None;
        let e = fuse_views(&object, Some(&table), &[blind], &params, "extra_views").unwrap_err();
        assert_eq!(e.field, "extra_views[0].camera_to_world");
    }
}
