//! The grip forces of a squeeze (issue 15): contact forces with which every touching finger
//! presses the object and that cancel — no net force and no net moment about the object's
//! estimated centre of mass — so that the squeeze holds the object where it stands instead of
//! pushing it out of the closing hand (grasp force optimisation).
//!
//! A squeeze that presses every contact equally deep is balanced only when the contacts are
//! antipodal and equally stiff: three fingers against a thumb, each driven to the same depth,
//! push the object toward the thumb with twice one finger's force, and a light object squirts
//! out (measured in MuJoCo on the Allegro: objects moved 3–24 cm during the close). Here the
//! forces are chosen first and the joints follow from them (`final_configuration::squeeze`).
//!
//! Model: contact i pushes the object with f_i inside a friction cone of half the request's μ
//! (linearised by [`CONE_EDGES`] edges), so the grip leans on its normals and keeps a margin
//! against the estimated normals' error; its normal part a_i. Every pressing group (a finger)
//! presses with Σ a_i ≥ 1 over its contacts; passive contacts (the palm) only push back. The
//! forces satisfy Σ f_i = 0 and Σ (p_i − c) × f_i = 0, and the program minimises the largest
//! group's press (then the total), so no finger does the work of two. Moments are divided by
//! the object radius only to condition the program.

use super::quality::tangents;
use microlp::{ComparisonOp, OptimizationDirection, Problem};
use nalgebra::{Point3, Vector3};

/// Edges of the linearised friction cone.
pub const CONE_EDGES: usize = 6;
/// Share of the friction coefficient the grip may lean on.
pub const FRICTION_SHARE: f64 = 0.5;

/// One contact of the grip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GripContact {
    pub position: Point3<f64>,
    /// Unit normal pointing into the object.
    pub inward: Vector3<f64>,
    /// The group that presses through it (a finger), or None for a passive contact (the palm).
    pub group: Option<usize>,
}

