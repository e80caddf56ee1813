//! The Ferrari–Canny ε-metric (L1 form) over linearised soft-finger friction cones: the radius of
//! the largest wrench ball around the origin inside the convex hull of the contacts' primitive
//! wrenches. Reported beside S as the physically grounded figure (method.md §3); it is not part of
//! the objective.
//!
//! Model: per contact, `edges` force directions on the friction cone (μ) with unit normal force,
//! each combined with ± a torsional moment μ_t·f_n about the normal (soft finger, μ_t = μ·r_patch).
//! Moments about the object's estimated centre of mass, divided by the object radius ρ.
//!
//! The 6-D hull is not enumerated. The support function h(u) = maxᵢ u·wᵢ is sampled on fixed
//! directions of S⁵; from the lowest ones the facet through the six most active wrenches is
//! solved and accepted when every wrench lies behind it. ε is the smallest such facet distance
//! (or sampled h, both upper bounds of the true ε); the unit tests compare it with brute-force facet
//! enumeration.

use super::quality::{ContactPoint, tangents};
use nalgebra::{Matrix6, Point3, Vector6};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::sync::OnceLock;

/// Parameters of the wrench model.
#[derive(Debug, Clone, Copy)]
pub struct WrenchModel {
    pub friction: f64,
    pub edges: usize,
    /// Radius of the contact patch that gives the torsional friction μ_t = μ·r_patch, m.
    pub patch_radius: f64,
}

impl Default for WrenchModel {
    fn default() -> Self {
        Self {
            friction: 0.6,
            edges: 8,
            patch_radius: 0.01,
        }
    }
}

/// The primitive wrenches of the contacts (forces applied on the object, inward).
pub fn primitive_wrenches(
    contacts: &[ContactPoint],
    center_of_mass: &Point3<f64>,
    radius: f64,
    model: WrenchModel,
) -> Vec<Vector6<f64>> {
    let rho = radius.max(1e-6);
    let tors = model.friction * model.patch_radius / rho;
    let mut w = Vec::with_capacity(contacts.len() * model.edges * 2);
    for c in contacts {
        let inward = -c.normal;
        let (t1, t2) = tangents(&inward);
        let r = c.position - center_of_mass;
        for j in 0..model.edges {
            let phi = 2.0 * std::f64::consts::PI * j as f64 / model.edges as f64;
            let f = inward + model.friction * (phi.cos() * t1 + phi.sin() * t2);
            let m = r.cross(&f) / rho;
            for s in [1.0, -1.0] {
                let mt = m + inward * (s * tors);
                w.push(Vector6::new(f.x, f.y, f.z, mt.x, mt.y, mt.z));
            }
        }
    }
    w
}

fn directions() -> &'static [Vector6<f64>] {
    static DIRS: OnceLock<Vec<Vector6<f64>>> = OnceLock::new();
    DIRS.get_or_init(|| {
        use rand_distr_free::gaussian;
        let mut rng = ChaCha8Rng::seed_from_u64(0xfe44a41);
        let mut v = Vec::with_capacity(1012);
        for k in 0..6 {
            for s in [1.0, -1.0] {
                let mut e = Vector6::zeros();
                e[k] = s;
                v.push(e);
            }
        }
        while v.len() < 1012 {
            let g = Vector6::from_fn(|_, _| gaussian(&mut rng));
            let n = g.norm();
            if n > 1e-6 {
                v.push(g / n);
            }
        }
        v
    })
}

