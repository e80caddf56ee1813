//! The desired contact force f_d (dissertation ch. 6.5, Eq 6.8, 6.9, Algorithm 5 lines 6–10).

use super::detector::{ContactEvent, Material};
use crate::error::FieldError;
use serde::{Deserialize, Serialize};

/// What the finger's low-level controller should do (Algorithm 5, lines 6–10).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControlMode {
    /// Non-contact: move to the desired joint position.
    Position,
    /// In contact: track f_d with the force PID.
    Force,
}

/// f0, δf_m, δf_s and the safety clip [f_min, f_max] (same units as the estimated force), and
/// whether slip latches.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DesiredForceLaw {
    pub f0: f64,
    pub delta_material: f64,
    pub delta_slip: f64,
    pub f_min: f64,
    pub f_max: f64,
    /// A deviation from Eq 6.9, off by default: each slip episode (and each further
    /// [`super::stabilizer::LATCH_STEP_S`] a slip lasts) raises f_d by δf_s for as long as the
    /// finger stays in contact (a ratchet), instead of f_d falling back to f_d^m as soon as the
    /// slip stops. Eq 6.9 answers a creeping object with a force that rises and
    /// falls with each episode; a load that persists (an object heavier than f0 was set for)
    /// makes it slip again each time ([`DesiredForceLaw::latched_force`]).
    #[serde(default)]
    pub latch_slip: bool,
}

impl Default for DesiredForceLaw {
    /// Newton-scale defaults for a calibrated BioTac: f0 = 1.5 N, δf_m = 0.5 N, δf_s = 0.5 N,
    /// clipped to [0.2, 5] N. With raw units configure values on the raw scale.
    fn default() -> Self {
        Self {
            f0: 1.5,
            delta_material: 0.5,
            delta_slip: 0.5,
            f_min: 0.2,
            f_max: 5.0,
            latch_slip: false,
        }
    }
}

impl DesiredForceLaw {
    /// Errors name `prefix.f0`, `prefix.f_max`, ….
    pub fn validate(&self, prefix: &str) -> Result<(), FieldError> {
        for (name, v) in [
            ("f0", self.f0),
            ("delta_material", self.delta_material),
            ("delta_slip", self.delta_slip),
            ("f_min", self.f_min),
            ("f_max", self.f_max),
        ] {
            if !v.is_finite() || v < 0.0 {
                return Err(FieldError::new(
                    format!("{prefix}.{name}"),
                    format!("must be a finite number ≥ 0, got {v}"),
                ));
            }
        }
        if self.f_min > self.f_max {
            return Err(FieldError::new(
                format!("{prefix}.f_min"),
                format!("must not exceed f_max ({}), got {}", self.f_max, self.f_min),
            ));
        }
        Ok(())
    }

    /// Eq 6.8: f_d^m from the material. `Unknown` (no material estimate) keeps f0, as for paper
    /// and plastic.
    pub fn material_force(&self, m: Material) -> f64 {
        match m {
            Material::Paper | Material::Plastic | Material::Unknown => self.f0,
            Material::Foam => self.f0 - self.delta_material,
            Material::Metal => self.f0 + self.delta_material,
        }
    }

    /// Eq 6.9: f_d^s from the event and f_d^m.
    pub fn event_force(&self, e: ContactEvent, f_dm: f64) -> f64 {
        match e {
            ContactEvent::NonContact => self.f0,
            ContactEvent::Contact => f_dm,
            ContactEvent::Slip => f_dm + self.delta_slip,
        }
    }

    /// f_d^s with the latch ([`DesiredForceLaw::latch_slip`]): in contact, after
    /// `slip_episodes` ≥ 1 slip episodes since the contact began, f_d^m + episodes · δf_s,
    /// whether or not the finger slips now; Eq 6.9 otherwise (or with the latch off).
    pub fn latched_force(&self, e: ContactEvent, f_dm: f64, slip_episodes: u32) -> f64 {
        if self.latch_slip && slip_episodes > 0 && e != ContactEvent::NonContact {
            f_dm + self.delta_slip * f64::from(slip_episodes)
        } else {
            self.event_force(e, f_dm)
        }
    }

