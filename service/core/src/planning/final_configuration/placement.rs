//! Where the hand goes for one candidate: the pre-shape's grasp frame aligned with the
//! opposition, then moved in along the approach as a robot moves it — from outside, until the
//! pre-shaped hand would touch the object or the table (the first contact, less a clearance),
//! and no deeper than the grasp family allows.
//!
//! - Finger oppositions (thumb against fingers): the frame's x (h1 → h2) on oc1 → oc2, its z on
//!   the approach (made perpendicular to x), its origin on the opposition's midpoint.
//! - A palm opposition: the frame's z (palm → fingers) on oc1 → oc2 and its y on the wrap axis
//!   the candidate gives (the fingers wrap around it: the object's long axis, rolled).
//! - Fingertip types (pinch, tripod, precision) stop at the aligned pose, the fingertips around
//!   the opposition; the wrap types (power, large and small wrap) go on until the palm or the
//!   open fingers meet the object.

use super::super::kinematic_model::KinematicModel;
use super::ObjectView;
use crate::error::FieldError;
use crate::hand::kinematics::PreShape;
use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// Clearance kept between the pre-shaped hand and the object or the table where the move in
/// stops, m.
pub const CLEARANCE: f64 = 0.003;
/// Step of the move in, m (refined by halving).
const STEP: f64 = 0.008;
const HALVINGS: usize = 4;
/// How far beyond the aligned pose a fingertip grasp may go in, m.
const FINGERTIP_DEPTH: f64 = 0.01;

/// The world frame a pre-shape's grasp frame is put on: x closing, z approach, the origin on
/// the opposition's midpoint (`direction`: the approach of a finger opposition, the wrap axis
/// of a palm opposition; made perpendicular to the opposition). With three or more fingers it
/// moves across the fingers (y) onto the estimated centre of mass, and along the closing axis
/// too when the object fits in the pre-shape's opening there (`extent_x`): balanced fingers, no
/// moment from the weight about the grasp. An object wider than the hand opens is grasped where the opposition is (a rim, an
/// edge); so is a two-finger pinch, whose opposition is the grasp (as for the P-Grip).
pub fn target_frame(
    pre: &PreShape,
    oc1: &Point3<f64>,
    oc2: &Point3<f64>,
    direction: &Vector3<f64>,
    centre_of_mass: &Point3<f64>,
    extent_x: impl Fn(&Vector3<f64>) -> f64,
) -> Option<Isometry3<f64>> {
    let line = (oc2 - oc1).try_normalize(1e-9)?;
    let mid = Point3::from((oc1.coords + oc2.coords) / 2.0);
    let rot = if pre.h1.is_empty() {
        // Palm opposition: z along the line, y along the wrap axis.
        let z = line;
        let y = (direction - z * direction.dot(&z))
            .try_normalize(0.2)
            .or_else(|| {
                let o = if z.x.abs() < 0.9 {
                    Vector3::x()
                } else {
                    Vector3::y()
                };
                (o - z * o.dot(&z)).try_normalize(1e-9)
            })?;
        Rotation3::from_basis_unchecked(&[y.cross(&z), y, z])
    } else {
        let x = line;
        let z = (direction - x * direction.dot(&x)).try_normalize(1e-6)?;
        Rotation3::from_basis_unchecked(&[x, z.cross(&x), z])
    };
    let (x, y) = (rot * Vector3::x(), rot * Vector3::y());
    let off = centre_of_mass - mid;
    let mut origin = mid;
    if pre.h1.len() + pre.h2.len() >= 3 {
        origin += y * off.dot(&y);
        if extent_x(&x) <= pre.opening[0] {
            origin += x * off.dot(&x);
        }
    }
    Some(Isometry3::from_parts(
        Translation3::from(origin.coords),
        UnitQuaternion::from_rotation_matrix(&rot),
    ))
}

/// The hand pose (hand frame in the world) that puts `pre`'s grasp frame on `target`.
pub fn hand_pose_for(pre: &PreShape, target: &Isometry3<f64>) -> Isometry3<f64> {
    target * pre.frame.inverse()
}

