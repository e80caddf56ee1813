//! Step 5 of the trial protocol, the close: every actuator ramps together from the pre-grasp
//! commands through the plan's touching commands (the first two thirds of [`CLOSE_S`]) on to its
//! squeeze commands, then the hand settles for [`CLOSE_SETTLE_S`].
//!
//! **Guarded** (the default), as a hand with contact or current sensing closes: an actuator
//! stops at the command it has when the bodies it moves touch the object — every branch it
//! drives, for an actuator that drives several (the 2F-85's one motor for both jaws) — and from
//! there it takes the plan's squeeze travel (squeeze − touch). A finger that meets the object
//! early, because the unseen side is nearer than graspd estimated from one view, then stops
//! pushing before the other fingers arrive; one that meets it late goes on to its squeeze, and
//! graspd's balanced squeeze (each finger's share of a grip that cancels on the object) is
//! pressed from where the fingers really touch. **Open loop** (`--open-loop`): the commands as
//! planned, whatever the fingers meet (a grasp benchmark's replay, DexGraspBench's). Measured on
//! Table 5.2 (10 trials per cell, 2026-12-02, balanced squeeze), open loop → guarded: Robotiq
//! 68 → 68, Barrett 65 → 65, Shadow 39 → 45, Allegro 56 → 55 of 80.
//!
//! A hand with force to spare (`hand.rs`, balanced grip) squeezes with the plan's proportions
//! kept within its force limits ([`within_force_limits`]) instead of the planned commands.

use crate::debug;
use crate::trial::world::Trial;

/// Time the close takes, from the pre-grasp through the touching commands to the squeeze, s.
pub const CLOSE_S: f64 = 0.5;
/// Time the hand settles after the close, s.
pub const CLOSE_SETTLE_S: f64 = 0.4;

/// Per actuator, the branches of hand bodies it moves: for each top-most body one of its
/// degrees of freedom belongs to (through its transmission: joint, tendon or gear), that body
/// and every body below it. Needs `trial.data` forwarded (the transmission moments).
fn moved_branches(trial: &Trial) -> Vec<Vec<Vec<bool>>> {
    let m = &trial.scene.model;
    let d = &trial.data;
    let (nu, nbody) = (m.ffi().nu as usize, m.ffi().nbody as usize);
    let (nnz, adr, col, moment) = (
        d.moment_rownnz(),
        d.moment_rowadr(),
        d.moment_colind(),
        d.actuator_moment(),
    );
    let (dof_body, parent) = (m.dof_bodyid(), m.body_parentid());
    let below = |root: usize, mut b: usize| loop {
        if b == root {
            break true;
        }
        if b == 0 {
            break false;
        }
        b = parent[b] as usize;
    };
    (0..nu)
        .map(|a| {
            let start = adr[a] as usize;
            let mut roots: Vec<usize> = (start..start + nnz[a] as usize)
                .filter(|&k| moment[k].abs() > 1e-9)
                .map(|k| dof_body[col[k] as usize] as usize)
                .collect();
            roots.sort_unstable();
            roots.dedup();
            let tops: Vec<usize> = roots
                .iter()
                .copied()
                .filter(|&r| !roots.iter().any(|&o| o != r && below(o, r)))
                .collect();
            tops.iter()
                .map(|&top| {
                    (0..nbody)
                        .map(|b| trial.scene.hand_bodies[b] && below(top, b))
                        .collect()
                })
                .collect()
        })
        .collect()
}

