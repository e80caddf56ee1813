//! The unseen side of a single view (method.md §6): a camera sees the near half of an object on
//! a table; the far half is where the opposing fingers land and what the hand must not sweep
//! through. graspd completes it by **mirror symmetry** (most household objects are symmetric
//! about a vertical plane through their centre):
//!
//! - h, the horizontal part of the viewing direction (camera → visible centroid, the support
//!   plane's normal removed), l = up × h across it;
//! - the mirror is the vertical plane {x : x·h = c} with
//!   c = max(front + w/2, (front + back)/2), front/back the least/largest x·h of the visible
//!   points and w their extent along l: for a cylinder, box or sphere seen from the side the
//!   object is as deep as it is wide, and a view from above that sees the top out to its back
//!   edge puts the plane at the middle of that depth;
//! - only points in front of the plane are mirrored (they land behind it, where the camera saw
//!   nothing); points already behind it are the far side itself;
//! - mirrored points below the support plane are dropped, and so are those the camera would have
//!   seen (free-space carving): seen from the camera, a mirrored point is kept only behind the
//!   visible surface — where a visible point lies on its line of sight nearer the camera — and
//!   dropped where it would lie in front of the visible surface or where the camera saw past the
//!   object (no visible point on that line of sight: a curved or asymmetric object's mirror
//!   image that is not there);
//! - a view within [`MAX_ELEVATION_DEG`] of vertical has no horizontal direction: its unseen
//!   side is the bottom, which the table bounds, and nothing is added.
//!
//! The mirrored points are seen from the mirrored viewpoint, so their normals are estimated and
//! oriented toward it ([`Orientation::Views`]).

use super::{Orientation, Plane};
use nalgebra::{Point3, Vector3};
use std::sync::Arc;

/// Views steeper than this (from the horizontal) are not completed, degrees.
pub const MAX_ELEVATION_DEG: f64 = 75.0;

/// A cloud with its unseen side added.
#[derive(Debug, Clone, PartialEq)]
pub struct Completion {
    /// The visible points (same order and indices), then the mirrored ones.
    pub points: Vec<Point3<f64>>,
    /// How many of `points` were seen.
    pub visible: usize,
    /// For each mirrored point `visible + k`: the index of the visible point it mirrors.
    pub source: Vec<usize>,
    /// The mirror plane (normal h, offset c: x·h = c on the plane).
    pub mirror: Plane,
    /// The camera reflected in the mirror: the mirrored points face it.
    pub mirrored_viewpoint: Point3<f64>,
}

impl Completion {
    /// Normal orientation for the completed cloud: the visible part toward the camera, the
    /// mirrored part toward its reflection.
    pub fn orientation(&self, viewpoint: Point3<f64>) -> Orientation {
        Orientation::Views(Arc::from(vec![
            (self.visible, viewpoint),
            (self.points.len(), self.mirrored_viewpoint),
        ]))
    }

    /// The index in the visible cloud of point `i` of the completed one (itself when seen).
    pub fn observed_index(&self, i: usize) -> usize {
        if i < self.visible {
            i
        } else {
            self.source[i - self.visible]
        }
    }
}

/// Completes a single view of an object (rules in the module documentation). `up` is the
/// support plane's normal (or the caller's up); `support` drops mirrored points below the table.
/// None when the view is too steep or the cloud is empty.
pub fn mirror_completion(
    points: &[Point3<f64>],
    viewpoint: &Point3<f64>,
    up: &Vector3<f64>,
    support: Option<&Plane>,
) -> Option<Completion> {
    let up = up.try_normalize(1e-9)?;
    if points.is_empty() {
        return None;
    }
    let centroid = super::point_cloud::centroid(points);
    let view = centroid - viewpoint;
    let horizontal = view - up * view.dot(&up);
    // The line of sight's angle below the horizontal: 90° looks straight down.
    let elevation = (-view.dot(&up)).atan2(horizontal.norm()).to_degrees();
    if elevation > MAX_ELEVATION_DEG || horizontal.norm() < 1e-9 {
        return None;
    }
    let h = horizontal.normalize();
    let l = up.cross(&h);
    let (mut front, mut back) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut left, mut right) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in points {
        let (a, b) = (p.coords.dot(&h), p.coords.dot(&l));
        front = front.min(a);
        back = back.max(a);
        left = left.min(b);
        right = right.max(b);
    }
    let c = (front + 0.5 * (right - left)).max(0.5 * (front + back));
    let seen = SeenDepth::new(points, viewpoint, &view);
    let mut out = points.to_vec();
    let mut source = Vec::new();
    for (i, p) in points.iter().enumerate() {
        let a = p.coords.dot(&h);
        if a >= c {
            continue;
        }
        let m = p + h * (2.0 * (c - a));
        if support.is_some_and(|pl| pl.distance(&m) < 0.0) || !seen.hidden(&m) {
            continue;
        }
        out.push(m);
        source.push(i);
    }
    let mirrored_viewpoint = viewpoint + h * (2.0 * (c - viewpoint.coords.dot(&h)));
    Some(Completion {
        visible: points.len(),
        points: out,
        source,
        mirror: Plane {
            normal: h,
            offset: -c,
        },
        mirrored_viewpoint,
    })
}