    /// f_d = clip(f_d^s, f_min, f_max) (with the latch, after `slip_episodes` slip episodes in
    /// this contact) and the control mode (non-contact → position).
    pub fn desired(&self, e: ContactEvent, m: Material, slip_episodes: u32) -> (f64, ControlMode) {
        let fd = self
            .latched_force(e, self.material_force(m), slip_episodes)
            .clamp(self.f_min, self.f_max);
        let mode = if e == ContactEvent::NonContact {
            ControlMode::Position
        } else {
            ControlMode::Force
        };
        (fd, mode)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn desired_force_follows_eq_6_8_and_6_9_for_every_material_and_event() {
        let law = DesiredForceLaw {
            f0: 2.0,
            delta_material: 0.5,
            delta_slip: 0.75,
            f_min: 0.0,
            f_max: 10.0,
            latch_slip: false,
        };
        let fdm = |m| match m {
            Material::Paper | Material::Plastic | Material::Unknown => 2.0,
            Material::Foam => 1.5,
            Material::Metal => 2.5,
        };
        for m in Material::CLASSES.into_iter().chain([Material::Unknown]) {
            assert_eq!(law.material_force(m), fdm(m), "{m:?}");
            for e in ContactEvent::ALL {
                let (fd, mode) = law.desired(e, m, 0);
                // Without the latch, past slip episodes change nothing (Eq 6.9 as printed).
                assert_eq!(law.desired(e, m, 3), (fd, mode), "{m:?} {e:?}");
                let want = match e {
                    ContactEvent::NonContact => 2.0,
                    ContactEvent::Contact => fdm(m),
                    ContactEvent::Slip => fdm(m) + 0.75,
                };
                assert_eq!(fd, want, "{m:?} {e:?}");
                assert_eq!(
                    mode,
                    if e == ContactEvent::NonContact {
                        ControlMode::Position
                    } else {
                        ControlMode::Force
                    }
                );
            }
        }
    }

    #[test]
    fn desired_force_is_clipped() {
        let law = DesiredForceLaw {
            f0: 2.0,
            delta_material: 1.5,
            delta_slip: 1.0,
            f_min: 1.0,
            f_max: 3.0,
            latch_slip: false,
        };
        assert_eq!(law.desired(ContactEvent::Slip, Material::Metal, 1).0, 3.0); // 4.5 → 3
        assert_eq!(law.desired(ContactEvent::Contact, Material::Foam, 0).0, 1.0); // 0.5 → 1
        assert_eq!(law.desired(ContactEvent::Slip, Material::Foam, 1).0, 1.5);
        let bad = DesiredForceLaw { f_min: 4.0, ..law };
        assert_eq!(bad.validate("session").unwrap_err().field, "session.f_min");
    }

    /// The latch: each slip episode adds δf_s and the force stays raised through contact
    /// without slip (2 + 0.5 = 2.5 after one episode, 3.0 after two, on plastic f_d^m = 2),
    /// clipped at f_max (3.2); out of contact the finger goes back to f0 in position mode.
    #[test]
    fn a_latched_slip_ratchets_the_force_until_contact_is_lost() {
        let law = DesiredForceLaw {
            f0: 2.0,
            delta_material: 0.5,
            delta_slip: 0.5,
            f_min: 0.0,
            f_max: 3.2,
            latch_slip: true,
        };
        let plastic = Material::Plastic;
        assert_eq!(law.desired(ContactEvent::Contact, plastic, 0).0, 2.0);
        assert_eq!(law.desired(ContactEvent::Slip, plastic, 1).0, 2.5);
        assert_eq!(law.desired(ContactEvent::Contact, plastic, 1).0, 2.5);
        assert_eq!(law.desired(ContactEvent::Contact, plastic, 2).0, 3.0);
        assert_eq!(law.desired(ContactEvent::Slip, plastic, 3).0, 3.2);
        // Metal's f_d^m is 2.5: one episode gives 3.0.
        assert_eq!(
            law.desired(ContactEvent::Contact, Material::Metal, 1).0,
            3.0
        );
        assert_eq!(
            law.desired(ContactEvent::NonContact, plastic, 2),
            (2.0, ControlMode::Position)
        );
    }
}
