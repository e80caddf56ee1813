//! The robustness figure that ranks final configurations (issue 15): the largest force, applied
//! at the object's estimated centre of mass, that the contacts resist — in the weakest of the six
//! axis directions ±x, ±y, ±z of the planning frame (gravity along any of them, as DexGraspBench's
//! force-closure test applies it) and straight down (gravity as it is).
//!
//! Model: every contact pushes with a normal force of at most 1 (the unit is the grip force of
//! one contact, so the figure reads "this many contacts' grip forces"), its tangential force
//! inside a friction cone linearised by [`CONE_EDGES`] inscribed edges (μ cos(π/edges)), and, as a
//! soft finger, a torsional moment of at most μ·r_patch times its normal force. The contacts must
//! produce −t·d and no moment about the centre of mass; t is maximised by a linear program
//! (microlp). Moments are divided by the object radius ρ only to condition the program.
//!
//! GII (Eq 5.3) stays the stability constraint S ≥ ε; this figure adds what S ignores: where
//! the mass is and how much friction the contacts can call on.

use super::quality::{ContactPoint, tangents};
use microlp::{ComparisonOp, OptimizationDirection, Problem};
use nalgebra::{Point3, Vector3};

/// Edges of the linearised friction cone.
pub const CONE_EDGES: usize = 6;

/// The six axis directions and gravity.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Robustness {
    /// Resisted force along +x, −x, +y, −y, +z, −z (per unit normal force per contact).
    pub axes: [f64; 6],
    /// min of `axes`: the figure candidates are ranked by.
    pub weakest: f64,
    /// Resisted force straight down (−up), when up is known; else `weakest`.
    pub gravity: f64,
}

/// Robustness of `contacts` (outward normals) about `centre_of_mass`.
pub fn robustness(
    contacts: &[ContactPoint],
    centre_of_mass: &Point3<f64>,
    radius: f64,
    friction: f64,
    patch_radius: f64,
    up: Option<&Vector3<f64>>,
) -> Robustness {
    robustness_above(
        contacts,
        centre_of_mass,
        radius,
        friction,
        patch_radius,
        up,
        f64::NEG_INFINITY,
    )
    .unwrap_or_else(|r| r)
}

/// [`robustness`], stopped as soon as the weakest axis is known to be at most `floor` (a
/// search that only wants figures above it spares the remaining programs): `Err` then, with
/// the axes solved so far (the rest 0) and `weakest` the least of those — at least the true
/// weakest, and ≤ `floor`.
pub fn robustness_above(
    contacts: &[ContactPoint],
    centre_of_mass: &Point3<f64>,
    radius: f64,
    friction: f64,
    patch_radius: f64,
    up: Option<&Vector3<f64>>,
    floor: f64,
) -> Result<Robustness, Robustness> {
    let dirs = [
        Vector3::x(),
        -Vector3::x(),
        Vector3::y(),
        -Vector3::y(),
        Vector3::z(),
        -Vector3::z(),
    ];
    let mut axes = [0.0; 6];
    let mut weakest = f64::INFINITY;
    for (a, d) in axes.iter_mut().zip(&dirs) {
        *a = resisted_force(contacts, centre_of_mass, radius, friction, patch_radius, d);
        weakest = weakest.min(*a);
        if weakest <= floor {
            return Err(Robustness {
                axes,
                weakest,
                gravity: weakest,
            });
        }
    }
    let gravity = up
        .and_then(|u| u.try_normalize(1e-9))
        .map(|u| {
            resisted_force(
                contacts,
                centre_of_mass,
                radius,
                friction,
                patch_radius,
                &-u,
            )
        })
        .unwrap_or(weakest);
    Ok(Robustness {
        axes,
        weakest,
        gravity,
    })
}

