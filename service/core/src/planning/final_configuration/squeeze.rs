//! Module step 3, the squeeze: the joints that press each touching finger's contacts a few mm
//! into the object along their normals, so that the position servos' error becomes the grip.
//!
//! The grip is balanced first ([`super::super::grip_forces`]): the contact forces that press
//! with every touching finger and cancel about the estimated centre of mass. With servos of
//! equal stiffness k a finger stopped at its touch presses with the joint torques k·Δq, so the
//! squeeze that presses with forces f_i is Δq = Jᵀf/k (the Jacobian-transpose map of each
//! finger's contacts), but for a joint that it would open: that one holds at its touch (a
//! guarded close stops the fingers where they really touch, and a joint pushed back there
//! turns its link away from the object: the Shadow's thumb so let an apple roll out of the
//! hand; Table 5.2, 20 trials per cell, paired: Shadow 134 → 139 of 160, the other hands
//! unchanged). All fingers share one scale, chosen so that the deepest contact is pressed
//! `depth` along its normal. When the contacts cannot balance (all on one side), each
//! finger is pressed on its own as deep as `depth` allows (a small linear program). Either way
//! the squeeze is then scaled back until no contact slides across the surface further than
//! `depth` ([`limit_slide`]), and a contact it drives off the object is marked ([`Squeeze`]).

use super::super::grip_forces::{GripContact, balanced_grip};
use super::super::kinematic_model::KinematicModel;
use super::closing_sweep::{Closed, SweepContact, SweepHand};
use super::object_view::ObjectView;
use crate::error::FieldError;
use nalgebra::{Point3, Vector3};

/// What the squeeze balances the grip about: the object's estimated centre of mass (world),
/// its radius and the friction coefficient.
pub(super) struct GripFrame {
    pub centre_of_mass: Point3<f64>,
    pub radius: f64,
    pub friction: f64,
}

/// The squeeze (module step 3): balanced when the contacts allow (module doc); otherwise per
/// touching finger the flexion steps that press its contacts, carried with their links, up to
/// `depth` along their inward normals and none outward (a linear program on the
/// finite-difference Jacobian, re-linearised); each group of linked fingers takes one path step
/// sized by least squares on its contacts. Taking-part fingers that touch nothing close fully.
/// Joints stay inside their limits. No contact slides across the surface further than
/// `depth` ([`limit_slide`]).
pub(super) fn squeeze_joints(
    model: &KinematicModel,
    sweep: &SweepHand,
    closed: &Closed,
    contacts: &[SweepContact],
    depth: f64,
    frame: &GripFrame,
    object: &ObjectView,
) -> Result<Squeeze, FieldError> {
    let (q, held) = unlimited_squeeze(model, sweep, closed, contacts, depth, frame)?;
    let travels = ContactTravel::new(model, sweep, closed, contacts)?;
    let (q, travel) = limit_slide(model, &travels, closed, contacts, q, depth)?;
    // A contact of a finger the balanced grip keeps in equilibrium presses with its share of
    // the balanced forces, inside its friction cone, wherever the squeeze's motion points; one
    // on a link a held joint moves (or any, pressed finger by finger) is not so kept.
    let unbalanced = |c: &SweepContact| {
        held.as_ref().is_none_or(|h| {
            h.iter()
                .enumerate()
                .any(|(j, &x)| x && model.hand.tree.joint_moves(j, c.body))
        })
    };
    // How far the object reaches from a contact the way the squeeze slides it (asked only of
    // a contact driven outside its cone).
    let room = |c: &SweepContact, moved: &Vector3<f64>| {
        let inward = -c.normal;
        let m = sweep.root_in_world.rotation * moved;
        let across = m - inward * m.dot(&inward);
        if across.norm() < 1e-9 {
            return f64::INFINITY;
        }
        object.reach_along(&c.position, &across.normalize())
    };
    let slides = contacts
        .iter()
        .zip(&travel)
        .map(|(c, &(press, slide, moved))| {
            unbalanced(c)
                && outside_cone(press, slide, frame.friction)
                && slide > room(c, &moved) + SLIDE_TOLERANCE
        })
        .collect();
    if tracing::enabled!(tracing::Level::TRACE) {
        let text: Vec<String> = contacts
            .iter()
            .zip(&travel)
            .map(|(c, (press, slide, _))| {
                format!(
                    "{:?}: press {:.1} mm slide {:.1} mm",
                    c.finger,
                    press * 1e3,
                    slide * 1e3
                )
            })
            .collect();
        tracing::trace!(contacts = ?text, "squeeze");
    }
    Ok(Squeeze { joints: q, slides })
}

