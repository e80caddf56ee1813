//! Module step 3 and the pre-grasp opening of a closed candidate (the squeeze, the opening
//! the fingers come in with, the table's clearance), and their completion for a candidate the
//! search judged by its contacts alone.

use super::closing_sweep::{Closed, SweepContact, SweepHand};
use super::object_view::ObjectView;
use super::pregrasp::{advance_contacts, joints_at};
use super::squeeze::{self, squeeze_joints};
use super::{FinalConfiguration, PREGRASP_TRAVELS, placement};
use crate::error::FieldError;
use crate::planning::evaluation::SearchContext;
use crate::planning::kinematic_model::KinematicModel;
use nalgebra::{Isometry3, Vector3};

impl FinalConfiguration {
    /// The candidate with its squeeze, pre-grasp opening and table clearance (module steps 3
    /// and 4), for one whose contacts alone ruled it out (the search spares them until then).
    pub(super) fn completed(
        mut self,
        ctx: &SearchContext,
        model: &KinematicModel,
        object: &ObjectView,
    ) -> Result<Self, FieldError> {
        let Some(Pending { closed, s0 }) = self.pending.take() else {
            return Ok(self);
        };
        let sweep = SweepHand {
            hand: &model.hand,
            synergy: &model.synergy,
            collision: &model.collision,
            projections: &model.projections,
            root_in_world: self.root_pose,
        };
        let pre = std::mem::take(&mut self.pregrasp);
        let (squeeze, clearance);
        (squeeze, self.pregrasp, clearance) = grip(
            ctx,
            model,
            object,
            &sweep,
            &closed,
            &self.contacts,
            &self.hand_pose,
            &self.approach,
            pre,
            s0,
        )?;
        (self.squeeze, self.sliding) = (squeeze.joints, squeeze.slides);
        self.plane_clearance = clearance.map(|c| c.grasp);
        self.squeeze_clearance = clearance.map(|c| c.squeeze);
        Ok(self)
    }
}

/// What a candidate ruled out by its contacts alone lacks until it is output: its squeeze, its
/// pre-grasp opening and its clearance to the table (the search's third largest cost, spared
/// for the 40–70 % of candidates that touch one side only or cannot balance).
#[derive(Debug, Clone)]
pub(super) struct Pending {
    pub closed: Closed,
    pub s0: f64,
}

/// The squeeze, pre-grasp joints, and the clearance of the grasp and the squeeze to the table
/// (None without one).
type Grip = (squeeze::Squeeze, Vec<f64>, Option<TableClearance>);

/// The hand's least clearance to the table (m, negative inside it) with the grasp joints and
/// with the squeeze joints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct TableClearance {
    pub grasp: f64,
    pub squeeze: f64,
}

/// Module step 3 and the pre-grasp opening of a closed candidate ([`Grip`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn grip(
    ctx: &SearchContext,
    model: &KinematicModel,
    object: &ObjectView,
    sweep: &SweepHand,
    closed: &Closed,
    contacts: &[SweepContact],
    hand_pose: &Isometry3<f64>,
    a: &Vector3<f64>,
    q_pre: Vec<f64>,
    s0: f64,
) -> Result<Grip, FieldError> {
    let hand = &model.hand;
    let root = sweep.root_in_world;
    let frame = squeeze::GripFrame {
        centre_of_mass: ctx.shape.center,
        radius: ctx.shape.radius,
        friction: ctx.options.friction,
    };
    let squeeze = squeeze_joints(
        model,
        sweep,
        closed,
        contacts,
        ctx.options.squeeze_depth,
        &frame,
        object,
    )?;
    // The pre-grasp opening: every finger backed off its touch by the same travel, so that
    // all arrive together — the tightest of PREGRASP_TRAVELS with which the hand so shaped
    // still comes in clear (else the pre-shape it came in with).
    let mut q_pre = q_pre;
    for travel in PREGRASP_TRAVELS {
        let mut opening = advance_contacts(model, sweep, closed, contacts, -travel, s0)?;
        for (_, sv) in &mut opening {
            sv.iter_mut().for_each(|x| *x = x.max(s0));
        }
        let q_open = joints_at(model, closed, &opening)?;
        if let Some(t2) = placement::move_in(
            model,
            &q_open,
            hand_pose,
            a,
            ctx.options.pregrasp_distance,
            0.0,
            object,
        )? && t2 >= -1e-9
        {
            q_pre = q_open;
            break;
        }
    }
    // The table at the grasp and under the squeeze (the pre-grasp and the way in were kept
    // clear).
    let plane_clearance = match object.plane {
        Some(pl) => {
            let mut c = [0.0; 2];
            for (c, q) in c.iter_mut().zip([&closed.joints, &squeeze.joints]) {
                let fk = hand.tree.forward(q)?;
                *c = model.collision.posed_fk(&fk, &root).plane_clearance(pl);
            }
            Some(TableClearance {
                grasp: c[0],
                squeeze: c[1],
            })
        }
        None => None,
    };
    Ok((squeeze, q_pre, plane_clearance))
}
