//! Surface normals by k-nearest-neighbour PCA (method.md §3), and the k-d tree index the planner
//! shares for its neighbourhood queries (Eq 5.6).

use kiddo::SquaredEuclidean;

/// kiddo's k-d tree with BUCKET points per leaf.
type KdTree = kiddo::float::kdtree::KdTree<f64, u64, 3, BUCKET, u32>;
const BUCKET: usize = 64;
use nalgebra::{Point3, Vector3};
use std::cell::OnceCell;

/// A k-d tree over the cloud's points (kiddo), indexed by point number.
pub struct CloudIndex {
    tree: KdTree,
}

impl CloudIndex {
    pub fn new(points: &[Point3<f64>]) -> Self {
        let entries: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
        Self {
            tree: (&entries).into(),
        }
    }

    /// Indices of the k nearest points (the query point itself included when it is in the cloud),
    /// nearest first.
    pub fn nearest(&self, p: &Point3<f64>, k: usize) -> Vec<usize> {
        self.tree
            .nearest_n::<SquaredEuclidean>(&[p.x, p.y, p.z], k)
            .into_iter()
            .map(|n| n.item as usize)
            .collect()
    }

    /// Indices of the points closer than `radius`, in no particular order.
    pub fn within_unsorted(
        &self,
        p: &Point3<f64>,
        radius: f64,
    ) -> impl Iterator<Item = usize> + use<> {
        // An iterator over kiddo's own result: the hot callers stop at the first hit
        // (`PosedCollision::any_within`) or only loop, so no second Vec is built.
        self.tree
            .within_unsorted::<SquaredEuclidean>(&[p.x, p.y, p.z], radius * radius)
            .into_iter()
            .map(|n| n.item as usize)
    }

    /// Whether `q` lies within `radius` of `p` by the very test (and float arithmetic) of
    /// [`Self::within_unsorted`]: a caller that filters an earlier, wider query's points with it
    /// gets that query's answer.
    pub fn within_radius(p: &Point3<f64>, q: &Point3<f64>, radius: f64) -> bool {
        let d = [p.x - q.x, p.y - q.y, p.z - q.z];
        d.iter().map(|v| v * v).fold(0.0, |a, b| a + b) <= radius * radius
    }

    /// Index of and distance to the nearest point.
    pub fn nearest_one(&self, p: &Point3<f64>) -> (usize, f64) {
        let n = self.tree.nearest_one::<SquaredEuclidean>(&[p.x, p.y, p.z]);
        (n.item as usize, n.distance.sqrt())
    }

    /// Indices of the points closer than `radius`: the neighbourhood Φ of Eq 5.6, in ascending
    /// index order (deterministic for the seeded search).
    pub fn within(&self, p: &Point3<f64>, radius: f64) -> Vec<usize> {
        let mut v: Vec<usize> = self
            .tree
            .within_unsorted::<SquaredEuclidean>(&[p.x, p.y, p.z], radius * radius)
            .into_iter()
            .map(|n| n.item as usize)
            .collect();
        v.sort_unstable();
        v
    }
}

/// Unit normal of each point from the PCA of its k nearest neighbours: the eigenvector of the
/// smallest eigenvalue of the neighbourhood covariance. Orientation follows `orient`.
pub fn estimate_normals(
    points: &[Point3<f64>],
    index: &CloudIndex,
    k: usize,
    orient: Orientation,
) -> Vec<Vector3<f64>> {
    normals_from_neighbours(points, &knn_lists(points, index, k), orient)
}

/// The k nearest neighbours of every point (itself first), k clamped to [3, n].
pub fn knn_lists(points: &[Point3<f64>], index: &CloudIndex, k: usize) -> Vec<Vec<usize>> {
    let k = k.clamp(3, points.len().max(3));
    points.iter().map(|p| index.nearest(p, k)).collect()
}