/// Sliding of a contact under the squeeze that counts whatever it presses, m.
const SLIDE_TOLERANCE: f64 = 0.002;

/// Whether a contact the squeeze moves `press` along its inward normal and `slide` across the
/// surface (m) is driven outside its friction cone (μ = `friction`): slide > μ·press, beyond
/// [`SLIDE_TOLERANCE`] (one that lifts off presses nothing).
fn outside_cone(press: f64, slide: f64, friction: f64) -> bool {
    slide > friction * press.max(0.0) + SLIDE_TOLERANCE
}

/// The squeeze joints, and per contact whether the squeeze drives it off the object. A finger
/// the balanced grip keeps in equilibrium presses with its share of the balanced forces,
/// inside its friction cone, wherever its motion points; a contact on a link that a held joint
/// moves (or any contact, when the fingers are pressed one by one) is not so kept, and its
/// motion says where it goes: driven outside its friction cone ([`outside_cone`]) further
/// across the surface than the object reaches that way from it (its points and their
/// completion), it wedges nothing and slides along the object and past its end until it
/// reaches its command. (The Allegro's middle finger 6 mm below a soup can's rim, its distal
/// joint held, pressed 31 mm and slid 47 mm: in MuJoCo it went over the rim and the can turned
/// out of the thumb–index pinch.) The robustness does not count such a contact.
pub(super) struct Squeeze {
    pub joints: Vec<f64>,
    pub slides: Vec<bool>,
}

/// A contact's motion: along its inward normal, across the surface (m), and the motion itself
/// (root frame).
type Travel = (f64, f64, Vector3<f64>);

/// A contact at the touch: its body, its point in that body's frame and in the root frame, and
/// its inward normal (root frame).
struct AtTouch {
    body: usize,
    local: Point3<f64>,
    posed: Point3<f64>,
    inward: Vector3<f64>,
}

/// Each contact's motion from the touching joints to other joints (root frame, carried with its
/// link): the contacts on their links, posed once at the touch.
struct ContactTravel<'a> {
    model: &'a KinematicModel,
    at_touch: Vec<AtTouch>,
}

impl<'a> ContactTravel<'a> {
    fn new(
        model: &'a KinematicModel,
        sweep: &SweepHand,
        closed: &Closed,
        contacts: &[SweepContact],
    ) -> Result<Self, FieldError> {
        let to_root = sweep.root_in_world.inverse();
        let fk0 = model.hand.tree.forward(&closed.joints)?;
        let at_touch = contacts
            .iter()
            .map(|c| {
                let local = fk0.body_poses[c.body].inverse() * (to_root * c.position);
                AtTouch {
                    body: c.body,
                    local,
                    posed: fk0.body_poses[c.body] * local,
                    inward: to_root.rotation * -c.normal,
                }
            })
            .collect();
        Ok(Self { model, at_touch })
    }

    /// Per contact, its motion to `q`.
    fn to(&self, q: &[f64]) -> Result<Vec<Travel>, FieldError> {
        let fk = self.model.hand.tree.forward(q)?;
        Ok(self
            .at_touch
            .iter()
            .map(|c| {
                let m = fk.body_poses[c.body] * c.local - c.posed;
                let press = m.dot(&c.inward);
                (press, (m - c.inward * press).norm(), m)
            })
            .collect())
    }
}

