//! Grasp quality measures of the dual-stage planner (dissertation ch. 5.4.1): stability S as the
//! Grasp Isotropy Index (Eq 5.3), reachability R (Eq 5.4) and attention G (Eq 5.5).

use nalgebra::{Matrix6, Point3, Vector3, Vector6};

/// A contact as the quality measures see it: a position and the object's outward unit normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPoint {
    pub position: Point3<f64>,
    pub normal: Vector3<f64>,
}

pub use crate::cloud::tangents;

/// G·Gᵀ of the soft-finger grasp matrix (method.md §3): per contact three force directions (normal
/// and two tangents) and a torsional moment γ·n about the normal. Moments are taken about the grasp
/// center (centroid of the contacts) and divided by the contact spread (mean contact distance from
/// that center), so S is unit-free. Returns `None` when the contacts coincide.
pub fn soft_finger_ggt(contacts: &[ContactPoint], gamma: f64) -> Option<Matrix6<f64>> {
    if contacts.is_empty() {
        return None;
    }
    let center = contacts
        .iter()
        .fold(Vector3::zeros(), |a, c| a + c.position.coords)
        / contacts.len() as f64;
    let spread = contacts
        .iter()
        .map(|c| (c.position.coords - center).norm())
        .sum::<f64>()
        / contacts.len() as f64;
    if spread < 1e-9 {
        return None;
    }
    let mut ggt = Matrix6::zeros();
    for c in contacts {
        let r = (c.position.coords - center) / spread;
        let (t1, t2) = tangents(&c.normal);
        for f in [c.normal, t1, t2] {
            let m = r.cross(&f);
            let col = Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z);
            ggt += col * col.transpose();
        }
        let tors = c.normal * gamma;
        let col = Vector6::new(0.0, 0.0, 0.0, tors.x, tors.y, tors.z);
        ggt += col * col.transpose();
    }
    Some(ggt)
}

/// Stability S = σ_min(G) / σ_max(G), the Grasp Isotropy Index (Eq 5.3), with the soft-finger
/// grasp matrix of [`soft_finger_ggt`]. In [0, 1]; 0 when the contacts cannot resist some wrench.
pub fn gii(contacts: &[ContactPoint], gamma: f64) -> f64 {
    let Some(ggt) = soft_finger_ggt(contacts, gamma) else {
        return 0.0;
    };
    let ev = ggt.symmetric_eigenvalues();
    let (lo, hi) = ev
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), &v| (l.min(v), h.max(v)));
    if hi <= 0.0 || lo <= 0.0 {
        return 0.0;
    }
    (lo / hi).sqrt()
}

/// Reachability R (Eq 5.4): cos(K(a − ½a_max))·e^(−2h) while both a ≤ a_max and h ≤ h_max, else
/// the constant cos(−½K·a_max)·e^(−2h_max). The printed condition reads "h < h_max or a < a_max";
/// the intent is "both within limits", so this uses AND (method.md §3). K = π / a_max, so R peaks
/// at half the hand's opening and falls to 0 at a = 0 and a = a_max (the text leaves K open).
/// `a` is the opening (two contacts, m) or the grasp-polygon area (m²); `h` is in metres.
pub fn reachability(a: f64, h: f64, a_max: f64, h_max: f64) -> f64 {
    let k = std::f64::consts::PI / a_max;
    if a <= a_max && h <= h_max {
        (k * (a - 0.5 * a_max)).cos() * (-2.0 * h).exp()
    } else {
        (-0.5 * k * a_max).cos() * (-2.0 * h_max).exp()
    }
}

/// Attention G (Eq 5.5): −|arccos(n_att·d / |n_att||d|) − π/2|, in [−π/2, 0]; 0 when the
/// opposition line d = oc2 − oc1 is perpendicular to the surface normal at the attention point.
pub fn attention(n_att: &Vector3<f64>, d: &Vector3<f64>) -> f64 {
    let denom = n_att.norm() * d.norm();
    if denom < 1e-12 {
        return -std::f64::consts::FRAC_PI_2;
    }
    let c = (n_att.dot(d) / denom).clamp(-1.0, 1.0);
    -(c.acos() - std::f64::consts::FRAC_PI_2).abs()
}

