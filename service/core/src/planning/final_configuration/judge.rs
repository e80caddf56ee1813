//! One candidate placed, closed, squeezed and judged (module steps 1–4 of [`super`]): the
//! pre-shape's openings tried tightest first, then the hand turned about the approach or a
//! wider pre-shape while none is feasible.

use super::closing_sweep::{SweepHand, close_fingers};
use super::contacts::{outside_friction_cone, palm_contacts, unlinked_pair};
use super::grip::{Pending, grip};
use super::*;
use crate::error::FieldError;
use crate::hand::kinematics::PreShape;
use crate::planning::collision::PLANE_TOLERANCE;
use crate::planning::evaluation::SearchContext;
use crate::planning::kinematic_model::KinematicModel;
use crate::planning::quality::{self, ContactPoint};
use crate::planning::robustness::Robustness;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

/// Places, closes, squeezes and judges one candidate; None when the hand cannot even start
/// (it collides at the pre-grasp for every free-finger posture) or the frames degenerate.
pub(super) fn judge(
    ctx: &SearchContext,
    model: &KinematicModel,
    grasp: &Grasp,
    object: &ObjectView,
    opposition: (usize, usize),
    approach: &Vector3<f64>,
    beat: Beat,
) -> Result<Option<FinalConfiguration>, FieldError> {
    // Wrap grasps come in open; fingertip grasps open PRESHAPE_MARGINS wider than the
    // opposition, tightest first (beside a low object the fingertips must come down steeply
    // enough to meet its side), until one closes on the object feasibly.
    let width = (ctx.points[opposition.1] - ctx.points[opposition.0]).norm();
    let openings = |pre: &PreShape| -> Vec<f64> {
        let mut o: Vec<f64> = if grasp.wrap {
            vec![0.0]
        } else {
            PRESHAPE_MARGINS
                .iter()
                .map(|m| pre.s_for_opening(width + m).min(0.8))
                .chain(std::iter::once(0.0))
                .collect()
        };
        o.dedup_by(|a, b| (*a - *b).abs() < 0.03);
        o
    };
    // The best pre-shape first. A fingertip grasp of an object wider than it ever opens, whose
    // every try with it touched one side only (the fingertips land on the top), tries once
    // more with the first wider pre-shape that opens past the tightest margin (else the
    // widest).
    let wider = if grasp.wrap || width <= grasp.pres[0].widest() {
        None
    } else {
        grasp.pres[1..]
            .iter()
            .find(|p| p.widest() >= width + PRESHAPE_MARGINS[0])
            .or(grasp.pres[1..].last())
    };
    let mut best: Option<(FinalConfiguration, f64, &PreShape)> = None;
    // The tightest opening first; then, while none is feasible, the best opening with the hand
    // turned about the approach (YAWS_DEG): the fingers' row then meets a curved or skewed
    // object elsewhere instead of landing on its top.
    let first = &grasp.pres[0];
    let mut tries: Vec<(&PreShape, f64, f64)> =
        openings(first).iter().map(|&s0| (first, s0, 0.0)).collect();
    let rank = |c: &FinalConfiguration| {
        let (feasible, two_sided, score) = c.rank();
        (feasible, two_sided, c.contacts.len().min(3), score)
    };
    let mut k = 0;
    let (mut yawed, mut widened) = (false, false);
    while k < tries.len() {
        let (pre, s0, yaw) = tries[k];
        k += 1;
        if let Some(c) = judge_with(
            ctx,
            model,
            grasp,
            object,
            opposition,
            approach,
            (pre, s0, yaw),
        )? {
            let c = c.rated(ctx, beat);
            if best.as_ref().is_none_or(|(b, _, _)| {
                rank(&c).partial_cmp(&rank(b)) == Some(std::cmp::Ordering::Greater)
            }) {
                let done = c.feasible;
                best = Some((c, s0, pre));
                if done {
                    break;
                }
            }
        }
        // Only while the search still lacks `want` feasible plans: the turns cost as much again
        // as the openings, and a search that has its plans gains little robustness from them.
        if k == tries.len() && !yawed && beat.feasible == f64::NEG_INFINITY {
            yawed = true;
            let (pre, s0) = best
                .as_ref()
                .map_or((first, openings(first)[0]), |(_, s0, p)| (*p, *s0));
            tries.extend(YAWS_DEG.iter().map(|d| (pre, s0, d.to_radians())));
        }
        if k == tries.len()
            && !widened
            && best.as_ref().is_none_or(|(b, _, _)| !b.two_sided)
            && let Some(w) = wider
        {
            widened = true;
            tries.extend(openings(w).iter().map(|&s0| (w, s0, 0.0)));
        }
    }
    Ok(best.map(|(c, _, _)| c))
}