/// Scales the touching fingers' squeeze back toward their touch, one factor for the whole
/// hand, until no contact slides across the surface further than `max_slide`.
///
/// The linearised squeeze sizes a finger's travel by how little it presses: a fingertip
/// touching a thin object's rounded edge, its path running along the surface there, was sent
/// 5–12 cm along it, and on the banana the Barrett's and Shadow's fingers closed past the
/// fruit (MuJoCo, at the planned squeeze: no link within reach of it). One factor keeps the
/// balanced grip balanced; holding back only the finger that slides (or capping the slide
/// below the depth) cost the Allegro and the Shadow their grip on the fruit and the cans
/// (Table 5.2, 10 trials: Allegro 65 → 44 of 80), since the squeeze is also the servos' force
/// command.
fn limit_slide(
    model: &KinematicModel,
    travels: &ContactTravel,
    closed: &Closed,
    contacts: &[SweepContact],
    q: Vec<f64>,
    max_slide: f64,
) -> Result<(Vec<f64>, Vec<Travel>), FieldError> {
    let slide = |t: &[Travel]| t.iter().map(|&(_, s, _)| s).fold(0.0, f64::max);
    let travel = travels.to(&q)?;
    if slide(&travel) <= max_slide {
        return Ok((q, travel));
    }
    // The joints of fingers that touch scale; a finger that touches nothing keeps its close.
    let mut scaled = vec![false; q.len()];
    for f in contacts.iter().filter_map(|c| c.finger) {
        for fj in &model.synergy.fingers[f].flexion {
            scaled[fj.joint] = true;
        }
    }
    let at = |alpha: f64| -> Vec<f64> {
        let mut qa = q.clone();
        for (j, x) in qa.iter_mut().enumerate() {
            if scaled[j] {
                *x = closed.joints[j] + alpha * (q[j] - closed.joints[j]);
            }
        }
        model.hand.tree.clamp(&mut qa);
        qa
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    let mut kept = None;
    for _ in 0..10 {
        let mid = 0.5 * (lo + hi);
        let qm = at(mid);
        let t = travels.to(&qm)?;
        if slide(&t) <= max_slide {
            lo = mid;
            kept = Some((qm, t));
        } else {
            hi = mid;
        }
    }
    match kept {
        Some(k) => Ok(k),
        None => {
            let q0 = at(0.0);
            let t = travels.to(&q0)?;
            Ok((q0, t))
        }
    }
}

/// The squeeze of [`squeeze_joints`] before its slide limit, with the joints the balanced grip
/// holds at their touch (None when the fingers are pressed one by one).
fn unlimited_squeeze(
    model: &KinematicModel,
    sweep: &SweepHand,
    closed: &Closed,
    contacts: &[SweepContact],
    depth: f64,
    frame: &GripFrame,
) -> Result<(Vec<f64>, Option<Vec<bool>>), FieldError> {
    use microlp::{ComparisonOp, OptimizationDirection, Problem};
    let hand = &model.hand;
    let syn = &model.synergy;
    if let Some((q, held)) = balanced_squeeze(model, sweep, closed, contacts, depth, frame)? {
        return Ok((q, Some(held)));
    }
    tracing::trace!("squeeze: the contacts cannot balance; each finger pressed on its own");
    let to_root = sweep.root_in_world.inverse();
    let fk0 = hand.tree.forward(&closed.joints)?;
    // Per contact: its point in its link's frame and its inward normal (root frame).
    let carried = |c: &SweepContact| {
        let at = to_root * c.position;
        (
            c.body,
            fk0.body_poses[c.body].inverse() * at,
            at,
            -(to_root.rotation * c.normal),
        )
    };
    let mut q = closed.joints.clone();
    let mut linked: Vec<usize> = Vec::new();
    const H: f64 = 1e-3;
    for (f, _) in &closed.s {
        let fs = &syn.fingers[*f];
        let mine: Vec<_> = contacts
            .iter()
            .filter(|c| c.finger == Some(*f))
            .map(carried)
            .collect();
        if mine.is_empty() {
            for fj in &fs.flexion {
                q[fj.joint] = fj.closed;
            }
            continue;
        }
        if fs.constrained {
            linked.push(*f);
            continue;
        }
        // Each contact's motion along its inward normal (sliding does not press) is linear in
        // the finger's flexion steps (finite differences); a small linear program takes the
        // steps that press most, each contact at most to `depth` and none outward, every joint
        // only closing and inside its limits — re-linearised a few times for the rotations.
        for _ in 0..3 {
            let fk = hand.tree.forward(&q)?;
            let left: Vec<f64> = mine
                .iter()
                .map(|(b, local, at, inward)| depth - (fk.body_poses[*b] * local - at).dot(inward))
                .collect();
            if left.iter().all(|&r| r < 2e-4) {
                break;
            }
            let mut lp = Problem::new(OptimizationDirection::Maximize);
            let mut rows: Vec<Vec<(microlp::Variable, f64)>> = vec![Vec::new(); mine.len()];
            let mut steps = Vec::new();
            for fj in &fs.flexion {
                let dir = fj.closing_sign();
                let (lo, hi) = hand.tree.joints[fj.joint].limits();
                let room = if dir > 0.0 {
                    hi - q[fj.joint]
                } else {
                    q[fj.joint] - lo
                }
                .max(0.0);
                let mut qh = q.clone();
                qh[fj.joint] += dir * H;
                let fk1 = hand.tree.forward_changed(&qh, &fk, fj.joint)?;
                let along: Vec<f64> = mine
                    .iter()
                    .map(|(b, local, _, inward)| {
                        (fk1.body_poses[*b] * local - fk.body_poses[*b] * local).dot(inward) / H
                    })
                    .collect();
                // Objective: the summed press, less a little motion.
                let gain: f64 = along.iter().sum::<f64>() - 1e-4;
                let x = lp.add_var(gain, (0.0, room));
                for (row, a) in rows.iter_mut().zip(&along) {
                    row.push((x, *a));
                }
                steps.push((fj.joint, dir, x));
            }
            for (row, r) in rows.iter().zip(&left) {
                lp.add_constraint(row.as_slice(), ComparisonOp::Le, r.max(0.0));
                lp.add_constraint(row.as_slice(), ComparisonOp::Ge, r.min(0.0));
            }
            let Ok(Ok(sol)) = lp.solve().map(|o| o.into_solution()) else {
                break;
            };
            for (joint, dir, x) in steps {
                q[joint] += dir * sol[x];
            }
        }
    }
    hand.tree.clamp(&mut q);
    // A linkage: one path parameter per group of linked fingers (a gripper's two jaws, or one
    // finger whose distal joints are coupled), sized by least squares on the group's contacts'
    // inward motion.
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for &f in &linked {
        let g: Vec<usize> = syn
            .group_of(f)
            .iter()
            .copied()
            .filter(|g| linked.contains(g))
            .collect();
        if !groups.contains(&g) {
            groups.push(g);
        }
    }
    let s_of = |f: usize| {
        closed
            .s
            .iter()
            .find(|(g, _)| *g == f)
            .map(|(_, v)| v.clone())
    };
    for group in &groups {
        let mine: Vec<_> = contacts
            .iter()
            .filter(|c| c.finger.is_some_and(|f| group.contains(&f)))
            .map(carried)
            .collect();
        let advanced = |q: &[f64], ds: f64| -> Result<Vec<f64>, FieldError> {
            let s: Vec<(usize, Vec<f64>)> = group
                .iter()
                .filter_map(|&f| s_of(f).map(|v| (f, v.iter().map(|x| x + ds).collect())))
                .collect();
            let mut base = q.to_vec();
            for (f, sv) in &s {
                for (fj, &v) in syn.fingers[*f].flexion.iter().zip(sv) {
                    base[fj.joint] = fj.at(v);
                }
            }
            hand.tree.clamp(&mut base);
            let held: Vec<usize> = s
                .iter()
                .flat_map(|(f, _)| syn.fingers[*f].flexion.iter().map(|fj| fj.joint))
                .collect();
            hand.tree.project_constraints_holding(&mut base, &held)?;
            Ok(base)
        };
        let qh = advanced(&q, 0.01)?;
        let fk1 = hand.tree.forward(&qh)?;
        let (mut num, mut den) = (0.0, 0.0);
        // Least squares on the motion along each inward normal (sliding does not press):
        // ds·(v·n) = depth for every contact.
        for (b, local, at, inward) in &mine {
            let along = ((fk1.body_poses[*b] * local) - at).dot(inward) / 0.01;
            num += along * depth;
            den += along * along;
        }
        let ds = if den > 1e-12 {
            (num / den).clamp(0.0, 0.6)
        } else {
            0.2
        };
        q = advanced(&q, ds)?;
    }
    Ok((q, None))
}

/// Per joint, the factor its finger's balanced squeeze is raised by: a finger whose flexion
/// joints are all force-limited ([`Joint::effort`]) presses its firmest contact at least
/// `depth` (by up to [`FLOOR_GAIN`] times its share); others keep their share (1).
///
/// The balanced grip gives a finger opposite several others a share of a few millimetres (the
/// Shadow's thumb across a sugar box: 2 mm), less than the single view's error in the surface
/// it lands on (2–9 mm measured), so in MuJoCo such a finger pressed nothing: 2.6 N of grip on
/// the 5 N box, the index alone pushing it over. (A finger all of whose joints the grip holds
/// at their touch has no share to raise and stays.) A
/// force-limited servo pushes at most its limit however far its target lies past the touch, so
/// the whole depth engages the finger without outpushing the others beyond their limits; a
/// servo without a limit (the Menagerie Allegro's) pushes in proportion to its travel and keeps
/// its balanced share. Measured (all 13 objects, 20 trials, paired): Shadow 220 → 230 of 260,
/// Barrett 255 → 255; applied to the Allegro's unlimited servos too it lost 236 → 214 (flat
/// boxes pushed 1–7 cm in the close).
///
/// [`Joint::effort`]: crate::hand::kinematics::Joint
fn force_limited_floor(
    model: &KinematicModel,
    closed: &Closed,
    contacts: &[SweepContact],
    press: &[f64],
    scale: f64,
    depth: f64,
) -> Vec<f64> {
    let tree = &model.hand.tree;
    let mut gain = vec![1.0; tree.joints.len()];
    for (f, _) in &closed.s {
        let flexion = &model.synergy.fingers[*f].flexion;
        if flexion
            .iter()
            .any(|fj| tree.joints[fj.joint].effort.is_none())
        {
            continue;
        }
        let firmest = contacts
            .iter()
            .zip(press)
            .filter(|(c, _)| c.finger == Some(*f))
            .map(|(_, p)| scale * p)
            .fold(0.0, f64::max);
        if firmest > 1e-9 && firmest < depth {
            let g = (depth / firmest).min(FLOOR_GAIN);
            for fj in flexion {
                gain[fj.joint] = g;
            }
        }
    }
    gain
}

/// The most a force-limited finger's balanced share is raised by ([`force_limited_floor`]).
const FLOOR_GAIN: f64 = 10.0;

/// A contact (its index) and how it moves per radian of one joint (root frame).
type ContactMotion = (usize, Vector3<f64>);

/// A contact presses through its finger when the finger's flexion joints move it along its
/// inward normal at least this much per radian (m/rad, a 1 cm lever); one they do not move
/// (a knuckle's link beside the palm) only pushes back, like the palm.
const MIN_LEVER: f64 = 0.01;

/// A balanced squeeze: its joints, and per joint whether it holds at its touch (the grip
/// would have it open).
type Balanced = (Vec<f64>, Vec<bool>);

/// The balanced squeeze (module doc): None when the contacts cannot balance, or a finger of a
/// linkage touches (its group is pressed by one path step instead).
fn balanced_squeeze(
    model: &KinematicModel,
    sweep: &SweepHand,
    closed: &Closed,
    contacts: &[SweepContact],
    depth: f64,
    frame: &GripFrame,
) -> Result<Option<Balanced>, FieldError> {
    let hand = &model.hand;
    let syn = &model.synergy;
    if contacts
        .iter()
        .any(|c| c.finger.is_some_and(|f| syn.fingers[f].constrained))
    {
        return Ok(None);
    }
    let to_root = sweep.root_in_world.inverse();
    let inward: Vec<Vector3<f64>> = contacts
        .iter()
        .map(|c| to_root.rotation * -c.normal)
        .collect();
    let q0 = &closed.joints;
    let fk0 = hand.tree.forward(q0)?;
    const H: f64 = 1e-4;
    // Per flexion joint of a taking-part finger: how each of its contacts moves per radian
    // (root frame), from finite differences.
    let mut moves: Vec<(usize, f64, Vec<ContactMotion>)> = Vec::new();
    let mut lever = vec![0.0; contacts.len()];
    for (f, _) in &closed.s {
        let mine: Vec<usize> = (0..contacts.len())
            .filter(|&i| contacts[i].finger == Some(*f))
            .collect();
        if mine.is_empty() {
            continue;
        }
        for fj in &syn.fingers[*f].flexion {
            let mut qh = q0.clone();
            qh[fj.joint] += H;
            let fk1 = hand.tree.forward_changed(&qh, &fk0, fj.joint)?;
            let v: Vec<ContactMotion> = mine
                .iter()
                .map(|&i| {
                    let c = &contacts[i];
                    let local = fk0.body_poses[c.body].inverse() * (to_root * c.position);
                    let d = fk1.body_poses[c.body] * local - fk0.body_poses[c.body] * local;
                    (i, d / H)
                })
                .collect();
            for (i, d) in &v {
                lever[*i] += d.dot(&inward[*i]).powi(2);
            }
            moves.push((fj.joint, fj.closing_sign(), v));
        }
    }
    let grip: Vec<GripContact> = contacts
        .iter()
        .enumerate()
        .map(|(i, c)| GripContact {
            position: c.position,
            inward: -c.normal,
            group: c.finger.filter(|_| lever[i].sqrt() >= MIN_LEVER),
        })
        .collect();
    let Some(forces) = balanced_grip(&grip, &frame.centre_of_mass, frame.radius, frame.friction)
    else {
        return Ok(None);
    };
    // τ_j = Σ_i (∂p_i/∂q_j)·f_i over the pressing contacts (forces in the root frame), and how
    // deep each contact goes per unit of the common scale (linearised).
    let mut press = vec![0.0; contacts.len()];
    let mut held = vec![false; q0.len()];
    let mut steps: Vec<(usize, f64)> = Vec::with_capacity(moves.len());
    for (joint, dir, v) in &moves {
        let tau: f64 = v
            .iter()
            .filter(|(i, _)| grip[*i].group.is_some())
            .map(|(i, d)| d.dot(&(to_root.rotation * forces[*i])))
            .sum();
        // No joint opens: where the grip asks a joint to push back, it holds at its touch.
        if tau * dir < 0.0 {
            held[*joint] = true;
        }
        let tau = if tau * dir < 0.0 { 0.0 } else { tau };
        for (i, d) in v {
            press[*i] += tau * d.dot(&inward[*i]);
        }
        steps.push((*joint, tau));
    }
    let deepest = press.iter().copied().fold(0.0, f64::max);
    if deepest < 1e-9 {
        return Ok(None);
    }
    let scale = depth / deepest;
    let mut q = q0.clone();
    let gain = force_limited_floor(model, closed, contacts, &press, scale, depth);
    for (joint, tau) in steps {
        q[joint] += scale * tau * gain[joint];
    }
    // Taking-part fingers that touch nothing close fully, as in the unbalanced squeeze.
    for (f, _) in &closed.s {
        if !contacts.iter().any(|c| c.finger == Some(*f)) {
            for fj in &syn.fingers[*f].flexion {
                q[fj.joint] = fj.closed;
            }
        }
    }
    hand.tree.clamp(&mut q);
    Ok(Some((q, held)))
}

#[cfg(test)]
mod tests {
    use super::outside_cone;

    /// μ = 0.6: the Allegro's middle finger on a can's rim, pressed 30.7 mm and slid 46.5 mm, is
    /// driven outside its cone (46.5 > 18.4 mm); a fingertip pressed 27.9 mm and slid 5.5 mm is
    /// not; at the cone's edge (10 mm, 6 mm) the 2 mm tolerance decides; a contact that lifts
    /// off presses nothing, so any slide beyond the tolerance is outside.
    #[test]
    fn a_contact_slid_further_than_mu_times_its_press_is_outside_its_cone() {
        assert!(outside_cone(0.0307, 0.0465, 0.6));
        assert!(!outside_cone(0.0279, 0.0055, 0.6));
        assert!(!outside_cone(0.010, 0.0079, 0.6));
        assert!(outside_cone(0.010, 0.0081, 0.6));
        assert!(outside_cone(-0.003, 0.0025, 0.6));
        assert!(!outside_cone(-0.003, 0.0015, 0.6));
    }
}
