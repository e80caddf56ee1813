//! Module step 4's opening: the taking-part fingers backed off their touch along their paths,
//! so that all arrive together when the hand closes from the pre-grasp.

use super::super::kinematic_model::KinematicModel;
use super::closing_sweep::{Closed, SweepContact, SweepHand};
use crate::error::FieldError;

/// Per taking-part finger, its path parameters advanced from the touch so that its contacts move
/// `travel` along their inward normals (negative: back out); `untouched` for a finger that
/// touches nothing. Linear in s from the touch (the speed measured over a small step).
pub(super) fn advance_contacts(
    model: &KinematicModel,
    sweep: &SweepHand,
    closed: &Closed,
    contacts: &[SweepContact],
    travel: f64,
    untouched: f64,
) -> Result<Vec<(usize, Vec<f64>)>, FieldError> {
    let hand = &model.hand;
    let syn = &model.synergy;
    let fk0 = hand.tree.forward(&closed.joints)?;
    let to_root = sweep.root_in_world.inverse();
    let mut out: Vec<(usize, Vec<f64>)> = Vec::new();
    const DS: f64 = 0.02;
    for (f, sv) in &closed.s {
        let mine: Vec<&SweepContact> = contacts.iter().filter(|c| c.finger == Some(*f)).collect();
        if mine.is_empty() {
            out.push((*f, vec![untouched; sv.len()]));
            continue;
        }
        let mut q = closed.joints.clone();
        for (fj, &v) in syn.fingers[*f].flexion.iter().zip(sv) {
            q[fj.joint] = fj.at(v + DS);
        }
        let fk1 = hand.tree.forward(&q)?;
        let mut speed: f64 = 0.0;
        for c in mine {
            let at = to_root * c.position;
            let local = fk0.body_poses[c.body].inverse() * at;
            let moved = fk1.body_poses[c.body] * local;
            let inward = -(to_root.rotation * c.normal);
            speed = speed.max((moved - at).dot(&inward) / DS);
        }
        let ds = if speed > 1e-4 {
            (travel / speed).clamp(-0.6, 0.6)
        } else {
            0.2 * travel.signum()
        };
        out.push((*f, sv.iter().map(|x| (x + ds).clamp(0.0, 1.0)).collect()));
    }
    Ok(out)
}

/// `closed.joints` with the taking-part fingers at path parameters `s` (projected onto the
/// model's constraints when linked).
pub(super) fn joints_at(
    model: &KinematicModel,
    closed: &Closed,
    s: &[(usize, Vec<f64>)],
) -> Result<Vec<f64>, FieldError> {
    let hand = &model.hand;
    let syn = &model.synergy;
    let mut q = closed.joints.clone();
    for (f, sv) in s {
        for (fj, &v) in syn.fingers[*f].flexion.iter().zip(sv) {
            q[fj.joint] = fj.at(v);
        }
    }
    hand.tree.clamp(&mut q);
    if s.iter().any(|(f, _)| syn.fingers[*f].constrained) {
        let held: Vec<usize> = s
            .iter()
            .flat_map(|(f, _)| syn.fingers[*f].flexion.iter().map(|fj| fj.joint))
            .collect();
        hand.tree.project_constraints_holding(&mut q, &held)?;
    }
    Ok(q)
}
