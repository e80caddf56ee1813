//! The grip reflex: after the close, a hand that feels its object slide grips harder, in the
//! proportions of graspd's balanced squeeze — what a hand with tactile sensing does when the
//! load comes on in the lift (graspd's own stabiliser, method.md §5, raises its force on slip
//! the same way).
//!
//! Armed when the close ends ([`GripReflex::arm`]); from then on, before every step, the
//! fastest sliding of the object across a touching hand body ([`sliding_speed`]) is measured,
//! and while it exceeds [`SLIP_SPEED`] the reflex's gain rises at [`RISE_PER_S`] up to 1 and never
//! falls. Each actuator that travelled in the squeeze then asks, on top of its position command,
//! `gain` times its reinforcement: its share of the plan's balanced grip, scaled so that the
//! most loaded asks its limit (the share of actuator a: its squeeze travel over Σ_j G_aj², G
//! its transmission's moments — the force that, through its joints, best gives the joint
//! torques graspd's squeeze asks for with one stiffness for the whole hand; a tendon coupling
//! two joints, the Shadow's distal pair, takes half its travel's share). A hand with a
//! travelling servo that has no force limit has no strength to reinforce up to and keeps the
//! grip of its close (reinforced by its planned force instead, the Allegro held 234 → 229 of
//! 260 on all 13 objects).
//!
//! Why on slip only: the object that does not slide keeps the grip the close gave it. Measured
//! on the Shadow (20 trials per cell, paired with session 13's run): reinforcing from the close
//! on knocked light round objects out of the hand (3 fused views: 149 → 142 of 160, the orange
//! 19 → 16) while heavy boxes held more (all 13 objects: 217 → 228 of 260, the sugar box 8 → 13);
//! on slip only it kept both (149 → 153, 217 → 226). Triggered by the share of friction the
//! contacts use (tangential over μ·normal above 0.8) instead: 149 → 149 and 217 → 224; scaling
//! every actuator's own force at the end of the close instead of the plan's proportions:
//! 149 → 145 and 217 → 220.

use crate::trial::world::{BeforeStep, Trial};
use mujoco_rs::prelude::*;
use nalgebra::{Point3, Vector3};

/// Sliding of the object across a touching hand body that counts as slip, m/s.
pub const SLIP_SPEED: f64 = 0.02;
/// How fast the gain rises while the object slides, per second (full in 0.2 s of sliding).
pub const RISE_PER_S: f64 = 5.0;

/// One actuator's reinforcement: its command at the end of the close and the force it adds
/// at full gain.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Reinforcement {
    actuator: usize,
    command: f64,
    force: f64,
}

/// The armed reflex of one trial.
#[derive(Debug, Clone, PartialEq)]
pub struct GripReflex {
    reinforcements: Vec<Reinforcement>,
    /// 0 (the grip of the close) to 1 (fully reinforced).
    pub gain: f64,
}

impl GripReflex {
    /// Armed at the end of the close on the plan's touching (`touch`) and squeeze (`squeeze`)
    /// commands, the actuators holding their current commands; None when no actuator travels
    /// or one that does has no force limit.
    /// Needs the transmission moments of `trial.data` (any step or forward computes them).
    pub fn arm(trial: &Trial, touch: &[f64], squeeze: &[f64]) -> Option<Self> {
        let m = &trial.scene.model;
        let d = &trial.data;
        let (gain, limited) = (m.actuator_gainprm(), m.actuator_forcelimited());
        let (nnz, adr, moment) = (d.moment_rownnz(), d.moment_rowadr(), d.actuator_moment());
        let travels: Vec<(usize, f64)> = (0..touch.len())
            .map(|a| (a, squeeze[a] - touch[a]))
            .filter(|&(a, t)| t.abs() > 1e-6 && gain[a][0].abs() > 1e-9)
            .collect();
        if travels.is_empty() {
            return None;
        }
        // A servo without a force limit has no strength to reinforce up to.
        if travels.iter().any(|&(a, _)| !limited[a]) {
            return None;
        }
        let shares: Vec<(usize, f64)> = travels
            .iter()
            .map(|&(a, t)| {
                let s = adr[a] as usize;
                let g2: f64 = moment[s..s + nnz[a] as usize].iter().map(|x| x * x).sum();
                (a, t / g2.max(1e-12))
            })
            .collect();
        let c = crate::closing::scale_to_limits(m, &shares);
        Some(GripReflex {
            reinforcements: shares
                .iter()
                .map(|&(a, u)| Reinforcement {
                    actuator: a,
                    command: d.ctrl()[a],
                    force: c * u,
                })
                .collect(),
            gain: 0.0,
        })
    }