/// The largest t such that the contacts balance a force t·`direction` applied at
/// `centre_of_mass` (module model). 0 when they cannot resist it at all.
pub fn resisted_force(
    contacts: &[ContactPoint],
    centre_of_mass: &Point3<f64>,
    radius: f64,
    friction: f64,
    patch_radius: f64,
    direction: &Vector3<f64>,
) -> f64 {
    let Some(d) = direction.try_normalize(1e-12) else {
        return 0.0;
    };
    if contacts.is_empty() {
        return 0.0;
    }
    let rho = radius.max(1e-3);
    let mu = friction.max(0.0);
    let torsion = mu * patch_radius;
    let mut lp = Problem::new(OptimizationDirection::Maximize);
    let t = lp.add_var(1.0, (0.0, 1e3));
    // Rows of the balance: three forces, three moments (divided by ρ).
    let mut rows: [Vec<(microlp::Variable, f64)>; 6] = Default::default();
    for (k, row) in rows.iter_mut().enumerate().take(3) {
        row.push((t, d[k]));
    }
    for c in contacts {
        let inward = -c.normal;
        let (t1, t2) = tangents(&inward);
        let r = c.position - centre_of_mass;
        let mut normal_sum = Vec::with_capacity(CONE_EDGES);
        for e in 0..CONE_EDGES {
            let phi = std::f64::consts::TAU * e as f64 / CONE_EDGES as f64;
            let f = inward + mu * (phi.cos() * t1 + phi.sin() * t2);
            let m = r.cross(&f) / rho;
            let v = lp.add_var(0.0, (0.0, f64::INFINITY));
            for k in 0..3 {
                rows[k].push((v, f[k]));
                rows[3 + k].push((v, m[k]));
            }
            normal_sum.push((v, 1.0));
        }
        // Normal force ≤ 1.
        lp.add_constraint(normal_sum.as_slice(), ComparisonOp::Le, 1.0);
        // Torsion ±, bounded by μ·r_patch times the normal force.
        let tp = lp.add_var(0.0, (0.0, f64::INFINITY));
        let tm = lp.add_var(0.0, (0.0, f64::INFINITY));
        for k in 0..3 {
            rows[3 + k].push((tp, inward[k] / rho));
            rows[3 + k].push((tm, -inward[k] / rho));
        }
        let mut bound: Vec<(microlp::Variable, f64)> = vec![(tp, 1.0), (tm, 1.0)];
        bound.extend(normal_sum.iter().map(|&(v, _)| (v, -torsion)));
        lp.add_constraint(bound.as_slice(), ComparisonOp::Le, 0.0);
    }
    for row in &rows {
        lp.add_constraint(row.as_slice(), ComparisonOp::Eq, 0.0);
    }
    match lp.solve().map(|o| o.into_solution()) {
        Ok(Ok(s)) => s.objective().max(0.0),
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two antipodal contacts on x, 3 cm either side of the axis, at height z.
    fn pinch_at(z: f64) -> [ContactPoint; 2] {
        [
            contact([-0.03, 0.0, z], [-1.0, 0.0, 0.0]),
            contact([0.03, 0.0, z], [1.0, 0.0, 0.0]),
        ]
    }

    fn contact(p: [f64; 3], n: [f64; 3]) -> ContactPoint {
        ContactPoint {
            position: Point3::new(p[0], p[1], p[2]),
            normal: Vector3::new(n[0], n[1], n[2]).normalize(),
        }
    }

    /// Two antipodal contacts on x through the centre of mass, μ = 0.6, 6 edges: along ±x one
    /// contact pushes with its full normal force (t = 1); across, both contacts' friction holds
    /// at most 2μ and at least the hexagon's inscribed 2μ·cos 30°, depending on how the edges lie
    /// against the direction.
    #[test]
    fn an_antipodal_pinch_through_the_centre_resists_what_friction_allows() {
        let c = pinch_at(0.0);
        let com = Point3::origin();
        let r = robustness(&c, &com, 0.03, 0.6, 0.01, Some(&Vector3::z()));
        assert!((r.axes[0] - 1.0).abs() < 1e-6, "{:?}", r.axes);
        assert!((r.axes[1] - 1.0).abs() < 1e-6, "{:?}", r.axes);
        let mu = 0.6;
        for k in 2..6 {
            assert!(
                r.axes[k] >= 2.0 * mu * (std::f64::consts::PI / 6.0).cos() - 1e-6
                    && r.axes[k] <= 2.0 * mu + 1e-6,
                "{k}: {:?}",
                r.axes
            );
        }
        assert!((r.gravity - r.axes[5]).abs() < 1e-9);
        assert!((r.weakest - r.axes.iter().copied().fold(f64::INFINITY, f64::min)).abs() < 1e-12);
    }

    /// Stopped early: with a floor of 1.5 the first axis (+x, where one contact pushes with its
    /// full normal force: 1) already falls to it, so only that program runs and the cut says so;
    /// with a floor below every axis the figure is the whole one.
    #[test]
    fn a_floor_stops_the_programs_once_the_weakest_axis_is_below_it() {
        let c = pinch_at(0.0);
        let com = Point3::origin();
        let full = robustness(&c, &com, 0.03, 0.6, 0.01, None);
        let above = robustness_above(&c, &com, 0.03, 0.6, 0.01, None, 0.5).unwrap();
        assert_eq!(above, full);
        let cut = robustness_above(&c, &com, 0.03, 0.6, 0.01, None, 1.5).unwrap_err();
        assert!((cut.weakest - 1.0).abs() < 1e-6, "{cut:?}");
        assert_eq!(cut.axes[1..], [0.0; 5]);
        assert!(cut.weakest >= full.weakest - 1e-12);
    }

    /// The same pinch 5 cm above the centre of mass: a downward force at the centre of mass now
    /// also tilts the object about the contact line, which only the contacts' torsion (μ·r_patch
    /// per unit force) resists, so the resisted weight drops sharply.
    #[test]
    fn a_pinch_far_from_the_centre_of_mass_resists_less() {
        let at = pinch_at;
        let com = Point3::origin();
        let centred = resisted_force(&at(0.0), &com, 0.05, 0.6, 0.01, &-Vector3::z());
        let high = resisted_force(&at(0.05), &com, 0.05, 0.6, 0.01, &-Vector3::y());
        assert!(centred > 1.0, "{centred}");
        // Along −y at 5 cm above: the moment 0.05 t about x is held by torsion 2·0.006 f_n.
        assert!(high < 0.25 * centred, "{high} vs {centred}");
        assert!(resisted_force(&[], &com, 0.05, 0.6, 0.01, &Vector3::z()) == 0.0);
    }
}