/// Normals by PCA over given neighbour lists (see [`estimate_normals`]).
pub fn normals_from_neighbours(
    points: &[Point3<f64>],
    neighbours: &[Vec<usize>],
    orient: Orientation,
) -> Vec<Vector3<f64>> {
    let mut normals = Vec::with_capacity(points.len());
    for nb in neighbours {
        let (_, cov) = super::pca::covariance(points, nb.iter().copied());
        normals.push(super::pca::smallest_axis(&cov));
    }
    orient_normals(points, &mut normals, orient);
    normals
}

/// Normals and k-NN lists computed on first use: the planner looks at a few hundred points of a
/// cloud of thousands (its thinned neighbourhoods and contacts), so eager per-point PCA would
/// dominate the plan's time.
pub struct LazyNormals<'a> {
    points: &'a [Point3<f64>],
    index: &'a CloudIndex,
    k: usize,
    orient: Orientation,
    centroid: Point3<f64>,
    given: Option<Vec<Vector3<f64>>>,
    normals: Vec<OnceCell<Vector3<f64>>>,
    neighbours: Vec<OnceCell<Vec<usize>>>,
}

impl<'a> LazyNormals<'a> {
    /// Normals estimated by k-NN PCA, oriented by `orient`; or `given` ones (one per point,
    /// unit length, used as they are).
    pub fn new(
        points: &'a [Point3<f64>],
        index: &'a CloudIndex,
        k: usize,
        orient: Orientation,
        given: Option<Vec<Vector3<f64>>>,
    ) -> Self {
        Self {
            points,
            index,
            k: k.clamp(3, points.len().max(3)),
            orient,
            centroid: super::point_cloud::centroid(points),
            given,
            normals: (0..points.len()).map(|_| OnceCell::new()).collect(),
            neighbours: (0..points.len()).map(|_| OnceCell::new()).collect(),
        }
    }

    /// The k nearest neighbours of point `i` (itself first).
    pub fn neighbours(&self, i: usize) -> &[usize] {
        self.neighbours[i].get_or_init(|| self.index.nearest(&self.points[i], self.k))
    }

    /// The unit outward normal of point `i`.
    pub fn get(&self, i: usize) -> Vector3<f64> {
        if let Some(g) = &self.given {
            return g[i];
        }
        *self.normals[i].get_or_init(|| {
            let (_, cov) = super::pca::covariance(self.points, self.neighbours(i).iter().copied());
            let n = super::pca::smallest_axis(&cov);
            let p = self.points[i];
            let out = self.orient.outward(i, &p, &self.centroid);
            if n.dot(&out) < 0.0 { -n } else { n }
        })
    }
}

/// Which way normals point.
#[derive(Debug, Clone, PartialEq)]
pub enum Orientation {
    /// Toward a sensor at this position (single-view clouds: every point is seen from it).
    TowardViewpoint(Point3<f64>),
    /// Away from the cloud's centroid (whole-object clouds without a known sensor).
    AwayFromCentroid,
    /// Points in consecutive ranges seen from different viewpoints (fused views, or a view and
    /// its mirror completion): `(end, viewpoint)` pairs in ascending `end`, point i faces the
    /// viewpoint of the first range with i < end (the last one beyond).
    Views(std::sync::Arc<[(usize, Point3<f64>)]>),
}

impl Orientation {
    /// A fused cloud's points each facing the camera that saw it, after a subset was kept:
    /// `seen_from` holds (end index, camera position) over the whole cloud in ascending `end`,
    /// `kept` the indices of the points kept from it, ascending.
    pub fn seen_from(seen_from: &[(usize, Point3<f64>)], kept: &[usize]) -> Self {
        Orientation::Views(
            seen_from
                .iter()
                .map(|&(end, eye)| (kept.partition_point(|&i| i < end), eye))
                .collect::<Vec<_>>()
                .into(),
        )
    }

