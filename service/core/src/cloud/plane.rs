//! The support plane: given by the caller, or found by RANSAC and removed from the cloud.

use crate::error::FieldError;
use nalgebra::{Point3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// A plane n·x + d = 0 with unit normal n pointing to the side the object stands on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Plane {
    pub normal: Vector3<f64>,
    pub offset: f64,
}

impl Plane {
    /// Validates and normalises a caller's plane (`field` names it in errors).
    pub fn checked(normal: Vector3<f64>, offset: f64, field: &str) -> Result<Self, FieldError> {
        let len = normal.norm();
        if !len.is_finite() || len < 1e-9 || !offset.is_finite() {
            return Err(FieldError::new(
                field,
                "normal must be finite and non-zero, offset finite",
            ));
        }
        Ok(Self {
            normal: normal / len,
            offset: offset / len,
        })
    }

    /// Signed distance, positive on the object's side.
    pub fn distance(&self, p: &Point3<f64>) -> f64 {
        self.normal.dot(&p.coords) + self.offset
    }

    /// The plane through `p` with normal `n`.
    pub fn through(p: &Point3<f64>, n: Vector3<f64>) -> Self {
        let n = n.normalize();
        Self {
            normal: n,
            offset: -n.dot(&p.coords),
        }
    }
}

/// Result of looking for the support plane in a cloud.
#[derive(Debug, Clone)]
pub struct SupportPlaneFit {
    pub plane: Plane,
    /// Points of the cloud that belong to the plane (within the inlier band) or lie below it.
    pub removed: Vec<bool>,
}

/// Parameters of the support-plane search.
#[derive(Debug, Clone, Copy)]
pub struct RansacParams {
    pub iterations: usize,
    /// Inlier band, m.
    pub threshold: f64,
    /// Smallest share of the cloud the plane must hold.
    pub min_inlier_fraction: f64,
}

impl Default for RansacParams {
    fn default() -> Self {
        Self {
            iterations: 200,
            threshold: 0.004,
            min_inlier_fraction: 0.2,
        }
    }
}

fn fit_plane_lsq(points: &[Point3<f64>], idx: &[usize]) -> Option<Plane> {
    if idx.len() < 3 {
        return None;
    }
    let (mean, cov) = super::pca::covariance(points, idx.iter().copied());
    Some(Plane::through(&mean, super::pca::smallest_axis(&cov)))
}