/// Box–Muller normal samples from a seeded generator (kept local: one use, no extra crate).
mod rand_distr_free {
    use rand::RngExt;
    pub fn gaussian(rng: &mut impl rand::Rng) -> f64 {
        let u1: f64 = rng.random_range(f64::EPSILON..1.0);
        let u2: f64 = rng.random();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

/// Lowest sampled directions used as starts of the vertex search.
const STARTS: usize = 8;
const TIGHT: f64 = 1e-9;

/// Facets of conv(W) at distance δ from the origin are the vertices a of P° = {a : a·wᵢ ≤ 1} with
/// ‖a‖ = 1/δ, so the nearest facet is the vertex of largest norm. From a feasible point, moves to
/// a vertex while increasing ‖a‖, then pivots along edges (simplex-style) while the norm grows.
/// Returns the distance 1/‖a‖ of the local optimum.
fn polar_hill_climb(w: &[Vector6<f64>], a0: Vector6<f64>) -> Option<f64> {
    let mut a = a0;
    let mut tight: Vec<usize> = Vec::with_capacity(6);
    // Phase 1: reach a vertex (six independent tight constraints).
    for _ in 0..64 {
        tight.clear();
        for (i, x) in w.iter().enumerate() {
            if a.dot(x) >= 1.0 - TIGHT && tight.len() < 6 && independent(w, &tight, i) {
                tight.push(i);
            }
        }
        if tight.len() == 6 {
            break;
        }
        // Direction in the null space of the tight rows that does not decrease ‖a‖.
        let mut d = a;
        let basis = orthonormal_rows(w, &tight);
        for b in &basis {
            d -= b * b.dot(&d);
        }
        if d.norm() < 1e-12 {
            // a is orthogonal to the null space: any null direction keeps ‖a‖ non-decreasing.
            let mut e = Vector6::zeros();
            for k in 0..6 {
                e.fill(0.0);
                e[k] = 1.0;
                for b in &basis {
                    e -= b * b.dot(&e);
                }
                if e.norm() > 1e-9 {
                    break;
                }
            }
            d = if e.dot(&a) >= 0.0 { e } else { -e };
        }
        let t = ratio_test(w, &a, &d)?;
        a += d * t;
    }
    if tight.len() < 6 {
        return None;
    }
    // Phase 2: pivot to neighbouring vertices while the norm grows.
    for _ in 0..256 {
        let m = Matrix6::from_fn(|r, c| w[tight[r]][c]);
        let inv = m.try_inverse()?;
        let mut improved = false;
        for k in 0..6 {
            // Leaving constraint k: d = −M⁻¹eₖ keeps the others tight and loosens k.
            let d: Vector6<f64> = -inv.column(k).into_owned();
            let Some(t) = ratio_test(w, &a, &d) else {
                return Some(0.0); // unbounded P°: the origin is on the hull's boundary
            };
            let next = a + d * t;
            if next.norm_squared() > a.norm_squared() * (1.0 + 1e-12) {
                let entering = (0..w.len())
                    .filter(|&i| !tight.contains(&i))
                    .find(|&i| next.dot(&w[i]) >= 1.0 - TIGHT && w[i].dot(&d) > 0.0)?;
                tight[k] = entering;
                a = next;
                improved = true;
                break;
            }
        }
        if !improved {
            break;
        }
    }
    let n = a.norm();
    (n > 1e-12).then(|| 1.0 / n)
}

/// Largest step t ≥ 0 along d keeping every a·wᵢ ≤ 1 (None when unbounded).
fn ratio_test(w: &[Vector6<f64>], a: &Vector6<f64>, d: &Vector6<f64>) -> Option<f64> {
    let mut t = f64::INFINITY;
    for x in w {
        let rate = x.dot(d);
        if rate > 1e-12 {
            t = t.min(((1.0 - a.dot(x)) / rate).max(0.0));
        }
    }
    t.is_finite().then_some(t)
}

fn orthonormal_rows(w: &[Vector6<f64>], rows: &[usize]) -> Vec<Vector6<f64>> {
    let mut basis: Vec<Vector6<f64>> = Vec::with_capacity(rows.len());
    for &r in rows {
        let mut v = w[r];
        for b in &basis {
            v -= b * b.dot(&v);
        }
        let n = v.norm();
        if n > 1e-9 {
            basis.push(v / n);
        }
    }
    basis
}

fn independent(w: &[Vector6<f64>], rows: &[usize], i: usize) -> bool {
    let mut v = w[i];
    for b in orthonormal_rows(w, rows) {
        v -= b * b.dot(&v);
    }
    v.norm() > 1e-7 * w[i].norm().max(1e-12)
}

/// Calls `f` with every ascending 6-subset of 0..n.
#[cfg(test)]
fn for_each_6_subset(n: usize, mut f: impl FnMut(&[usize; 6])) {
    if n < 6 {
        return;
    }
    let mut idx = [0usize, 1, 2, 3, 4, 5];
    loop {
        f(&idx);
        let mut k = 5;
        loop {
            if idx[k] < n - 6 + k {
                idx[k] += 1;
                for j in k + 1..6 {
                    idx[j] = idx[j - 1] + 1;
                }
                break;
            }
            if k == 0 {
                return;
            }
            k -= 1;
        }
    }
}

/// ε of the wrench set: the distance from the origin to the nearest facet of its convex hull, or
/// 0 when the origin is not strictly inside (no force closure).
pub fn epsilon_of_wrenches(w: &[Vector6<f64>]) -> f64 {
    if w.len() < 7 {
        return 0.0;
    }
    let dirs = directions();
    let support = |u: &Vector6<f64>| w.iter().map(|x| u.dot(x)).fold(f64::NEG_INFINITY, f64::max);
    let mut scored: Vec<(f64, usize)> = dirs
        .iter()
        .enumerate()
        .map(|(i, u)| (support(u), i))
        .collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    if scored[0].0 <= 1e-9 {
        return 0.0;
    }
    let mut best = scored[0].0;
    for &(h, i) in scored.iter().take(STARTS) {
        // a₀ = u / h(u) lies in the polar polytope P° = {a : a·wᵢ ≤ 1} with a tight constraint.
        let a0 = dirs[i] / h;
        if let Some(d) = polar_hill_climb(w, a0) {
            best = best.min(d);
        }
    }
    best.max(0.0)
}

/// Ferrari–Canny ε of a grasp (see the module doc).
pub fn ferrari_canny(
    contacts: &[ContactPoint],
    center_of_mass: &Point3<f64>,
    radius: f64,
    model: WrenchModel,
) -> f64 {
    epsilon_of_wrenches(&primitive_wrenches(contacts, center_of_mass, radius, model))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// Exact ε by enumerating every 6-subset as a candidate facet.
    fn brute_force(w: &[Vector6<f64>]) -> f64 {
        let mut best = f64::INFINITY;
        for_each_6_subset(w.len(), |idx| {
            let m = Matrix6::from_fn(|r, c| w[idx[r]][c]);
            if let Some(a) = m.lu().solve(&Vector6::repeat(1.0))
                && a.iter().all(|v| v.is_finite())
                && w.iter().all(|x| a.dot(x) <= 1.0 + 1e-9)
            {
                best = best.min(1.0 / a.norm());
            }
        });
        if best.is_finite() { best } else { 0.0 }
    }

    fn c(p: [f64; 3], n: [f64; 3]) -> ContactPoint {
        ContactPoint {
            position: Point3::from(p),
            normal: Vector3::from(n).normalize(),
        }
    }

    #[test]
    fn matches_brute_force_on_small_grasps() {
        let model = WrenchModel {
            friction: 0.6,
            edges: 4,
            patch_radius: 0.01,
        };
        let com = Point3::origin();
        let pair = [
            c([0.03, 0.0, 0.0], [1.0, 0.0, 0.0]),
            c([-0.03, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        ];
        let w = primitive_wrenches(&pair, &com, 0.04, model);
        let (fast, exact) = (epsilon_of_wrenches(&w), brute_force(&w));
        assert!(exact > 0.0);
        assert!((fast - exact).abs() < 1e-9, "fast {fast} exact {exact}");

        let tri: Vec<ContactPoint> = (0..3)
            .map(|i| {
                let th = 2.0 * std::f64::consts::PI * i as f64 / 3.0 + 0.3;
                c(
                    [0.04 * th.cos(), 0.04 * th.sin(), 0.005],
                    [th.cos(), th.sin(), 0.1],
                )
            })
            .collect();
        let w = primitive_wrenches(&tri, &com, 0.04, WrenchModel { edges: 3, ..model });
        let (fast, exact) = (epsilon_of_wrenches(&w), brute_force(&w));
        assert!(exact > 0.0);
        assert!(
            (fast - exact).abs() < 1e-6 * exact.max(1.0),
            "fast {fast} exact {exact}"
        );
    }

    #[test]
    fn no_force_closure_gives_zero() {
        // Both contacts push the same way: the origin is outside the hull.
        let same = [
            c([0.03, 0.0, 0.0], [1.0, 0.0, 0.0]),
            c([0.03, 0.02, 0.0], [1.0, 0.0, 0.0]),
        ];
        assert_eq!(
            ferrari_canny(&same, &Point3::origin(), 0.04, WrenchModel::default()),
            0.0
        );
    }

    #[test]
    fn centred_antipodal_grasp_beats_an_off_centre_one() {
        let m = WrenchModel::default();
        let com = Point3::origin();
        let centred = [
            c([0.03, 0.0, 0.0], [1.0, 0.0, 0.0]),
            c([-0.03, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        ];
        let off = [
            c([0.03, 0.0, 0.05], [1.0, 0.0, 0.0]),
            c([-0.03, 0.0, 0.05], [-1.0, 0.0, 0.0]),
        ];
        let (a, b) = (
            ferrari_canny(&centred, &com, 0.08, m),
            ferrari_canny(&off, &com, 0.08, m),
        );
        assert!(a > b && b > 0.0, "centred {a} off {b}");
    }
}