/// Whether the hand posed by `posed`, shifted by `offset`, keeps `clearance` from the object
/// and the table.
pub fn clear_at(
    posed: &crate::hand::kinematics::PosedCollision,
    offset: &Vector3<f64>,
    object: &ObjectView,
    clearance: f64,
) -> bool {
    for k in 0..posed.len() {
        let (c, r) = posed.sphere(k);
        let c = c + offset;
        if let Some(pl) = object.plane
            && pl.distance(&c) < r
            && posed.piece_plane_clearance(k, pl) + offset.dot(&pl.normal) < 0.0
        {
            return false;
        }
        if object.near(&c, r + clearance)
            && posed.any_within(k, &object.points, &object.index, clearance, offset)
        {
            return false;
        }
    }
    true
}

/// Moves the pre-shaped hand (joints `q` at `pose`) in along `approach` from `back` metres
/// outside to at most `depth` metres in, stopping [`CLEARANCE`] short of the first contact.
/// Returns the offset along the approach (negative: short of `pose`), or None when the hand
/// collides already at the start.
pub fn move_in(
    model: &KinematicModel,
    q: &[f64],
    pose: &Isometry3<f64>,
    approach: &Vector3<f64>,
    back: f64,
    depth: f64,
    object: &ObjectView,
) -> Result<Option<f64>, FieldError> {
    let (hand, collision) = (&model.hand, &model.collision);
    let fk = hand.tree.forward(q)?;
    let root = pose * (fk.body_poses[hand.palm] * hand.hand_frame()).inverse();
    let posed = collision.posed_fk(&fk, &root);
    let clear = |t: f64| clear_at(&posed, &(approach * t), object, CLEARANCE);
    // At trace level: which bodies meet the object or the table at offset t, and why it matters
    // (the hand cannot start, or this is where the move in stops).
    let report = |t: f64, why: &str| {
        if !tracing::enabled!(tracing::Level::TRACE) {
            return;
        }
        let off = approach * t;
        for k in 0..posed.len() {
            let (c, r) = posed.sphere(k);
            let table = object
                .plane
                .map(|pl| posed.piece_plane_clearance(k, pl) + off.dot(&pl.normal));
            let obj = posed.any_within(k, &object.points, &object.index, CLEARANCE, &off);
            if obj || table.is_some_and(|x| x < 0.0) {
                tracing::trace!(why, t, body = %hand.tree.bodies[posed.body_of(k)].name, obj, ?table, ?c, r, "hand meets");
            }
        }
    };
    let mut t = -back;
    if !clear(t) {
        report(t, "collides at the pre-grasp");
        return Ok(None);
    }
    while t < depth {
        let next = (t + STEP).min(depth);
        if !clear(next) {
            let (mut lo, mut hi) = (t, next);
            for _ in 0..HALVINGS {
                let mid = 0.5 * (lo + hi);
                if clear(mid) { lo = mid } else { hi = mid }
            }
            report(hi, "the move in stops");
            return Ok(Some(lo));
        }
        t = next;
    }
    Ok(Some(t))
}

/// The rise along the table's normal that keeps the pre-shaped hand (joints `q` at `pose`,
/// and `back` metres out along `approach`) [`CLEARANCE`] above the table; 0 when it already is
/// or there is no table.
pub fn rise_above_table(
    model: &KinematicModel,
    q: &[f64],
    pose: &Isometry3<f64>,
    approach: &Vector3<f64>,
    back: f64,
    object: &ObjectView,
) -> Result<f64, FieldError> {
    let Some(pl) = object.plane else {
        return Ok(0.0);
    };
    let (hand, collision) = (&model.hand, &model.collision);
    let fk = hand.tree.forward(q)?;
    let root = pose * (fk.body_poses[hand.palm] * hand.hand_frame()).inverse();
    let posed = collision.posed_fk(&fk, &root);
    let at = posed.plane_clearance(pl);
    let out = at - back * approach.dot(&pl.normal);
    if tracing::enabled!(tracing::Level::TRACE) {
        for k in 0..posed.len() {
            let c = posed.piece_plane_clearance(k, pl);
            if c < CLEARANCE {
                tracing::trace!(body = %hand.tree.bodies[posed.body_of(k)].name, c, "below the table");
            }
        }
    }
    Ok((CLEARANCE - at.min(out)).max(0.0))
}

/// How deep a grasp family goes past the aligned pose: fingertip types a centimetre, wrap types
/// until the palm's plane reaches the opposition (the frame origin's height above the palm).
pub fn family_depth(pre: &PreShape, wrap: bool) -> f64 {
    if wrap {
        pre.frame.translation.vector.z.max(FINGERTIP_DEPTH)
    } else {
        FINGERTIP_DEPTH
    }
}