/// Finds a support plane by RANSAC (seeded), refines it by least squares and accepts it only if
/// it looks like a table under an object: it holds ≥ `min_inlier_fraction` of the points, the
/// other points lie on one side of it (≥ 95 %), and it is wider than what stands on it (its
/// in-plane extent ≥ 1.5 × theirs) — so that a box's large face is not taken for the table.
/// The normal is flipped to point toward the object.
pub fn detect_support_plane(
    points: &[Point3<f64>],
    params: RansacParams,
    seed: u64,
    min_remaining: usize,
) -> Option<SupportPlaneFit> {
    let n = points.len();
    if n < 3 * min_remaining.max(3) {
        return None;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_91a7);
    let mut best: Option<(usize, Plane)> = None;
    for _ in 0..params.iterations {
        let (a, b, c) = (
            rng.random_range(0..n),
            rng.random_range(0..n),
            rng.random_range(0..n),
        );
        let nrm = (points[b] - points[a]).cross(&(points[c] - points[a]));
        if nrm.norm() < 1e-9 {
            continue;
        }
        let pl = Plane::through(&points[a], nrm);
        let count = points
            .iter()
            .filter(|p| pl.distance(p).abs() < params.threshold)
            .count();
        if best.is_none_or(|(bc, _)| count > bc) {
            best = Some((count, pl));
        }
    }
    let (_, rough) = best?;
    let inliers: Vec<usize> = (0..n)
        .filter(|&i| rough.distance(&points[i]).abs() < params.threshold)
        .collect();
    let mut plane = fit_plane_lsq(points, &inliers)?;
    let inlier: Vec<bool> = points
        .iter()
        .map(|p| plane.distance(p).abs() < params.threshold)
        .collect();
    let n_in = inlier.iter().filter(|&&b| b).count();
    if (n_in as f64) < params.min_inlier_fraction * n as f64 || n - n_in < min_remaining {
        return None;
    }
    // Orient toward the side where the other points are.
    let rest: Vec<&Point3<f64>> = points
        .iter()
        .zip(&inlier)
        .filter(|(_, i)| !**i)
        .map(|(p, _)| p)
        .collect();
    let above = rest.iter().filter(|p| plane.distance(p) > 0.0).count();
    if above * 2 < rest.len() {
        plane = Plane {
            normal: -plane.normal,
            offset: -plane.offset,
        };
    }
    let one_side = rest.iter().filter(|p| plane.distance(p) > 0.0).count();
    if (one_side as f64) < 0.95 * rest.len() as f64 {
        return None;
    }
    // In-plane extents of the plane's points and of the rest.
    let u = plane.normal.cross(&Vector3::x());
    let u = if u.norm() < 0.1 {
        plane.normal.cross(&Vector3::y())
    } else {
        u
    }
    .normalize();
    let v = plane.normal.cross(&u);
    let extent = |it: &mut dyn Iterator<Item = &Point3<f64>>| {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in it {
            let q = [p.coords.dot(&u), p.coords.dot(&v)];
            for k in 0..2 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt()
    };
    let table_extent = extent(
        &mut points
            .iter()
            .zip(&inlier)
            .filter(|(_, i)| **i)
            .map(|(p, _)| p),
    );
    let object_extent = extent(&mut rest.iter().copied());
    if table_extent < 1.5 * object_extent {
        return None;
    }
    let removed = points
        .iter()
        .map(|p| plane.distance(p) < params.threshold)
        .collect();
    Some(SupportPlaneFit { plane, removed })
}

/// Two unit tangents completing the unit vector `n` to an orthonormal frame (t1, t2, n): a
/// plane's in-plane directions, the friction cone's edges about a contact normal, a view's
/// image axes.
pub fn tangents(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let a = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let t1 = n.cross(&a).normalize();
    let t2 = n.cross(&t1);
    (t1, t2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table_and_box() -> Vec<Point3<f64>> {
        let mut pts = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                pts.push(Point3::new(
                    i as f64 * 0.01 - 0.2,
                    j as f64 * 0.01 - 0.2,
                    0.0,
                ));
            }
        }
        // A 6 cm cube's top and one side.
        for i in 0..12 {
            for j in 0..12 {
                let (a, b) = (i as f64 * 0.005, j as f64 * 0.005);
                pts.push(Point3::new(a, b, 0.06));
                pts.push(Point3::new(a, -0.0, b + 0.002));
            }
        }
        pts
    }

    #[test]
    fn finds_the_table_and_orients_it_up() {
        let pts = table_and_box();
        let fit = detect_support_plane(&pts, RansacParams::default(), 1, 32).unwrap();
        assert!((fit.plane.normal.z - 1.0).abs() < 1e-3, "{:?}", fit.plane);
        // The side face's lowest row lies in the 4 mm inlier band and pulls the fit slightly.
        assert!(fit.plane.offset.abs() < 1e-3);
        let kept = fit.removed.iter().filter(|r| !**r).count();
        assert!((144..=288).contains(&kept), "kept {kept}");
    }

    #[test]
    fn a_lone_box_face_is_not_a_table() {
        // Only the object: two faces of a box, the larger one 60 % of the points.
        let mut pts = Vec::new();
        for i in 0..30 {
            for j in 0..20 {
                pts.push(Point3::new(i as f64 * 0.005, j as f64 * 0.005, 0.1));
            }
        }
        for i in 0..30 {
            for j in 0..14 {
                pts.push(Point3::new(i as f64 * 0.005, 0.0, 0.1 - j as f64 * 0.005));
            }
        }
        assert!(detect_support_plane(&pts, RansacParams::default(), 3, 32).is_none());
    }

    #[test]
    fn checked_plane_rejects_zero_normal() {
        assert!(Plane::checked(Vector3::zeros(), 0.0, "support_plane").is_err());
        let p = Plane::checked(Vector3::new(0.0, 0.0, 2.0), -1.0, "x").unwrap();
        assert!((p.distance(&Point3::new(0.0, 0.0, 0.5))).abs() < 1e-12);
    }
}
