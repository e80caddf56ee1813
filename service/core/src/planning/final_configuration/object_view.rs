//! The object as the final-configuration search sees it (the visible points and their
//! completion, thinned for the collision queries).

use crate::cloud::{CloudIndex, LazyNormals, Plane};
use nalgebra::{Point3, Vector3};

/// Cell of the grid the object's points are thinned to for collision queries, m: well below a
/// finger's thickness, so no link passes between two points.
pub const COLLISION_CELL: f64 = 0.004;

/// The object as the search sees it: its points thinned to one per [`COLLISION_CELL`] for the
/// collision queries, with the planner's normals.
pub struct ObjectView<'a> {
    pub points: Vec<Point3<f64>>,
    pub index: CloudIndex,
    /// For each thinned point, its index in the planner's cloud.
    pub source: Vec<usize>,
    pub normals: &'a LazyNormals<'a>,
    pub plane: Option<&'a Plane>,
    /// Bounds of the points.
    lo: Point3<f64>,
    hi: Point3<f64>,
}

impl<'a> ObjectView<'a> {
    pub fn new(
        cloud: &[Point3<f64>],
        normals: &'a LazyNormals<'a>,
        plane: Option<&'a Plane>,
    ) -> Self {
        let all: Vec<usize> = (0..cloud.len()).collect();
        let source = super::super::slot_set::voxel_subset(cloud, &all, COLLISION_CELL);
        let points: Vec<Point3<f64>> = source.iter().map(|&i| cloud[i]).collect();
        let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut hi = -lo;
        for p in &points {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        Self {
            index: CloudIndex::new(&points),
            points,
            source,
            normals,
            plane,
            lo,
            hi,
        }
    }

    /// Whether `p` lies below the object's top (along `up`) by at least `fraction` of its height.
    pub fn below_top(&self, p: &Point3<f64>, up: &Vector3<f64>, fraction: f64) -> bool {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for q in &self.points {
            let h = q.coords.dot(up);
            lo = lo.min(h);
            hi = hi.max(h);
        }
        p.coords.dot(up) <= hi - fraction * (hi - lo)
    }

    /// The object's extent along unit `dir`, m.
    pub fn extent_along(&self, dir: &Vector3<f64>) -> f64 {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for q in &self.points {
            let h = q.coords.dot(dir);
            lo = lo.min(h);
            hi = hi.max(h);
        }
        (hi - lo).max(0.0)
    }

    /// How far the object reaches from `from` along unit `dir` (0 when nothing lies ahead), m:
    /// the room a finger sliding that way has before it passes the object's end.
    pub fn reach_along(&self, from: &Point3<f64>, dir: &Vector3<f64>) -> f64 {
        self.points
            .iter()
            .map(|q| (q - from).dot(dir))
            .fold(0.0, f64::max)
    }

    /// Whether a sphere may reach the points (overlaps their bounding box).
    pub fn near(&self, c: &Point3<f64>, r: f64) -> bool {
        (0..3).all(|k| c[k] + r >= self.lo[k] && c[k] - r <= self.hi[k])
    }
}

/// Room a piece's cloud query leaves about its ball, m: the closing sweep's next steps, which
/// move the piece less than this, filter those points instead of querying the k-d tree again
/// (a tenth of a Shadow plan's time went to these queries; the move in, 8 mm a step, gained
/// nothing from it).
const NEAR_SLACK: f64 = 0.01;

/// One piece's last cloud query: its centre, its reach and the points within it.
#[derive(Debug, Clone)]
struct NearQuery {
    at: Point3<f64>,
    reach: f64,
    points: Vec<usize>,
}

/// Per collision piece, the cloud points within its last query's reach.
#[derive(Default)]
pub struct NearPoints(Vec<Option<NearQuery>>);

impl NearPoints {
    /// The points within `radius` of `c` (by the k-d tree's own test), from the piece's last
    /// query when its reach covers that ball.
    pub fn within(
        &mut self,
        k: usize,
        object: &ObjectView,
        c: &Point3<f64>,
        radius: f64,
    ) -> impl Iterator<Item = usize> {
        if k >= self.0.len() {
            self.0.resize(k + 1, None);
        }
        let covered = self.0[k]
            .as_ref()
            .is_some_and(|q| (c - q.at).norm() + radius + 1e-9 < q.reach);
        if !covered {
            let reach = radius + NEAR_SLACK;
            self.0[k] = Some(NearQuery {
                at: *c,
                reach,
                points: object.index.within_unsorted(c, reach).collect(),
            });
        }
        let near = self.0[k].as_ref().map_or(&[][..], |q| q.points.as_slice());
        near.iter()
            .copied()
            .filter(move |&i| CloudIndex::within_radius(c, &object.points[i], radius))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::{CloudIndex, LazyNormals, Orientation};

    /// A can 66 mm wide and 101 mm tall (its side sampled every 2 mm, ring by ring): from a
    /// point on its side 6 mm below the rim, the object reaches 6 mm up (to within a ring's
    /// spacing), 95 mm down and one diameter across; along the can's outward normal there,
    /// nothing.
    #[test]
    fn the_object_reaches_from_a_point_to_its_end_along_a_direction() {
        let r = 0.033;
        let mut pts = Vec::new();
        for k in 0..=50 {
            let z = 0.002 * k as f64 + 0.001;
            for a in 0..36 {
                let t = a as f64 * std::f64::consts::TAU / 36.0;
                pts.push(Point3::new(r * t.cos(), r * t.sin(), z));
            }
        }
        let index = CloudIndex::new(&pts);
        let normals = LazyNormals::new(&pts, &index, 8, Orientation::AwayFromCentroid, None);
        let view = ObjectView::new(&pts, &normals, None);
        let at = Point3::new(r, 0.0, 0.095);
        let up = view.reach_along(&at, &Vector3::z());
        assert!((up - 0.006).abs() <= COLLISION_CELL, "{up}");
        let down = view.reach_along(&at, &-Vector3::z());
        assert!((down - 0.094).abs() <= COLLISION_CELL, "{down}");
        let across = view.reach_along(&at, &-Vector3::x());
        assert!((across - 2.0 * r).abs() <= 1e-9, "{across}");
        assert_eq!(view.reach_along(&at, &Vector3::x()), 0.0);
    }
}