/// Closes the hand from its current commands to `squeeze` through `touch` (module doc); returns
/// the object's position when the touching commands are reached (before the squeeze), so a
/// record can tell a push while closing from one while squeezing.
pub fn close(
    trial: &mut Trial,
    touch: &[f64],
    squeeze: &[f64],
    guarded: bool,
) -> nalgebra::Point3<f64> {
    trial.data.forward();
    let branches = if guarded {
        moved_branches(trial)
    } else {
        Vec::new()
    };
    let open: Vec<f64> = trial.data.ctrl().to_vec();
    let nbody = trial.scene.model.ffi().nbody as usize;
    let mut stopped: Vec<Option<f64>> = vec![None; open.len()];
    let mut at_touch = trial.object_position();
    for (k, phase) in ["closing_1", "closing_2", "closing_3"].iter().enumerate() {
        trial.run(CLOSE_S / 3.0, |t, f| {
            let f = (k as f64 + f) / 3.0;
            if f < 2.0 / 3.0 {
                if guarded {
                    let mut touching = vec![false; nbody];
                    for (_, b) in t.hand_contacts_with_object() {
                        touching[b] = true;
                    }
                    for (a, s) in stopped.iter_mut().enumerate() {
                        let met = !branches[a].is_empty()
                            && branches[a]
                                .iter()
                                .all(|br| br.iter().zip(&touching).any(|(m, t)| *m && *t));
                        if s.is_none() && met {
                            *s = Some(t.data.ctrl()[a]);
                        }
                    }
                }
                let g = f * 1.5;
                for (a, c) in t.data.ctrl_mut().iter_mut().enumerate() {
                    *c = stopped[a].unwrap_or(open[a] + (touch[a] - open[a]) * g);
                }
            } else {
                let g = (f - 2.0 / 3.0) * 3.0;
                for (a, c) in t.data.ctrl_mut().iter_mut().enumerate() {
                    *c = stopped[a].unwrap_or(touch[a]) + (squeeze[a] - touch[a]) * g;
                }
            }
        });
        debug::snapshot(trial, phase);
        if k == 1 {
            at_touch = trial.object_position();
        }
    }
    trial.run(CLOSE_SETTLE_S, |_, _| {});
    at_touch
}

/// The squeeze commands with the plan's proportions kept and the grip set by the actuators'
/// force limits: graspd's squeeze asks each joint for a torque in proportion to its travel
/// (one stiffness for the whole hand); here every actuator's travel from its touch is made
/// `c·Δ/g` (g its servo gain), `c` the common scale at which the most loaded force-limited
/// actuator asks exactly its limit: none saturates, so the forces keep the proportions graspd
/// balanced. (Asked twice its limit, the most loaded saturated while the others pushed their
/// full share, and the grip pushed light objects out of the hand: Barrett, 20 trials per
/// cell, 3 fused views, banana 13 → 18, orange 17 → 20 of 20 at the limit; what it costs is
/// force on a heavy box, the 514 g sugar box held 15 of 20 instead of 20.) Unchanged when an
/// actuator that travels has no force limit (its squeeze depth was sized for its gain) or only
/// one actuator travels.
pub fn within_force_limits(
    m: &mujoco_rs::prelude::MjModel,
    touch: &[f64],
    squeeze: &[f64],
) -> Vec<f64> {
    let (gain, limited) = (m.actuator_gainprm(), m.actuator_forcelimited());
    let travels: Vec<usize> = (0..touch.len())
        .filter(|&a| (squeeze[a] - touch[a]).abs() > 1e-6)
        .collect();
    if travels.len() < 2
        || travels
            .iter()
            .any(|&a| !limited[a] || gain[a][0].abs() < 1e-9)
    {
        return squeeze.to_vec();
    }
    // Each travelling actuator's share: its planned travel (one stiffness for the hand).
    let shares: Vec<(usize, f64)> = travels
        .iter()
        .map(|&a| (a, squeeze[a] - touch[a]))
        .collect();
    let c = scale_to_limits(m, &shares);
    let mut out = squeeze.to_vec();
    for &a in &travels {
        out[a] = touch[a] + c * (squeeze[a] - touch[a]) / gain[a][0];
    }
    out
}

/// The common scale c at which the most loaded of force-limited actuators (index, share of a
/// force distribution) asks its limit: c·share within every actuator's force range, one at its
/// end.
pub fn scale_to_limits(m: &mujoco_rs::prelude::MjModel, shares: &[(usize, f64)]) -> f64 {
    let range = m.actuator_forcerange();
    shares
        .iter()
        .filter(|&&(_, u)| u.abs() > 1e-12)
        .map(|&(a, u)| {
            let limit = if u > 0.0 { range[a][1] } else { -range[a][0] };
            limit.max(0.0) / u.abs()
        })
        .fold(f64::INFINITY, f64::min)
}