/// What the camera saw: the nearest visible point's distance per cell of a grid of its lines of
/// sight (tangent-plane coordinates about the viewing direction), cells about 1.5 times the
/// visible points' spacing.
struct SeenDepth {
    eye: Point3<f64>,
    axes: [Vector3<f64>; 3],
    cell: f64,
    lo: (f64, f64),
    width: usize,
    height: usize,
    depth: Vec<f64>,
}

/// A mirrored point this much in front of the visible surface on its line of sight is in seen
/// free space, m.
const FREE_SPACE_TOLERANCE: f64 = 0.005;

impl SeenDepth {
    fn new(points: &[Point3<f64>], eye: &Point3<f64>, view: &Vector3<f64>) -> Self {
        let z = view.normalize();
        let helper = if z.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let x = z.cross(&helper).normalize();
        let y = z.cross(&x);
        let axes = [x, y, z];
        let project = |p: &Point3<f64>| {
            let d = p - eye;
            let zz = d.dot(&z).max(1e-6);
            (d.dot(&x) / zz, d.dot(&y) / zz, d.norm())
        };
        let (mut lo, mut hi) = (
            (f64::INFINITY, f64::INFINITY),
            (f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for p in points {
            let (u, v, _) = project(p);
            lo = (lo.0.min(u), lo.1.min(v));
            hi = (hi.0.max(u), hi.1.max(v));
        }
        let area = ((hi.0 - lo.0) * (hi.1 - lo.1)).max(1e-12);
        let cell = 1.5 * (area / points.len().max(1) as f64).sqrt();
        let width = (((hi.0 - lo.0) / cell) as usize + 1).min(4096);
        let height = (((hi.1 - lo.1) / cell) as usize + 1).min(4096);
        let mut depth = vec![f64::INFINITY; width * height];
        let mut me = Self {
            eye: *eye,
            axes,
            cell,
            lo,
            width,
            height,
            depth: Vec::new(),
        };
        for p in points {
            let (u, v, r) = project(p);
            if let Some(k) = me.cell_of(u, v) {
                depth[k] = depth[k].min(r);
            }
        }
        me.depth = depth;
        me
    }

    fn cell_of(&self, u: f64, v: f64) -> Option<usize> {
        let i = ((u - self.lo.0) / self.cell).floor();
        let j = ((v - self.lo.1) / self.cell).floor();
        (i >= 0.0 && j >= 0.0 && (i as usize) < self.width && (j as usize) < self.height)
            .then(|| j as usize * self.width + i as usize)
    }

    /// Whether `p` lies behind the visible surface (module rules): some visible point on its
    /// line of sight (its cell or a neighbour) is nearer the camera.
    fn hidden(&self, p: &Point3<f64>) -> bool {
        let [x, y, z] = &self.axes;
        let d = p - self.eye;
        let zz = d.dot(z).max(1e-6);
        let (u, v, r) = (d.dot(x) / zz, d.dot(y) / zz, d.norm());
        let mut nearest = f64::INFINITY;
        for du in [-1.0, 0.0, 1.0] {
            for dv in [-1.0, 0.0, 1.0] {
                if let Some(k) = self.cell_of(u + du * self.cell, v + dv * self.cell) {
                    nearest = nearest.min(self.depth[k]);
                }
            }
        }
        nearest.is_finite() && nearest < r + FREE_SPACE_TOLERANCE
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The near half of a vertical cylinder (radius 3 cm, 10 cm tall, axis through (0.1, 0, 0))
    /// as a camera at (−0.5, 0, 0.3) sees it.
    fn half_cylinder() -> Vec<Point3<f64>> {
        let mut pts = Vec::new();
        for i in 0..=36 {
            let phi = std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * i as f64 / 36.0;
            for k in 0..=10 {
                pts.push(Point3::new(
                    0.1 + 0.03 * phi.cos(),
                    0.03 * phi.sin(),
                    0.01 * k as f64,
                ));
            }
        }
        pts
    }

    #[test]
    fn a_half_cylinder_seen_from_the_side_is_mirrored_about_its_axis() {
        let pts = half_cylinder();
        let table = Plane {
            normal: Vector3::z(),
            offset: 0.0,
        };
        let c = mirror_completion(
            &pts,
            &Point3::new(-0.5, 0.0, 0.3),
            &Vector3::z(),
            Some(&table),
        )
        .unwrap();
        // h = +x; front = 0.07, width 0.06 → c = 0.1, the axis.
        assert!((c.mirror.normal - Vector3::x()).norm() < 1e-9);
        assert!((c.mirror.offset + 0.1).abs() < 1e-9, "{}", c.mirror.offset);
        assert_eq!(c.visible, pts.len());
        assert!(c.points.len() > pts.len() + pts.len() / 2);
        // Every mirrored point lies on the full cylinder, behind the axis.
        for p in &c.points[c.visible..] {
            let r = ((p.x - 0.1).powi(2) + p.y.powi(2)).sqrt();
            assert!((r - 0.03).abs() < 1e-9 && p.x >= 0.1 - 1e-12, "{p}");
        }
        assert_eq!(c.observed_index(c.visible), c.source[0]);
        // The mirrored camera is at x = 0.7, on the far side.
        assert!((c.mirrored_viewpoint - Point3::new(0.7, 0.0, 0.3)).norm() < 1e-9);
        let o = c.orientation(Point3::new(-0.5, 0.0, 0.3));
        let far = c.points[c.visible];
        assert!(o.outward(c.visible, &far, &Point3::origin()).x > 0.0);
        assert!(o.outward(0, &c.points[0], &Point3::origin()).x < 0.0);
    }

    /// An asymmetric object: a wall (x = 0.1, y from 0 to 0.1) and a post nearer the camera
    /// off to the side (x = 0.05, y = −0.1). The mirror plane lies at x = 0.15: the wall's
    /// mirror image lands behind the wall, where the camera could not see, and stays; the post's
    /// lands where the camera looked past the object (nothing seen on that line of sight) and is
    /// carved away.
    #[test]
    fn mirrored_points_the_camera_would_have_seen_are_dropped() {
        let eye = Point3::new(-0.5, 0.0, 0.03);
        let mut pts = Vec::new();
        for i in 0..=40 {
            for k in 0..=20 {
                pts.push(Point3::new(0.1, 0.0025 * i as f64, 0.0025 * k as f64));
            }
        }
        let wall = pts.len();
        for i in 0..=4 {
            for k in 0..=20 {
                pts.push(Point3::new(
                    0.05,
                    -0.1 + 0.0025 * i as f64,
                    0.0025 * k as f64,
                ));
            }
        }
        let c = mirror_completion(&pts, &eye, &Vector3::z(), None).unwrap();
        assert!((c.mirror.offset + 0.15).abs() < 0.01, "{:?}", c.mirror);
        let from_wall = c.source.iter().filter(|&&i| i < wall).count();
        let from_post = c.source.iter().filter(|&&i| i >= wall).count();
        assert!(
            from_wall > wall / 2,
            "{from_wall} of {wall} wall points mirrored"
        );
        assert_eq!(
            from_post, 0,
            "the post's mirror image is in seen free space"
        );
        // In front of the visible wall is free space; behind it is hidden.
        let seen = SeenDepth::new(
            &pts,
            &eye,
            &(super::super::point_cloud::centroid(&pts) - eye),
        );
        let on = pts[wall / 2];
        assert!(!seen.hidden(&(on + (eye - on) * 0.05)));
        assert!(seen.hidden(&(on + (on - eye) * 0.05)));
    }

    #[test]
    fn a_view_from_above_is_not_completed() {
        let pts = half_cylinder();
        assert!(
            mirror_completion(&pts, &Point3::new(0.1, 0.0, 1.0), &Vector3::z(), None).is_none()
        );
        assert!(
            mirror_completion(&[], &Point3::new(-1.0, 0.0, 0.3), &Vector3::z(), None).is_none()
        );
    }
}