/// Balanced contact forces on the object, one per contact, scaled so that the largest group
/// presses with a summed normal force of 1; None when the contacts cannot balance a press of
/// every group (they all push one way).
pub fn balanced_grip(
    contacts: &[GripContact],
    centre_of_mass: &Point3<f64>,
    radius: f64,
    friction: f64,
) -> Option<Vec<Vector3<f64>>> {
    if contacts.iter().all(|c| c.group.is_none()) {
        return None;
    }
    let rho = radius.max(1e-3);
    let mu = (friction * FRICTION_SHARE).max(0.0);
    let mut lp = Problem::new(OptimizationDirection::Minimize);
    let largest = lp.add_var(1.0, (0.0, f64::INFINITY));
    let mut rows: [Vec<(microlp::Variable, f64)>; 6] = Default::default();
    let mut edges: Vec<Vec<(microlp::Variable, Vector3<f64>)>> = Vec::new();
    let mut groups: Vec<(usize, Vec<(microlp::Variable, f64)>)> = Vec::new();
    for c in contacts {
        let (t1, t2) = tangents(&c.inward);
        let r = c.position - centre_of_mass;
        let mut mine = Vec::with_capacity(CONE_EDGES);
        for e in 0..CONE_EDGES {
            let phi = std::f64::consts::TAU * e as f64 / CONE_EDGES as f64;
            let f = c.inward + mu * (phi.cos() * t1 + phi.sin() * t2);
            let m = r.cross(&f) / rho;
            // A little weight on the total, so that among the balanced grips the lightest wins.
            let v = lp.add_var(1e-3, (0.0, f64::INFINITY));
            for k in 0..3 {
                rows[k].push((v, f[k]));
                rows[3 + k].push((v, m[k]));
            }
            mine.push((v, f));
        }
        if let Some(g) = c.group {
            let at = match groups.iter().position(|(h, _)| *h == g) {
                Some(k) => k,
                None => {
                    groups.push((g, Vec::new()));
                    groups.len() - 1
                }
            };
            groups[at].1.extend(mine.iter().map(|&(v, _)| (v, 1.0)));
        }
        edges.push(mine);
    }
    for row in &rows {
        lp.add_constraint(row.as_slice(), ComparisonOp::Eq, 0.0);
    }
    for (_, press) in &groups {
        lp.add_constraint(press.as_slice(), ComparisonOp::Ge, 1.0);
        let mut below: Vec<(microlp::Variable, f64)> = press.clone();
        below.push((largest, -1.0));
        lp.add_constraint(below.as_slice(), ComparisonOp::Le, 0.0);
    }
    let solution = lp.solve().ok()?.into_solution().ok()?;
    let top = solution[largest].max(1e-9);
    Some(
        edges
            .iter()
            .map(|mine| {
                mine.iter()
                    .map(|&(v, f)| f * solution[v])
                    .sum::<Vector3<f64>>()
                    / top
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contact(p: [f64; 3], inward: [f64; 3], group: Option<usize>) -> GripContact {
        GripContact {
            position: Point3::new(p[0], p[1], p[2]),
            inward: Vector3::new(inward[0], inward[1], inward[2]).normalize(),
            group,
        }
    }

    fn net(contacts: &[GripContact], f: &[Vector3<f64>]) -> (Vector3<f64>, Vector3<f64>) {
        let force = f.iter().sum();
        let moment = contacts
            .iter()
            .zip(f)
            .map(|(c, f)| c.position.coords.cross(f))
            .sum();
        (force, moment)
    }

    /// A thumb against three fingers on a 4 cm sphere, all on its equator: each finger presses
    /// about a third of what the thumb does (the thumb is the largest group), and nothing is
    /// left over.
    #[test]
    fn three_fingers_against_a_thumb_press_a_third_each() {
        let r = 0.04;
        let mut c = vec![contact([-r, 0.0, 0.0], [1.0, 0.0, 0.0], Some(0))];
        for (k, y) in [-0.02f64, 0.0, 0.02].iter().enumerate() {
            let x = (r * r - y * y).sqrt();
            c.push(contact([x, *y, 0.0], [-x, -y, 0.0], Some(k + 1)));
        }
        let f = balanced_grip(&c, &Point3::origin(), r, 0.6).unwrap();
        let (force, moment) = net(&c, &f);
        assert!(
            force.norm() < 1e-6 && moment.norm() < 1e-6,
            "{force} {moment}"
        );
        let normal: Vec<f64> = c.iter().zip(&f).map(|(c, f)| f.dot(&c.inward)).collect();
        assert!((normal[0] - 1.0).abs() < 1e-6, "{normal:?}");
        let fingers: f64 = normal[1..].iter().sum();
        // The outer fingers' normals lean 30° away from x (cos 30° = 0.87), so together the
        // fingers press a little more than the thumb: 1/(1 + 2·0.87) = 0.37 each with normal
        // forces alone, up to 0.45 as friction shares the press.
        assert!((1.0..1.3).contains(&fingers), "{normal:?}");
        for n in &normal[1..] {
            assert!((0.25..0.45).contains(n), "{normal:?}");
        }
    }

    /// Fingers that all press one way, with nothing against them, cannot balance; a palm
    /// behind the object can, and it takes the whole press back.
    #[test]
    fn one_sided_fingers_need_the_palm() {
        let c = [
            contact([0.03, -0.01, 0.0], [-1.0, 0.0, 0.0], Some(0)),
            contact([0.03, 0.01, 0.0], [-1.0, 0.0, 0.0], Some(1)),
        ];
        assert!(balanced_grip(&c, &Point3::origin(), 0.03, 0.6).is_none());
        let mut with_palm = c.to_vec();
        with_palm.push(contact([-0.03, 0.0, 0.0], [1.0, 0.0, 0.0], None));
        let f = balanced_grip(&with_palm, &Point3::origin(), 0.03, 0.6).unwrap();
        let (force, moment) = net(&with_palm, &f);
        assert!(force.norm() < 1e-6 && moment.norm() < 1e-6);
        assert!((f[2].dot(&with_palm[2].inward) - 2.0).abs() < 1e-6, "{f:?}");
    }
}