/// Attention for the palm opposition P–FS (small_wrap): the palm approaches along −n_att, so the
/// line from palm to fingers should be parallel to n_att, not perpendicular (deviation from
/// Eq 5.5, which the text states for finger–finger oppositions). Range [−π/2, 0].
pub fn attention_palm(n_att: &Vector3<f64>, d: &Vector3<f64>) -> f64 {
    let denom = n_att.norm() * d.norm();
    if denom < 1e-12 {
        return -std::f64::consts::FRAC_PI_2;
    }
    -(n_att.dot(d).abs() / denom).clamp(0.0, 1.0).acos()
}

/// Area of the grasp polygon a of Eq 5.4 for three or more contacts: the area of the convex hull
/// of the contacts projected on their best-fit plane. For two contacts use the distance.
pub fn polygon_area(points: &[Point3<f64>]) -> f64 {
    if points.len() < 3 {
        return 0.0;
    }
    let (c, cov) = crate::cloud::pca::covariance(points, 0..points.len());
    let n = crate::cloud::pca::smallest_axis(&cov);
    let (u, v) = tangents(&n);
    let mut pts2: Vec<(f64, f64)> = points
        .iter()
        .map(|p| {
            let d = p - c;
            (d.dot(&u), d.dot(&v))
        })
        .collect();
    hull_area_2d(&mut pts2)
}

