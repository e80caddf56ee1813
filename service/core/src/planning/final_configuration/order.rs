//! The order in which the final-configuration search judges candidates (module docs of
//! [`super`]): up to four stage-1 oppositions, and the best one moved to the height of the
//! estimated centre of mass (a tall object held high tips and slides out of the hand in the
//! lift), each × the approach preferences (made perpendicular to the opposition) × turns about
//! the opposition line; best prior first.

use super::super::search_context::SearchContext;
use nalgebra::{UnitQuaternion, Vector3};

/// Turns about the opposition line tried for each approach, degrees.
const TURNS_DEG: [f64; 5] = [0.0, 30.0, -30.0, 60.0, -60.0];
/// Approaches closer than this (cosine) count as one.
const SAME_APPROACH_COS: f64 = 0.97;

/// The candidates to judge, in order: (opposition, approach direction).
pub(super) fn candidate_order(
    ctx: &SearchContext,
    oppositions: &[(usize, usize)],
) -> Vec<((usize, usize), Vector3<f64>)> {
    for (a, b) in oppositions.iter().take(4) {
        tracing::debug!(
            oc1 = ?ctx.points[*a].coords.as_slice(),
            oc2 = ?ctx.points[*b].coords.as_slice(),
            width = (ctx.points[*b] - ctx.points[*a]).norm(),
            "stage-1 opposition"
        );
    }
    let mut opps: Vec<((usize, usize), f64)> = oppositions
        .iter()
        .take(4)
        .enumerate()
        .map(|(rank, &o)| (o, rank as f64))
        .collect();
    if let Some(level) = oppositions
        .first()
        .and_then(|&o| at_centre_height(ctx, o))
        .filter(|l| !oppositions.contains(l))
    {
        opps.push((level, 0.5));
    }
    let mut order: Vec<(f64, (usize, usize), Vector3<f64>)> = Vec::new();
    for &((a, b), base_prior) in &opps {
        let Some(line) = (ctx.points[b] - ctx.points[a]).try_normalize(1e-9) else {
            continue;
        };
        let mut seen: Vec<Vector3<f64>> = Vec::new();
        for (pref_rank, pref) in ctx.approach_prefs.iter().enumerate() {
            let Some(base) = (pref - line * pref.dot(&line)).try_normalize(0.2) else {
                continue;
            };
            for (turn_rank, deg) in TURNS_DEG.iter().enumerate() {
                let r = UnitQuaternion::from_axis_angle(
                    &nalgebra::Unit::new_normalize(line),
                    deg.to_radians(),
                );
                let a_dir = r * base;
                if seen.iter().any(|s| s.dot(&a_dir) > SAME_APPROACH_COS) {
                    continue;
                }
                seen.push(a_dir);
                let prior = base_prior + 0.6 * pref_rank as f64 + 0.8 * turn_rank as f64;
                order.push((prior, (a, b), a_dir));
            }
        }
    }
    order.sort_by(|x, y| x.0.total_cmp(&y.0));
    order.into_iter().map(|(_, o, a)| (o, a)).collect()
}

/// The opposition `(a, b)` moved along the support's normal to the height of the estimated
/// centre of mass: each point replaced by the cloud point nearest to it at that height, on the
/// same side. None without a support plane, when the move is under a centimetre, or when no
/// point lies within a centimetre of the moved one.
fn at_centre_height(ctx: &SearchContext, (a, b): (usize, usize)) -> Option<(usize, usize)> {
    let up = ctx.plane.as_ref()?.normal;
    let mid = nalgebra::Point3::from((ctx.points[a].coords + ctx.points[b].coords) / 2.0);
    let shift = (ctx.shape.center - mid).dot(&up);
    if shift.abs() < 0.01 {
        return None;
    }
    let moved = |i: usize| {
        let (k, d) = ctx.index.nearest_one(&(ctx.points[i] + up * shift));
        (d <= 0.01).then_some(k)
    };
    Some((moved(a)?, moved(b)?))
}
