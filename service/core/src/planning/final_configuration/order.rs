//! The order in which the final-configuration search judges candidates (module docs of
//! [`super`]): up to four stage-1 oppositions, and the best one moved to the height of the
//! estimated centre of mass (a tall object held high tips and slides out of the hand in the
//! lift), these two also with their ends swapped — the thumb on the other side, the hand turned
//! half round about the approach (beside a tall object one of the two puts the forearm into the
//! table; swapping the lesser oppositions too cost the Shadow 7 ms at the median and held no
//! more); each × the approach preferences (made perpendicular to the opposition) × turns about
//! the opposition line; best prior first. A palm opposition fixes the approach (the line
//! itself): its candidates are rolls about the line instead.

use super::super::evaluation::SearchContext;
use nalgebra::{UnitQuaternion, Vector3};

/// Turns about the opposition line tried for each approach, degrees.
const TURNS_DEG: [f64; 5] = [0.0, 30.0, -30.0, 60.0, -60.0];
/// Rolls about the opposition line of a palm grasp, degrees from the object's long axis.
const PALM_ROLLS_DEG: [f64; 6] = [0.0, 180.0, 45.0, -45.0, 135.0, -135.0];
/// Approaches closer than this (cosine) count as one.
const SAME_APPROACH_COS: f64 = 0.97;
/// How far down the order the swapped opposition comes after its original (in the units of
/// the oppositions' ranks).
const SWAPPED_PRIOR: f64 = 0.3;
/// Oppositions ranked before this (the best and its centre-height version) are also tried
/// with their ends swapped.
const SWAPPED_BELOW: f64 = 1.0;
/// Half the thickness of the object's section at the centre-of-mass height (along the
/// support's normal and across the opposition's line), m: a few cloud spacings at 1 m.
const SECTION_HALF_WIDTH: f64 = 0.004;
/// Angles between a chord and its ends' normals closer than this are not told apart, degrees:
/// k-NN normals of a depth cloud are a few degrees off (the Shadow's fused orange and soup can
/// chords, own 15° and 7°, turned 3° better, changed plan for nothing), while the 2F-85's fused
/// mustard bottle's (own 27°, turned 15°) held only turned (docs/final-configuration.md).
const NORMAL_NOISE_DEG: f64 = 10.0;
/// Turns about the support's normal of the planes a two-finger gripper's centre-height section
/// is cut along, degrees from the opposition's line (`at_centre_height`), up to across it.
const SECTION_TURNS_DEG: [f64; 12] = [
    0.0, 15.0, -15.0, 30.0, -30.0, 45.0, -45.0, 60.0, -60.0, 75.0, -75.0, 90.0,
];

