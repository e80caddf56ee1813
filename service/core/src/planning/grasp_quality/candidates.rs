//! The candidate grasps G of Eq 3.2 and the initial set of the Bayesian search (dissertation
//! §3.2.3, "sampled from the depth image"), for a parallel-jaw gripper coming straight down.
//!
//! Choice where the text leaves it open (it cites Smith et al.'s sampler): an object point at
//! random (of the visible points and their completed unseen side, `cloud::completion`, as the
//! planner sees the object), the jaws' line through it at a random angle θ, the jaws' centre a
//! random 10–40 mm below that point (at least [`MIN_HEIGHT`] above the table), moved along the
//! line to the middle of the section the jaws close on; kept when they enclose it within the
//! opening less 5 mm ([`ParallelGrasp::centred`]).

use crate::cloud::{CloudIndex, Plane, symmetric_completion};
use crate::planning::parallel_grasp::{ParallelGrasp, TableFrame};
use crate::planning::scene::PLANE_BAND;
use nalgebra::Point3;
use rand::{Rng, RngExt};

/// Lowest jaw centre above the table, m (a jaw's pad is about 20 mm tall).
pub const MIN_HEIGHT: f64 = 0.012;
/// Depths below the sampled point the jaws' centre is put at, m.
pub const DEPTHS: (f64, f64) = (0.01, 0.04);
/// Attempts per candidate asked for before the sampler gives up.
const ATTEMPTS: usize = 20;
/// Features' length unit for the search's kernel, m: qualities of grasps this far apart are
/// alike (about a jaw pad's width).
pub const FEATURE_UNIT: f64 = 0.02;

/// The object as the planner sees it from one view: the visible points above the table's noise
/// band (`scene::PLANE_BAND`), and those with the unseen side completed
/// (`cloud::symmetric_completion`, as `plan` does) — the crop is made of the first, the
/// candidates are sampled on the second.
pub fn object_from_view(
    points: &[Point3<f64>],
    plane: &Plane,
    viewpoint: &Point3<f64>,
) -> (Vec<Point3<f64>>, Vec<Point3<f64>>) {
    let visible: Vec<Point3<f64>> = points
        .iter()
        .filter(|p| plane.distance(p) >= PLANE_BAND)
        .copied()
        .collect();
    let completed = symmetric_completion(&visible, viewpoint, &plane.normal, Some(plane))
        .map_or_else(|| visible.clone(), |c| c.points);
    (visible, completed)
}

/// Up to `n` candidates on the object whose points (visible and completed) are `points`
/// (indexed by `index`) on `table`, for jaws that open `max_opening`.
pub fn sample_candidates(
    points: &[Point3<f64>],
    index: &CloudIndex,
    table: &TableFrame,
    max_opening: f64,
    n: usize,
    rng: &mut impl Rng,
) -> Vec<ParallelGrasp> {
    let mut out = Vec::with_capacity(n);
    if points.is_empty() {
        return out;
    }
    for _ in 0..n * ATTEMPTS {
        if out.len() == n {
            break;
        }
        let p = points[rng.random_range(0..points.len())];
        let theta = rng.random_range(0.0..std::f64::consts::PI);
        let h = (p - table.origin).dot(&table.z);
        let z = (h - rng.random_range(DEPTHS.0..DEPTHS.1)).max(MIN_HEIGHT);
        let on_table = p - table.z * h;
        let g = ParallelGrasp {
            centre: on_table + table.z * z,
            axis: table.x * theta.cos() + table.y * theta.sin(),
        };
        if let Some((g, (a, b))) = g.centred(points, index, max_opening / 2.0)
            && (points[b] - points[a]).dot(&g.axis) <= max_opening - 0.005
        {
            out.push(g);
        }
    }
    out
}

/// The search's features of `g` on `table`: x, y and z in [`FEATURE_UNIT`]s, and the jaws'
/// angle as (cos 2θ, sin 2θ) (a jaw line has no sense: θ and θ + π are one grasp).
pub fn features(g: &ParallelGrasp, table: &TableFrame) -> Vec<f64> {
    let d = g.centre - table.origin;
    let (c, s) = (g.axis.dot(&table.x), g.axis.dot(&table.y));
    let theta = s.atan2(c);
    vec![
        d.dot(&table.x) / FEATURE_UNIT,
        d.dot(&table.y) / FEATURE_UNIT,
        d.dot(&table.z) / FEATURE_UNIT,
        (2.0 * theta).cos(),
        (2.0 * theta).sin(),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use rand::SeedableRng;

    /// On a 50 mm cube (all its sides) every candidate's jaws close on it within the opening,
    /// at least MIN_HEIGHT up and below its top; opened less than the cube is wide, the jaws
    /// only take its corners; the features name the same grasp for θ and θ + π.
    #[test]
    fn candidates_close_on_the_object_within_the_opening() {
        let mut points = Vec::new();
        for i in 0..=25 {
            for j in 0..=25 {
                let (a, b) = (-0.025 + i as f64 * 0.002, j as f64 * 0.002);
                points.push(Point3::new(a, -0.025 + b, 0.05));
                points.push(Point3::new(a, -0.025 + b, 0.0));
                points.push(Point3::new(a, -0.025, b));
                points.push(Point3::new(a, 0.025, b));
                points.push(Point3::new(-0.025, a, b));
                points.push(Point3::new(0.025, a, b));
            }
        }
        let index = CloudIndex::new(&points);
        let table = TableFrame::under(&Point3::origin(), &Vector3::z(), 0.0);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let gs = sample_candidates(&points, &index, &table, 0.085, 50, &mut rng);
        assert_eq!(gs.len(), 50);
        for g in &gs {
            assert!(g.centre.z >= MIN_HEIGHT - 1e-12 && g.centre.z <= 0.05 - DEPTHS.0 + 1e-12);
            assert!(g.axis.z.abs() < 1e-12 && (g.axis.norm() - 1.0).abs() < 1e-12);
            assert!(g.opposition(&points, &index, 0.0425).is_some());
        }
        // Opened 40 mm, the jaws span only sections across the cube's corners.
        for g in sample_candidates(&points, &index, &table, 0.04, 10, &mut rng) {
            let (a, b) = g.opposition(&points, &index, 0.02).unwrap();
            assert!((points[b] - points[a]).dot(&g.axis) <= 0.035 + 1e-9);
            let (c, s) = (g.axis.x.abs(), g.axis.y.abs());
            assert!(
                c.min(s) > 0.2,
                "a 40 mm jaw across the 50 mm cube's face: {:?}",
                g.axis
            );
        }
        let turned = ParallelGrasp {
            axis: -gs[0].axis,
            ..gs[0]
        };
        let (f, t) = (features(&gs[0], &table), features(&turned, &table));
        assert!(
            f.iter().zip(&t).all(|(a, b)| (a - b).abs() < 1e-9),
            "{f:?} {t:?}"
        );
    }
}