/// [`judge`] with the taking-part fingers in pre-shape `pre` at path parameter `s0` and the
/// opposition turned by `yaw` (radians) about the approach through its midpoint.
fn judge_with(
    ctx: &SearchContext,
    model: &KinematicModel,
    grasp: &Grasp,
    object: &ObjectView,
    (oc1, oc2): (usize, usize),
    approach: &Vector3<f64>,
    (pre, s0, yaw): (&PreShape, f64, f64),
) -> Result<Option<FinalConfiguration>, FieldError> {
    let hand = &model.hand;
    let syn = &model.synergy;
    let (mut p1, mut p2) = (ctx.points[oc1], ctx.points[oc2]);
    if yaw != 0.0 {
        let mid = Point3::from((p1.coords + p2.coords) / 2.0);
        let axis = nalgebra::Unit::new_normalize(*approach);
        let r = UnitQuaternion::from_axis_angle(&axis, yaw);
        p1 = mid + r * (p1 - mid);
        p2 = mid + r * (p2 - mid);
    }
    let Some(target) = placement::target_frame(pre, &p1, &p2, approach, &ctx.shape.center, |x| {
        object.extent_along(x)
    }) else {
        return Ok(None);
    };
    let mut aligned = placement::hand_pose_for(pre, &target);
    let a = target.rotation * Vector3::z();
    let depth = placement::family_depth(pre, grasp.wrap);
    // The pre-shape with the free fingers open or curled: the one that goes in deepest.
    let mut best: Option<(f64, Vec<f64>, Isometry3<f64>)> = None;
    for curl in [0.0, 1.0] {
        if curl > 0.0 && grasp.free.is_empty() {
            break;
        }
        let mut q = pre.base.clone();
        let mut fs: Vec<(usize, f64)> = grasp.taking_part.iter().map(|&f| (f, s0)).collect();
        fs.extend(grasp.free.iter().map(|&f| (f, curl)));
        syn.close(hand, &mut q, &fs)?;
        // From the side, a grasp low on the object puts the palm or the arm into the table:
        // raise it, as long as the grasp centre stays below the object's top less a quarter
        // of its height. (From above the table lies ahead: the move in stops at it.)
        let from_above = object.plane.is_some_and(|p| a.dot(&p.normal) < -0.5);
        let rise = if from_above {
            0.0
        } else {
            placement::rise_above_table(
                model,
                &q,
                &aligned,
                &a,
                ctx.options.pregrasp_distance,
                object,
            )?
        };
        let mut pose = aligned;
        if rise > 0.0 {
            let Some(up) = object.plane.map(|p| p.normal) else {
                continue;
            };
            let centre = target.translation.vector + up * rise;
            if !object.below_top(&Point3::from(centre), &up, 0.25) {
                continue;
            }
            pose = Isometry3::from_parts(Translation3::from(up * rise), UnitQuaternion::identity())
                * aligned;
        }
        if let Some(t) = placement::move_in(
            model,
            &q,
            &pose,
            &a,
            ctx.options.pregrasp_distance,
            depth,
            object,
        )? && best.as_ref().is_none_or(|(bt, _, _)| t > *bt + 1e-4)
        {
            best = Some((t, q, pose));
        }
    }
    let Some((t, q_pre, placed)) = best else {
        tracing::debug!(
            ?approach,
            "candidate: the pre-shaped hand collides at the pre-grasp, or would have to rise \
             above the object's top to clear the table"
        );
        return Ok(None);
    };
    aligned = placed;
    let mut hand_pose =
        Isometry3::from_parts(Translation3::from(a * t), UnitQuaternion::identity()) * aligned;
    let fk = hand.tree.forward(&q_pre)?;
    let to_root = (fk.body_poses[hand.palm] * hand.hand_frame()).inverse();
    // Fingertips that close along the table (beside a low object) end up below it: raise the
    // hand by what they reach into it, while it stays clear, and close again.
    let up = object.plane.map(|p| p.normal);
    let mut raised = 0;
    let (root, sweep, closed) = loop {
        let root = hand_pose * to_root;
        let sweep = SweepHand {
            hand,
            synergy: syn,
            collision: &model.collision,
            projections: &model.projections,
            root_in_world: root,
        };
        let closed = close_fingers(&sweep, &q_pre, &grasp.taking_part, s0, object)?;
        let below = match object.plane {
            Some(pl) => {
                let fk = hand.tree.forward(&closed.joints)?;
                -model.collision.posed_fk(&fk, &root).plane_clearance(pl)
            }
            None => 0.0,
        };
        let Some(up) = up.filter(|_| below > PLANE_TOLERANCE && raised < MAX_RAISES) else {
            break (root, sweep, closed);
        };
        let next = Isometry3::from_parts(
            Translation3::from(up * (below + placement::CLEARANCE)),
            UnitQuaternion::identity(),
        ) * hand_pose;
        let fk = hand.tree.forward(&q_pre)?;
        let posed = model.collision.posed_fk(&fk, &(next * to_root));
        if !placement::clear_at(&posed, &Vector3::zeros(), object, placement::CLEARANCE) {
            break (root, sweep, closed);
        }
        hand_pose = next;
        raised += 1;
    };
    let mut contacts = closed.contacts.clone();
    contacts.extend(palm_contacts(model, &sweep, &closed.joints, object)?);
    let cps: Vec<ContactPoint> = contacts
        .iter()
        .map(|c| ContactPoint {
            position: c.position,
            normal: c.normal,
        })
        .collect();
    let gii = if cps.len() >= 2 {
        quality::gii(&cps, ctx.options.torsion_gamma)
    } else {
        0.0
    };
    let h1_side = contacts.iter().any(|c| match c.finger {
        Some(f) => pre.h1.contains(&f),
        None => true,
    });
    let h2_side = contacts
        .iter()
        .any(|c| c.finger.is_some_and(|f| pre.h2.contains(&f)));
    let early = if !(h1_side && h2_side) {
        Some(format!(
            "closing the fingers at the planned pose touches {} side of the object",
            if h1_side || h2_side {
                "only one"
            } else {
                "neither"
            }
        ))
    } else if let Some(end) = outside_friction_cone(ctx.cos_friction, &contacts) {
        Some(format!(
            "the line between the two contacts leaves the {end} contact's friction cone (μ = {})",
            ctx.options.friction
        ))
    } else if let Some((f1, f2)) = unlinked_pair(model, &contacts) {
        Some(format!(
            "only the {} and the {} touch, each driven on its own: their squeeze does not \
             balance without a third contact",
            hand.fingers[f1].name, hand.fingers[f2].name
        ))
    } else {
        None
    };
    // The squeeze and the pre-grasp opening: now for a candidate the contacts leave in the
    // running, when it is output for one they already rule out (`completed`).
    let (squeeze, sliding, q_pre, clearance, pending) = if early.is_some() {
        let pending = Pending {
            closed: closed.clone(),
            s0,
        };
        (Vec::new(), Vec::new(), q_pre, None, Some(pending))
    } else {
        let (squeeze, q_pre, clearance) = grip(
            ctx, model, object, &sweep, &closed, &contacts, &hand_pose, &a, q_pre, s0,
        )?;
        (squeeze.joints, squeeze.slides, q_pre, clearance, None)
    };
    let into_table = clearance
        .map(|c| c.grasp.min(c.squeeze))
        .filter(|&c| c < -PLANE_TOLERANCE);
    let squeeze_only = clearance.is_some_and(|c| c.grasp >= -PLANE_TOLERANCE);
    let contacts_fail = early.is_some();
    let reason = if early.is_some() {
        early
    } else if let Some(c) = into_table {
        Some(format!(
            "the {} hand reaches {:.1} mm into the support plane",
            if squeeze_only { "squeezing" } else { "closed" },
            -c * 1e3
        ))
    } else if closed.push > MAX_PUSH {
        Some(format!(
            "the linked fingers would push the object {:.0} mm before both touch",
            closed.push * 1e3
        ))
    } else if gii < ctx.options.epsilon {
        // Last, so that S < ε alone can be waived for a firm grip (`rated`).
        Some(format!(
            "final configuration: S = {gii:.3} < ε = {}",
            ctx.options.epsilon
        ))
    } else {
        None
    };
    // The robustness comes after (`rated`): its programs are the search's largest cost.
    let assessment = ctx.assess(&[oc1], &[oc2], ctx.options.stage2_weights);
    let score = 0.1 * assessment.q.max(-1.0) - 2.0 * closed.push;
    tracing::debug!(
        opposition = ?(oc1, oc2),
        approach = ?[a.x, a.y, a.z],
        yaw_deg = yaw.to_degrees(),
        s0,
        t,
        contacts = contacts.len(),
        fingers = ?contacts.iter().map(|c| c.finger).collect::<Vec<_>>(),
        gii,
        reason = reason.as_deref().unwrap_or("feasible"),
        "candidate"
    );
    Ok(Some(FinalConfiguration {
        opposition: (oc1, oc2),
        approach: a,
        hand_pose,
        root_pose: root,
        pregrasp: q_pre,
        grasp: closed.joints,
        squeeze,
        contacts,
        sliding,
        gii,
        robustness: Robustness::default(),
        plane_clearance: clearance.map(|c| c.grasp),
        squeeze_clearance: clearance.map(|c| c.squeeze),
        push: closed.push,
        feasible: reason.is_none(),
        two_sided: h1_side && h2_side,
        short_of_epsilon_only: reason
            .as_deref()
            .is_some_and(|r| r.starts_with("final configuration: S")),
        on_table_only: !contacts_fail
            && into_table.is_some()
            && squeeze_only
            && closed.push <= MAX_PUSH
            && gii >= ctx.options.epsilon,
        reason,
        score,
        cut: false,
        pending,
    }))
}