/// The candidates to judge, in order: (opposition, direction) — the approach direction for a
/// finger opposition, the axis the fingers wrap around for a palm opposition
/// ([`super::placement::target_frame`]).
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
    let palm = ctx.grasp.h1_fingers.is_empty();
    if !palm {
        let swapped: Vec<_> = opps
            .iter()
            .filter(|&&(_, p)| p < SWAPPED_BELOW)
            .map(|&((a, b), p)| ((b, a), p + SWAPPED_PRIOR))
            .collect();
        opps.extend(swapped);
    }
    let mut order: Vec<(f64, (usize, usize), Vector3<f64>)> = Vec::new();
    for &((a, b), base_prior) in &opps {
        let Some(line) = (ctx.points[b] - ctx.points[a]).try_normalize(1e-9) else {
            continue;
        };
        let turn = |deg: f64| {
            UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(line), deg.to_radians())
        };
        if palm {
            // The axis the fingers wrap around: the object's long axis, both ways (which side
            // the thumb lies on), then turned.
            let axis = ctx.shape.axes[0];
            let Some(base) = (axis - line * axis.dot(&line))
                .try_normalize(0.2)
                .or_else(|| line.cross(&Vector3::x()).try_normalize(0.2))
                .or_else(|| line.cross(&Vector3::y()).try_normalize(0.2))
            else {
                continue;
            };
            for (rank, deg) in PALM_ROLLS_DEG.iter().enumerate() {
                order.push((base_prior + 0.4 * rank as f64, (a, b), turn(*deg) * base));
            }
            continue;
        }
        let mut seen: Vec<Vector3<f64>> = Vec::new();
        for (pref_rank, pref) in ctx.approach_prefs.iter().enumerate() {
            let Some(base) = (pref - line * pref.dot(&line)).try_normalize(0.2) else {
                continue;
            };
            for (turn_rank, deg) in TURNS_DEG.iter().enumerate() {
                let a_dir = turn(*deg) * base;
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
/// centre of mass: the object's section there, in an upright plane through the moved midpoint,
/// and its two outermost points along the line (where closing jaws meet it first: on a bottle
/// that narrows toward its top the section at the centre is wider than the shoulder, and the
/// moved points lie inside it). The plane is the opposition's own; for a two-finger gripper
/// also those turned about the normal by [`SECTION_TURNS_DEG`], and of the chords the jaws span
/// the one whose ends' normals lie closest along it (the most antipodal; the least turned on a
/// tie) unless the own one is within [`NORMAL_NOISE_DEG`] of it — a box-like body seen turned
/// from its shoulder (a mustard bottle) is otherwise taken across its corners. None without a
/// support plane, when the move is under a centimetre (unless, for a two-finger gripper, the own
/// chord there leaves the friction cones and a turned one is the better), for a line within 30°
/// of the normal, or when the section has no point on either side of the moved midpoint.
fn at_centre_height(ctx: &SearchContext, (a, b): (usize, usize)) -> Option<(usize, usize)> {
    let up = ctx.plane.as_ref()?.normal;
    let mid = nalgebra::Point3::from((ctx.points[a].coords + ctx.points[b].coords) / 2.0);
    let shift = (ctx.shape.center - mid).dot(&up);
    // A two-finger gripper's opposition already near the centre's height is still turned to
    // the section's most antipodal chord when its own line leaves the friction cones and that
    // chord is clearly better (a flat box's top crossed obliquely: session 33).
    let level = shift.abs() < 0.01;
    let two_jaws = ctx.hand.fingers.len() == 2;
    if level && !two_jaws {
        return None;
    }
    let raw = ctx.points[b] - ctx.points[a];
    let line = (raw - up * raw.dot(&up)).try_normalize(1e-9)?;
    if line.dot(&raw.normalize()) < 60f64.to_radians().cos() {
        return None;
    }
    let centre = mid + up * shift;
    let slab: Vec<usize> = (0..ctx.points.len())
        .filter(|&k| (ctx.points[k] - centre).dot(&up).abs() <= SECTION_HALF_WIDTH)
        .collect();
    let chord = |line: Vector3<f64>| -> Option<(usize, usize)> {
        let across = up.cross(&line);
        let (mut lo, mut hi) = (None::<(usize, f64)>, None::<(usize, f64)>);
        for &k in &slab {
            let d = ctx.points[k] - centre;
            if d.dot(&across).abs() > SECTION_HALF_WIDTH {
                continue;
            }
            let s = d.dot(&line);
            if s < 0.0 && lo.is_none_or(|(_, m)| s < m) {
                lo = Some((k, s));
            }
            if s > 0.0 && hi.is_none_or(|(_, m)| s > m) {
                hi = Some((k, s));
            }
        }
        Some((lo?.0, hi?.0))
    };
    // A two-finger gripper's jaws take exactly the chord; a hand's fingers curl round the
    // section and find their own contacts, and turned chords held them less often
    // (docs/final-configuration.md, session 32).
    if !two_jaws {
        return chord(line);
    }
    // (chord, the larger of its ends' angles to the line), the opposition's own plane first.
    let mut own: Option<((usize, usize), f64)> = None;
    let mut best: Option<((usize, usize), f64)> = None;
    for deg in SECTION_TURNS_DEG {
        let turned =
            UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(up), deg.to_radians())
                * line;
        let Some((lo, hi)) = chord(turned) else {
            continue;
        };
        if (ctx.points[hi] - ctx.points[lo]).dot(&turned) > ctx.hand.geometry.max_aperture {
            continue;
        }
        let cos = (-ctx.normals.get(lo).dot(&turned)).min(ctx.normals.get(hi).dot(&turned));
        let angle = cos.clamp(-1.0, 1.0).acos();
        if deg == 0.0 {
            own = Some(((lo, hi), angle));
        }
        if best.is_none_or(|(_, a)| angle < a - 1e-9) {
            best = Some(((lo, hi), angle));
        }
    }
    // Near the centre's height, only a line that leaves the friction cones is turned: on a
    // round can the turned chords fall short of a diameter, and dropped more often.
    let cone = ctx.cos_friction.clamp(-1.0, 1.0).acos();
    match (own, best) {
        (Some((o, a)), Some((_, b)))
            if b > a - NORMAL_NOISE_DEG.to_radians() || level && a < cone =>
        {
            (!level).then_some(o)
        }
        (_, Some((o, _))) => Some(o),
        // Nothing the jaws span: the opposition's own section (a wider pre-shape may yet take
        // it).
        _ if level => None,
        _ => chord(line),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp_type::GraspType;
    use crate::planning::test_scene::Rod;
    use nalgebra::Point3;

    /// A finger opposition comes first as found, then (further down) with its ends swapped,
    /// each with approaches perpendicular to its line.
    #[test]
    fn finger_oppositions_come_both_ways_round() {
        let rod = Rod::new(0.2, "barrett", GraspType::Tripod);
        let normals = rod.normals();
        let ctx = rod.context(&normals, rod.nearest(Point3::new(0.0, 0.0, 0.04)));
        let (a, b) = (
            rod.nearest(Point3::new(0.0, -0.02, 0.02)),
            rod.nearest(Point3::new(0.0, 0.02, 0.02)),
        );
        let order = candidate_order(&ctx, &[(a, b)]);
        assert_eq!(order[0].0, (a, b));
        let swapped = order.iter().position(|c| c.0 == (b, a)).unwrap();
        assert!(swapped > 0);
        let line = (rod.points[b] - rod.points[a]).normalize();
        assert!(order.iter().all(|(_, d)| d.dot(&line).abs() < 1e-9));
        // Straight down first: the only approach preference.
        assert!(
            (order[0].1 + Vector3::z()).norm() < 1e-9,
            "{:?}",
            order[0].1
        );
    }

    /// A palm opposition's candidates are rolls about its line: the wrap axis along the
    /// object's long axis both ways (thumb on either side) first, every one perpendicular to
    /// the line, and the opposition never swapped (the palm side is the palm).
    #[test]
    fn palm_oppositions_roll_about_their_line() {
        let rod = Rod::new(0.2, "shadow", GraspType::SmallWrap);
        assert!(rod.grasp.h1_fingers.is_empty());
        let normals = rod.normals();
        let ctx = rod.context(&normals, rod.nearest(Point3::new(0.0, 0.0, 0.04)));
        let (a, b) = (
            rod.nearest(Point3::new(0.0, 0.0, 0.04)),
            rod.nearest(Point3::new(0.0, 0.02, 0.02)),
        );
        let order = candidate_order(&ctx, &[(a, b)]);
        assert_eq!(order.len(), PALM_ROLLS_DEG.len());
        assert!(order.iter().all(|c| c.0 == (a, b)));
        let line = (rod.points[b] - rod.points[a]).normalize();
        assert!(order.iter().all(|(_, d)| d.dot(&line).abs() < 1e-9));
        assert!(order[0].1.x.abs() > 0.99, "{:?}", order[0].1);
        assert!((order[0].1 + order[1].1).norm() < 1e-9);
    }

    /// A bottle narrowing toward its top (radius 40 mm at the table, 12 mm at 20 cm): an
    /// opposition across its top, moved to the centre's height, lands on the wall there, not
    /// on the points nearest to its ends moved down (13–14 mm inside the wall).
    #[test]
    fn the_centre_height_opposition_lies_on_the_section_there() {
        let radius = |z: f64| 0.04 - 0.028 * z / 0.2;
        let mut points = Vec::new();
        for i in 0..=40 {
            let z = 0.005 * i as f64;
            for k in 0..48 {
                let a = std::f64::consts::TAU * k as f64 / 48.0;
                points.push(Point3::new(radius(z) * a.cos(), radius(z) * a.sin(), z));
            }
        }
        let bottle = Rod::with_points(points, "parallel_gripper", GraspType::Pinch);
        let normals = bottle.normals_outward();
        let top = 0.195;
        let (a, b) = (
            bottle.nearest(Point3::new(-radius(top), 0.0, top)),
            bottle.nearest(Point3::new(radius(top), 0.0, top)),
        );
        let ctx = bottle.context(&normals, a);
        let zc = bottle.shape.center.z;
        assert!(zc < 0.12, "centre at {zc}");
        let (a2, b2) = at_centre_height(&ctx, (a, b)).expect("a section at the centre");
        let (pa, pb) = (bottle.points[a2], bottle.points[b2]);
        for (p, side) in [(pa, -1.0), (pb, 1.0)] {
            assert!((p.z - zc).abs() <= SECTION_HALF_WIDTH + 1e-9, "{p:?}");
            assert!(p.y.abs() <= SECTION_HALF_WIDTH + 1e-9, "{p:?}");
            assert!(
                (p.x - side * radius(p.z)).abs() < 0.002,
                "{p:?} off the wall"
            );
        }
        // An opposition already at the centre's height is not moved.
        let level = |x: f64| bottle.nearest(Point3::new(x * radius(zc), 0.0, zc));
        assert_eq!(at_centre_height(&ctx, (level(-1.0), level(1.0))), None);
    }

    /// A tall box, 60 × 100 mm across: an opposition across a corner of its top (from the
    /// −x face to the +y face, its line 60° from x), moved to the centre's height, lands on
    /// two opposite faces there — the chord whose ends' normals lie along it — not across the
    /// corner as the opposition's own plane cuts it (normals 60° and 30° off the line).
    #[test]
    fn the_centre_height_opposition_is_the_most_antipodal_chord() {
        let (hx, hy) = (0.03, 0.05);
        let mut points = Vec::new();
        for i in 0..=40 {
            let z = 0.005 * i as f64;
            for k in 0..=12 {
                let x = -hx + 2.0 * hx * k as f64 / 12.0;
                points.extend([Point3::new(x, -hy, z), Point3::new(x, hy, z)]);
            }
            for k in 1..20 {
                let y = -hy + 2.0 * hy * k as f64 / 20.0;
                points.extend([Point3::new(-hx, y, z), Point3::new(hx, y, z)]);
            }
        }
        let bx = Rod::with_points(points.clone(), "parallel_gripper", GraspType::Pinch);
        let normals = bx.normals_outward();
        let (a, b) = (
            bx.nearest(Point3::new(-hx, -0.02, 0.19)),
            bx.nearest(Point3::new(0.01, hy, 0.19)),
        );
        let ctx = bx.context(&normals, a);
        let zc = bx.shape.center.z;
        let (a2, b2) = at_centre_height(&ctx, (a, b)).expect("a section at the centre");
        let (pa, pb) = (bx.points[a2], bx.points[b2]);
        assert!((pa.z - zc).abs() <= SECTION_HALF_WIDTH + 1e-9, "{pa:?}");
        let across_x = (pa.x + hx).abs() < 1e-9 && (pb.x - hx).abs() < 1e-9;
        let across_y = (pa.y + hy).abs() < 1e-9 && (pb.y - hy).abs() < 1e-9;
        assert!(
            across_x || across_y,
            "{pa:?} – {pb:?} not on opposite faces"
        );
        let width = (pb - pa).norm();
        assert!(width <= ctx.hand.geometry.max_aperture, "{width}");
        // The same corner crossed at the centre's height: no move, but the chord still turns
        // to opposite faces.
        let (a1, b1) = (
            bx.nearest(Point3::new(-hx, -0.02, zc)),
            bx.nearest(Point3::new(0.01, hy, zc)),
        );
        let (pa, pb) = at_centre_height(&ctx, (a1, b1))
            .map(|(p, q)| (bx.points[p], bx.points[q]))
            .expect("a turned chord");
        assert!(
            ((pa.x + hx).abs() < 1e-9 && (pb.x - hx).abs() < 1e-9)
                || ((pa.y + hy).abs() < 1e-9 && (pb.y - hy).abs() < 1e-9),
            "{pa:?} – {pb:?} not on opposite faces"
        );
        // A three-finger hand's fingers find their own contacts: its section stays in the
        // opposition's own plane, across the corner.
        let hand = Rod::with_points(points, "barrett", GraspType::Tripod);
        let normals = hand.normals_outward();
        let ctx = hand.context(&normals, a);
        let (a3, b3) = at_centre_height(&ctx, (a, b)).expect("a section at the centre");
        let (pa, pb) = (hand.points[a3], hand.points[b3]);
        assert!(
            (pa.x + hx).abs() < 1e-9 && (pb.y - hy).abs() < 1e-9,
            "{pa:?} – {pb:?}"
        );
    }
}