/// Area of the 2-D convex hull (monotone chain).
fn hull_area_2d(pts: &mut [(f64, f64)]) -> f64 {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(pts.len() * 2);
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    let n = hull.len();
    if n < 3 {
        return 0.0;
    }
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (hull[i], hull[(i + 1) % n]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum::<f64>()
        .abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_3, FRAC_PI_4, PI};

    fn c(p: [f64; 3], n: [f64; 3]) -> ContactPoint {
        ContactPoint {
            position: Point3::from(p),
            normal: Vector3::from(n).normalize(),
        }
    }

    #[test]
    fn gii_two_antipodal_soft_contacts_equals_gamma() {
        // Hand computation (method.md §3): G·Gᵀ = diag(2, 2, 2, 2γ², 2, 2), so S = γ for γ ≤ 1.
        let pair = [
            c([0.03, 0.0, 0.0], [1.0, 0.0, 0.0]),
            c([-0.03, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        ];
        assert_relative_eq!(gii(&pair, 1.0), 1.0, epsilon = 1e-12);
        assert_relative_eq!(gii(&pair, 0.3), 0.3, epsilon = 1e-12);
        let ggt = soft_finger_ggt(&pair, 0.5).unwrap();
        let expect = Matrix6::from_diagonal(&Vector6::new(2.0, 2.0, 2.0, 0.5, 2.0, 2.0));
        assert_relative_eq!(ggt, expect, epsilon = 1e-12);
        // The scale of the object does not matter (spread-normalised moments).
        let big = [
            c([0.3, 0.0, 0.0], [1.0, 0.0, 0.0]),
            c([-0.3, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        ];
        assert_relative_eq!(gii(&big, 1.0), 1.0, epsilon = 1e-12);
    }

    #[test]
    fn gii_three_contacts_at_120_degrees_on_a_sphere() {
        // Contacts on the equator of a sphere, normals radial. Hand computation with unit
        // spread r̂ᵢ = (cos θᵢ, sin θᵢ, 0), γ = 1:
        //   forces:  Σ nnᵀ + t1t1ᵀ + t2t2ᵀ = 3·I₃ → Fx, Fy, Fz rows = 3;
        //   moments: r̂×n = 0; r̂×t (tangent in plane) = ±z; r̂×z = −(tangent): Mx, My each
        //            Σ over contacts of the in-plane tangent outer products = 3/2, plus torsion
        //            γ²·Σ nnᵀ (in-plane) = 3/2 → Mx = My = 3, Mz = 3;
        //   cross terms force–moment: Σ t_i z-moment... cancel by symmetry.
        // So G·Gᵀ = 3·I₆ and S = 1.
        let r = 0.04;
        let pts: Vec<ContactPoint> = (0..3)
            .map(|i| {
                let th = 2.0 * PI * i as f64 / 3.0;
                c([r * th.cos(), r * th.sin(), 0.0], [th.cos(), th.sin(), 0.0])
            })
            .collect();
        let ggt = soft_finger_ggt(&pts, 1.0).unwrap();
        assert_relative_eq!(ggt, Matrix6::identity() * 3.0, epsilon = 1e-9);
        assert_relative_eq!(gii(&pts, 1.0), 1.0, epsilon = 1e-9);
        // Without torsion the in-plane moments drop to 3/2 while forces stay 3: S = √(1/2).
        assert_relative_eq!(gii(&pts, 0.0), (0.5f64).sqrt(), epsilon = 1e-9);
    }

    #[test]
    fn gii_same_side_contacts_are_unstable() {
        // Two contacts on one face with parallel normals cannot resist a moment about the axis
        // through them along the face: σ_min = 0.
        let pts = [
            c([0.0, 0.02, 0.0], [1.0, 0.0, 0.0]),
            c([0.0, -0.02, 0.0], [1.0, 0.0, 0.0]),
        ];
        assert!(gii(&pts, 1.0) < 1e-9);
        assert_eq!(gii(&[pts[0], pts[0]], 1.0), 0.0);
    }

    #[test]
    fn reachability_against_hand_values() {
        let (a_max, h_max) = (0.08, 0.05);
        // Peak at half the opening, h = 0: cos 0 · e⁰ = 1.
        assert_relative_eq!(reachability(0.04, 0.0, a_max, h_max), 1.0, epsilon = 1e-12);
        // a = a_max/4: K(a − a_max/2) = −π/4 → cos = √2/2; h = 0.02: e^(−0.04).
        assert_relative_eq!(
            reachability(0.02, 0.02, a_max, h_max),
            FRAC_PI_4.cos() * (-0.04f64).exp(),
            epsilon = 1e-12
        );
        // Beyond the limits (either one): cos(−π/2)·e^(−0.1) = 0.
        assert_relative_eq!(reachability(0.09, 0.0, a_max, h_max), 0.0, epsilon = 1e-12);
        assert_relative_eq!(reachability(0.04, 0.06, a_max, h_max), 0.0, epsilon = 1e-12);
    }

    #[test]
    fn attention_against_hand_values() {
        let n = Vector3::z();
        assert_relative_eq!(attention(&n, &Vector3::x()), 0.0, epsilon = 1e-12);
        assert_relative_eq!(attention(&n, &Vector3::z()), -FRAC_PI_2, epsilon = 1e-12);
        assert_relative_eq!(attention(&n, &-Vector3::z()), -FRAC_PI_2, epsilon = 1e-12);
        // 60° between n and d → |π/3 − π/2| = π/6.
        let d = Vector3::new(FRAC_PI_3.sin(), 0.0, FRAC_PI_3.cos());
        assert_relative_eq!(attention(&n, &d), -PI / 6.0, epsilon = 1e-12);
        assert_relative_eq!(attention_palm(&n, &-Vector3::z()), 0.0, epsilon = 1e-12);
        assert_relative_eq!(
            attention_palm(&n, &Vector3::x()),
            -FRAC_PI_2,
            epsilon = 1e-12
        );
    }

    #[test]
    fn polygon_area_of_known_shapes() {
        let tri = [
            Point3::new(0.0, 0.0, 0.1),
            Point3::new(0.04, 0.0, 0.1),
            Point3::new(0.0, 0.03, 0.1),
        ];
        assert_relative_eq!(polygon_area(&tri), 0.5 * 0.04 * 0.03, epsilon = 1e-12);
        let sq = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.0, 0.02, 0.0),
            Point3::new(0.0, 0.02, 0.02),
            Point3::new(0.0, 0.0, 0.02),
            Point3::new(0.0, 0.01, 0.01),
        ];
        assert_relative_eq!(polygon_area(&sq), 0.0004, epsilon = 1e-12);
    }
}
