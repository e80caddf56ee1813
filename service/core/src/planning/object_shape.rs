//! What the planner knows of the object from its cloud: estimated centre and radius, principal
//! axes and extents (for the geometric type rule), and the convex-hull vertices used to place the
//! palm clear of the object (h of Eq 5.4).

use nalgebra::{Point3, Vector3};
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::transformation::try_convex_hull;

/// Shape summary of the object cloud.
#[derive(Debug, Clone)]
pub struct ObjectShape {
    /// Centroid of the points: the estimated centre of mass.
    pub center: Point3<f64>,
    /// Largest distance of a point from `center`.
    pub radius: f64,
    /// Principal axes, longest extent first (unit, right-handed).
    pub axes: [Vector3<f64>; 3],
    /// Extents along `axes` (max − min of the projections), d1 ≥ d2 ≥ d3.
    pub extents: [f64; 3],
    /// Convex-hull vertices of the cloud (all points if the hull is degenerate).
    pub hull: Vec<Point3<f64>>,
}

impl ObjectShape {
    pub fn of(points: &[Point3<f64>]) -> Self {
        let center = crate::cloud::point_cloud::centroid(points);
        let radius = points
            .iter()
            .map(|p| (p - center).norm())
            .fold(0.0, f64::max);
        let (_, cov) = crate::cloud::pca::covariance(points, 0..points.len());
        let (_, vecs) = crate::cloud::pca::eigen(&cov);
        let mut axes = [vecs[2], vecs[1], vecs[0]];
        axes[2] = axes[0].cross(&axes[1]);
        let mut extents = axes.map(|a| {
            let (lo, hi) = points
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                    let v = (p - center).dot(&a);
                    (l.min(v), h.max(v))
                });
            hi - lo
        });
        // PCA order and extent order can differ for boxes; keep d1 ≥ d2 ≥ d3.
        let mut idx = [0usize, 1, 2];
        idx.sort_by(|&a, &b| extents[b].total_cmp(&extents[a]));
        let (ax, ex) = (axes, extents);
        axes = idx.map(|i| ax[i]);
        extents = idx.map(|i| ex[i]);
        axes[2] = axes[0].cross(&axes[1]);
        let pv: Vec<PVec> = points.iter().map(|p| PVec::new(p.x, p.y, p.z)).collect();
        let hull = match try_convex_hull(&pv) {
            Ok((v, _)) if v.len() >= 4 => v.iter().map(|q| Point3::new(q.x, q.y, q.z)).collect(),
            _ => points.to_vec(),
        };
        Self {
            center,
            radius,
            axes,
            extents,
            hull,
        }
    }

    /// How far the object reaches from `from` in direction `dir` (unit): max over the hull of
    /// (v − from)·dir. Used to keep the palm clear of the object.
    pub fn reach(&self, from: &Point3<f64>, dir: &Vector3<f64>) -> f64 {
        self.hull
            .iter()
            .map(|v| (v - from).dot(dir))
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_extents_and_reach() {
        let mut pts = Vec::new();
        for i in 0..=10 {
            for j in 0..=10 {
                for k in 0..=10 {
                    if [i, j, k].iter().any(|&v| v == 0 || v == 10) {
                        pts.push(Point3::new(
                            0.1 * i as f64 / 10.0,
                            0.04 * j as f64 / 10.0,
                            0.02 * k as f64 / 10.0,
                        ));
                    }
                }
            }
        }
        let s = ObjectShape::of(&pts);
        assert!((s.extents[0] - 0.1).abs() < 1e-9, "{:?}", s.extents);
        assert!((s.extents[1] - 0.04).abs() < 1e-9);
        assert!((s.extents[2] - 0.02).abs() < 1e-9);
        assert!(s.axes[0].x.abs() > 0.999);
        assert!(s.hull.len() >= 8 && s.hull.len() < pts.len());
        let r = s.reach(&Point3::new(0.05, 0.02, 0.01), &Vector3::z());
        assert!((r - 0.01).abs() < 1e-9);
    }
}