    /// One step: the gain after `dt` s at slip speed `v_slip` (m/s).
    pub fn rise(gain: f64, v_slip: f64, dt: f64) -> f64 {
        if v_slip > SLIP_SPEED {
            (gain + RISE_PER_S * dt).min(1.0)
        } else {
            gain
        }
    }

    /// Measures the slip, updates the gain and sets the reinforced commands (within the
    /// control range).
    pub fn apply(&mut self, trial: &mut Trial) {
        // At full gain there is nothing left to measure for.
        if self.gain < 1.0 {
            let dt = trial.scene.model.ffi().opt.timestep;
            self.gain = Self::rise(self.gain, sliding_speed(trial), dt);
        }
        let m = &trial.scene.model;
        let (gain, limited, range) = (
            m.actuator_gainprm(),
            m.actuator_ctrllimited(),
            m.actuator_ctrlrange(),
        );
        for r in &self.reinforcements {
            let a = r.actuator;
            let mut c = r.command + self.gain * r.force / gain[a][0];
            if limited[a] {
                c = c.clamp(range[a][0], range[a][1]);
            }
            trial.data.ctrl_mut()[a] = c;
        }
    }
}

/// Armed on a trial, the reflex runs before every step.
impl BeforeStep for GripReflex {
    fn before_step(&mut self, trial: &mut Trial) {
        self.apply(trial);
    }

    fn boxed_clone(&self) -> Box<dyn BeforeStep> {
        Box::new(self.clone())
    }
}

/// The fastest sliding of the object across a hand body touching it (tangential speed of the
/// object's material point relative to the body's at each contact), m/s.
pub fn sliding_speed(trial: &Trial) -> f64 {
    let obj = trial.scene.object_bodies[0];
    trial
        .hand_contacts_with_object()
        .map(|(i, b)| contact_sliding(trial, i, obj, b))
        .fold(0.0, f64::max)
}

/// Tangential speed of body `obj` relative to body `b` at contact `i`, m/s.
pub fn contact_sliding(trial: &Trial, i: usize, obj: usize, b: usize) -> f64 {
    let c = &trial.data.contact()[i];
    let n = Vector3::new(c.frame[0], c.frame[1], c.frame[2]);
    let p = Point3::from(c.pos);
    let v = point_velocity(trial, obj, &p) - point_velocity(trial, b, &p);
    (v - n * v.dot(&n)).norm()
}

/// Velocity of body `b`'s material point at `p` (world).
fn point_velocity(trial: &Trial, b: usize, p: &Point3<f64>) -> Vector3<f64> {
    let v = trial
        .data
        .object_velocity(MjtObjBase::mjOBJ_XBODY, b, false);
    let (w, lin) = (
        Vector3::new(v[0], v[1], v[2]),
        Vector3::new(v[3], v[4], v[5]),
    );
    let o = trial.data.xpos()[b];
    lin + w.cross(&(p - Point3::new(o[0], o[1], o[2])))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The gain rises only while the object slides faster than the threshold, at the set rate,
    /// and stops at 1.
    #[test]
    fn the_gain_rises_on_slip_only_and_saturates() {
        let dt = 0.002;
        assert_eq!(GripReflex::rise(0.0, 0.5 * SLIP_SPEED, dt), 0.0);
        let once = GripReflex::rise(0.0, 2.0 * SLIP_SPEED, dt);
        assert!((once - RISE_PER_S * dt).abs() < 1e-12, "{once}");
        // Held where it got to when the sliding stops.
        assert_eq!(GripReflex::rise(once, 0.0, dt), once);
        let mut g = 0.0;
        for _ in 0..200 {
            g = GripReflex::rise(g, 1.0, dt);
        }
        assert_eq!(g, 1.0);
    }
}
