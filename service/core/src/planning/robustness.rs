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
//! ([`super::dense_simplex`], with microlp behind it; session 33). Moments are divided by the
//! object radius ρ only to condition the program.
//!
//! GII (Eq 5.3) stays the stability constraint S ≥ ε; this figure adds what S ignores: where
//! the mass is and how much friction the contacts can call on.

use super::dense_simplex::{DenseProgram, Row};
use super::quality::{ContactPoint, tangents};
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
    robustness_program(
        contacts,
        centre_of_mass,
        radius,
        friction,
        patch_radius,
        direction,
    )
    .and_then(|lp| lp.maximize())
    .map_or(0.0, |(value, _)| value.max(0.0))
}

/// The linear program of [`resisted_force`]: maximise t (variable 0); None without contacts or
/// a direction.
fn robustness_program(
    contacts: &[ContactPoint],
    centre_of_mass: &Point3<f64>,
    radius: f64,
    friction: f64,
    patch_radius: f64,
    direction: &Vector3<f64>,
) -> Option<DenseProgram> {
    let d = direction.try_normalize(1e-12)?;
    if contacts.is_empty() {
        return None;
    }
    let rho = radius.max(1e-3);
    let mu = friction.max(0.0);
    let torsion = mu * patch_radius;
    let mut lp = DenseProgram::default();
    let t = lp.add_var(1.0, 1e3);
    // Columns first (the program's rows are dense over them): per contact its cone edges, then
    // its torsion + and −.
    let firsts: Vec<usize> = contacts
        .iter()
        .map(|_| {
            let first = lp.add_var(0.0, f64::INFINITY);
            (1..CONE_EDGES + 2).for_each(|_| {
                lp.add_var(0.0, f64::INFINITY);
            });
            first
        })
        .collect();
    // Rows of the balance: three forces, three moments (divided by ρ).
    let mut rows: [Vec<(usize, f64)>; 6] = Default::default();
    for (k, row) in rows.iter_mut().enumerate().take(3) {
        row.push((t, d[k]));
    }
    for (c, &first) in contacts.iter().zip(&firsts) {
        let inward = -c.normal;
        let (t1, t2) = tangents(&inward);
        let r = c.position - centre_of_mass;
        let edges: Vec<usize> = (first..first + CONE_EDGES).collect();
        for (e, &v) in edges.iter().enumerate() {
            let phi = std::f64::consts::TAU * e as f64 / CONE_EDGES as f64;
            let f = inward + mu * (phi.cos() * t1 + phi.sin() * t2);
            let m = r.cross(&f) / rho;
            for k in 0..3 {
                rows[k].push((v, f[k]));
                rows[3 + k].push((v, m[k]));
            }
        }
        // Normal force ≤ 1.
        let normal_sum: Vec<(usize, f64)> = edges.iter().map(|&v| (v, 1.0)).collect();
        lp.add_row(&normal_sum, Row::Le, 1.0);
        // Torsion ±, bounded by μ·r_patch times the normal force.
        let (tp, tm) = (first + CONE_EDGES, first + CONE_EDGES + 1);
        for k in 0..3 {
            rows[3 + k].push((tp, inward[k] / rho));
            rows[3 + k].push((tm, -inward[k] / rho));
        }
        let mut bound: Vec<(usize, f64)> = vec![(tp, 1.0), (tm, 1.0)];
        bound.extend(edges.iter().map(|&v| (v, -torsion)));
        lp.add_row(&bound, Row::Le, 0.0);
    }
    for row in &rows {
        lp.add_row(row, Row::Eq, 0.0);
    }
    Some(lp)
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

    /// The dense simplex gives microlp's optimum on the robustness programs of random contact
    /// sets (2–6 contacts, any normals, some pointing the same way so that nothing is resisted,
    /// any direction): the two solvers agree to 1e-7.
    #[test]
    fn the_dense_simplex_agrees_with_microlp_on_random_programs() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(33);
        let unit = |rng: &mut rand_chacha::ChaCha8Rng| -> Vector3<f64> {
            loop {
                let v = Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                if let Some(u) = v.try_normalize(0.1) {
                    return u;
                }
            }
        };
        let mut positive = 0;
        for case in 0..400 {
            let n = rng.random_range(2..=6);
            let contacts: Vec<ContactPoint> = (0..n)
                .map(|_| {
                    let p: Vector3<f64> = unit(&mut rng) * rng.random_range(0.01..0.06);
                    // Mostly outward-ish normals, as on an object's surface; some at random.
                    let normal = if rng.random_bool(0.7) {
                        (p.normalize() + 0.5 * unit(&mut rng)).normalize()
                    } else {
                        unit(&mut rng)
                    };
                    ContactPoint {
                        position: Point3::from(p),
                        normal,
                    }
                })
                .collect();
            let d = unit(&mut rng);
            let com = Point3::from(unit(&mut rng) * 0.01);
            let mu = rng.random_range(0.2..1.0);
            let program = robustness_program(&contacts, &com, 0.04, mu, 0.01, &d).unwrap();
            let dense = program
                .maximize_dense()
                .expect("the dense simplex solves it");
            let reference = program.maximize_microlp().expect("microlp solves it");
            assert!(
                (dense.0 - reference.0).abs() <= 1e-7 * (1.0 + reference.0.abs()),
                "case {case}: dense {} microlp {}",
                dense.0,
                reference.0
            );
            positive += usize::from(reference.0 > 1e-6);
        }
        // Both kinds of answer occur: contacts that resist the direction and those that cannot.
        assert!((100..400).contains(&positive), "{positive}");
    }
}
