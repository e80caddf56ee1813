//! Where the closed hand touches the object beyond its fingers, and whether two contacts can
//! hold at all (module step 4 of [`super`]).

use super::ObjectView;
use super::closing_sweep::{SweepContact, SweepHand, patch};
use super::object_view::NearPoints;
use crate::error::FieldError;
use crate::planning::kinematic_model::KinematicModel;

/// For exactly two contacts, which of them (first, second) the line between them leaves the
/// friction cone of: two contacts hold only along a line inside both cones (Nguyen's
/// antipodal condition; stage 1 asks it of the opposition, this of where the fingers really
/// touch — a pinch across a chord of an object wider than the hand's opening fails it).
pub(super) fn outside_friction_cone(
    cos_friction: f64,
    contacts: &[SweepContact],
) -> Option<&'static str> {
    let [c1, c2] = contacts else {
        return None;
    };
    let d = (c2.position - c1.position).try_normalize(1e-9)?;
    if -c1.normal.dot(&d) < cos_friction {
        Some("first")
    } else if c2.normal.dot(&d) < cos_friction {
        Some("second")
    } else {
        None
    }
}

/// For contacts on exactly two fingers and nothing else, of a hand with a third finger, that no
/// linkage joins: those two fingers. Each presses with what its own servo gives, rarely equal
/// and opposite, and the squeeze pushes the object toward the weaker (the Shadow's thumb, at
/// 2–3 N·m, against its index finger at 1 N·m: none of 19 such plans held in MuJoCo); a
/// gripper's jaws on one motor press alike, and a third finger or the palm takes up the
/// difference.
pub(super) fn unlinked_pair(
    model: &KinematicModel,
    contacts: &[SweepContact],
) -> Option<(usize, usize)> {
    if contacts.iter().any(|c| c.finger.is_none()) {
        return None;
    }
    let fingers: Vec<usize> = contacts.iter().filter_map(|c| c.finger).collect();
    unlinked_fingers(model, &fingers)
}

/// Whether `fingers` (with repeats) are exactly two fingers that no linkage joins, of a hand
/// with a third ([`unlinked_pair`]).
pub(super) fn unlinked_fingers(
    model: &KinematicModel,
    fingers: &[usize],
) -> Option<(usize, usize)> {
    if model.hand.fingers.len() < 3 {
        return None;
    }
    let mut fingers = fingers.to_vec();
    fingers.sort_unstable();
    fingers.dedup();
    let [a, b] = fingers[..] else {
        return None;
    };
    (!model.synergy.group_of(a).contains(&b)).then_some((a, b))
}

/// Contacts of the bodies that belong to no finger (the palm, the hand's base) at `q`.
pub(super) fn palm_contacts(
    model: &KinematicModel,
    sweep: &SweepHand,
    q: &[f64],
    object: &ObjectView,
) -> Result<Vec<SweepContact>, FieldError> {
    let hand = &model.hand;
    let fk = hand.tree.forward(q)?;
    let posed = model.collision.posed_fk(&fk, &sweep.root_in_world);
    let in_finger = |b: usize| hand.fingers.iter().any(|f| f.bodies.contains(&b));
    let mut bodies: Vec<usize> = model
        .collision
        .pieces
        .iter()
        .map(|p| p.body)
        .filter(|&b| !in_finger(b))
        .collect();
    bodies.dedup();
    let mut out = Vec::new();
    for b in bodies {
        let pieces: Vec<usize> = (0..model.collision.pieces.len())
            .filter(|&k| model.collision.pieces[k].body == b)
            .collect();
        if let Some(c) = patch(&posed, &pieces, object, b, None, &mut NearPoints::default()) {
            out.push(c);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Point3, Vector3};

    /// A contact on a 5 cm cylinder about z at `deg`, its normal outward.
    fn on_can(deg: f64) -> SweepContact {
        let (s, c) = deg.to_radians().sin_cos();
        SweepContact {
            finger: Some(0),
            body: 0,
            point: 0,
            position: Point3::new(0.05 * c, 0.05 * s, 0.0),
            normal: Vector3::new(c, s, 0.0),
            gap: 0.0,
            coherence: 1.0,
        }
    }

    /// μ = 0.6: the cone's half-angle is atan 0.6 = 31°. Across the diameter the line lies on
    /// both normals; across a chord of 107° (a 2F-85's 79 mm on a 102 mm can) it is 36.5° off
    /// each; at 130° apart, 25° off, inside. Three contacts are left to the robustness.
    #[test]
    fn two_contacts_hold_only_along_a_line_inside_both_cones() {
        let cos = (0.6f64).atan().cos();
        assert_eq!(
            outside_friction_cone(cos, &[on_can(0.0), on_can(180.0)]),
            None
        );
        assert_eq!(
            outside_friction_cone(cos, &[on_can(0.0), on_can(107.0)]),
            Some("first")
        );
        assert_eq!(
            outside_friction_cone(cos, &[on_can(0.0), on_can(130.0)]),
            None
        );
        assert_eq!(
            outside_friction_cone(cos, &[on_can(0.0), on_can(107.0), on_can(220.0)]),
            None
        );
    }
}