    /// The outward direction of point `i` at `p` (`centroid`: the cloud's).
    pub fn outward(&self, i: usize, p: &Point3<f64>, centroid: &Point3<f64>) -> Vector3<f64> {
        match self {
            Orientation::TowardViewpoint(v) => v - p,
            Orientation::AwayFromCentroid => p - centroid,
            Orientation::Views(ranges) => {
                let k = ranges.partition_point(|(end, _)| *end <= i);
                match ranges.get(k).or(ranges.last()) {
                    Some((_, v)) => v - p,
                    None => p - centroid,
                }
            }
        }
    }
}

/// Flips normals so they point outward as `orient` says.
pub fn orient_normals(points: &[Point3<f64>], normals: &mut [Vector3<f64>], orient: Orientation) {
    let c = super::point_cloud::centroid(points);
    for (i, (p, n)) in points.iter().zip(normals.iter_mut()).enumerate() {
        let out = orient.outward(i, p, &c);
        if n.dot(&out) < 0.0 {
            *n = -*n;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points 0–3 came from camera A, 4–9 from B; points 1, 4, 7 and 8 were dropped: the kept
    /// ones (0, 2, 3 | 5, 6, 9) face A, A, A, B, B, B.
    #[test]
    fn a_fused_cloud_faces_each_camera_through_the_kept_subset() {
        let (a, b) = (Point3::new(-1.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0));
        let o = Orientation::seen_from(&[(4, a), (10, b)], &[0, 2, 3, 5, 6, 9]);
        let origin = Point3::origin();
        let faces: Vec<f64> = (0..6).map(|i| o.outward(i, &origin, &origin).x).collect();
        assert_eq!(faces, vec![-1.0, -1.0, -1.0, 1.0, 1.0, 1.0]);
    }

    /// Points on a sphere of radius r by a Fibonacci lattice.
    pub fn sphere(n: usize, r: f64) -> Vec<Point3<f64>> {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let rad = (1.0 - y * y).sqrt();
                let th = golden * i as f64;
                Point3::new(r * rad * th.cos(), r * y, r * rad * th.sin())
            })
            .collect()
    }

    #[test]
    fn sphere_normals_are_radial_and_outward() {
        let pts = sphere(1500, 0.04);
        let idx = CloudIndex::new(&pts);
        let n = estimate_normals(&pts, &idx, 12, Orientation::AwayFromCentroid);
        for (p, n) in pts.iter().zip(&n) {
            let radial = p.coords.normalize();
            assert!(n.dot(&radial) > 0.99, "normal {n:?} at {p:?}");
        }
    }

    #[test]
    fn plane_normals_face_the_viewpoint() {
        let pts: Vec<_> = (0..400)
            .map(|i| Point3::new((i % 20) as f64 * 0.005, (i / 20) as f64 * 0.005, 0.0))
            .collect();
        let idx = CloudIndex::new(&pts);
        let down = estimate_normals(
            &pts,
            &idx,
            10,
            Orientation::TowardViewpoint(Point3::new(0.0, 0.0, -1.0)),
        );
        assert!(down.iter().all(|n| (n.z + 1.0).abs() < 1e-9));
    }

    #[test]
    fn lazy_normals_equal_eager_ones() {
        let pts = sphere(800, 0.05);
        let idx = CloudIndex::new(&pts);
        let eager = estimate_normals(&pts, &idx, 12, Orientation::AwayFromCentroid);
        let lazy = LazyNormals::new(&pts, &idx, 12, Orientation::AwayFromCentroid, None);
        for i in [0, 5, 400, 799] {
            assert!((lazy.get(i) - eager[i]).norm() < 1e-12);
        }
        assert_eq!(lazy.neighbours(5)[0], 5);
    }

    #[test]
    fn within_is_sorted_and_exact() {
        let pts = sphere(500, 0.05);
        let idx = CloudIndex::new(&pts);
        let q = pts[10];
        let w = idx.within(&q, 0.02);
        assert!(w.windows(2).all(|p| p[0] < p[1]));
        let brute: Vec<usize> = (0..pts.len())
            .filter(|&i| (pts[i] - q).norm() < 0.02)
            .collect();
        assert_eq!(w, brute);
        assert_eq!(idx.nearest_one(&q).0, 10);
    }
}
