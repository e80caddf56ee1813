//! The virtual human control f of Eq 3.9, learned from demonstrations by locally weighted
//! regression (§3.3.1, after Ijspeert et al. [77]).
//!
//! A demonstration is a reach from its first to its last point. It is expressed in its *reach
//! frame* (x from start to goal, scaled so the goal is at x = 1; z the world's up made
//! perpendicular to x) so that one demonstration generalises to any start and goal: the model
//! is linear, so a reach D times as long, turned by R, is driven by D·R·f. The target of the
//! regression is what the impedance model needs to reproduce the demonstration:
//! f_t = M ẍ + C ẋ + K(x − x_g) (Eq 3.7, τ = 1).
//!
//! As in [77], the kernels ψ_i of Eq 3.9 are Gaussians in the movement's *phase*
//! s = exp(−α t / τT), not in the position (a position-based f cannot tell the way out from
//! the way back), and f is multiplied by s so that it vanishes as the reach ends and the
//! spring alone settles the hand on the goal: f(s) = s · Σ ω_i ψ_i(s) / Σ ψ_i(s).

use super::impedance::ImpedanceModel;
use crate::error::FieldError;
use nalgebra::{Rotation3, Vector3};

/// Decay of the phase over a reach: s falls from 1 to e^−4 ≈ 0.018.
pub const PHASE_DECAY: f64 = 4.0;

/// Kernels of Eq 3.9.
pub const KERNELS: usize = 30;

/// A demonstrated reach: positions sampled every `dt` seconds (world frame, m).
#[derive(Debug, Clone, PartialEq)]
pub struct Demonstration {
    pub dt: f64,
    pub positions: Vec<Vector3<f64>>,
}

impl Demonstration {
    /// The built-in demonstration: a minimum-jerk reach of 1 m in 1 s (the bell-shaped speed
    /// of human point-to-point reaching, Flash & Hogan 1985) that rises by a tenth of its length
    /// on the way, as a hand lifts over a table. It is synthesised, not recorded: graspd ships
    /// no human data.
    pub fn minimum_jerk() -> Self {
        const STEPS: usize = 200;
        let dt = 1.0 / STEPS as f64;
        let positions = (0..=STEPS)
            .map(|k| {
                let t = k as f64 / STEPS as f64;
                let along = 10.0 * t.powi(3) - 15.0 * t.powi(4) + 6.0 * t.powi(5);
                let rise = 0.1 * 16.0 * t * t * (1.0 - t) * (1.0 - t);
                Vector3::new(along, 0.0, rise)
            })
            .collect();
        Self { dt, positions }
    }

    /// Duration, s.
    pub fn duration(&self) -> f64 {
        self.dt * (self.positions.len() - 1) as f64
    }

    /// Checks what the regression needs; `field` names the demonstration in errors.
    pub fn validate(&self, field: &str) -> Result<(), FieldError> {
        if !(self.dt.is_finite() && self.dt > 0.0) {
            return Err(FieldError::new(format!("{field}.dt"), "must be positive"));
        }
        if self.positions.len() < 5 {
            return Err(FieldError::new(
                format!("{field}.positions"),
                "needs at least 5 samples",
            ));
        }
        if let Some(i) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(FieldError::new(
                format!("{field}.positions[{i}]"),
                "must be finite",
            ));
        }
        let (a, b) = (self.positions[0], self.positions[self.positions.len() - 1]);
        if (b - a).norm() < 1e-3 {
            return Err(FieldError::new(
                format!("{field}.positions"),
                "start and goal must lie at least 1 mm apart",
            ));
        }
        Ok(())
    }
}

/// The rotation from a reach frame to the world: x along `along`, z the world's `up` made
/// perpendicular to it (any perpendicular when the reach is vertical).
pub fn reach_frame(along: &Vector3<f64>, up: &Vector3<f64>) -> Rotation3<f64> {
    let x = along.normalize();
    let mut z = up - x * x.dot(up);
    if z.norm() < 1e-6 {
        z = x.cross(&Vector3::x());
        if z.norm() < 1e-6 {
            z = x.cross(&Vector3::y());
        }
    }
    let z = z.normalize();
    let y = z.cross(&x);
    Rotation3::from_basis_unchecked(&[x, y, z])
}

/// f of Eq 3.9 in the reach frame of a unit reach (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct ForcingTerm {
    centres: Vec<f64>,
    widths: Vec<f64>,
    weights: Vec<Vector3<f64>>,
    /// The demonstration's duration, s: τ = 1 reproduces it.
    pub duration: f64,
}

impl ForcingTerm {
    /// Learns the weights from demonstrations (LWR, [77]): each kernel's weight is the
    /// s-weighted least-squares fit of the targets f_t under it. `up` is the world's up, which
    /// fixes each demonstration's reach frame. All demonstrations must share one duration
    /// (within a step).
    pub fn learn(
        model: &ImpedanceModel,
        demos: &[Demonstration],
        up: &Vector3<f64>,
    ) -> Result<Self, FieldError> {
        let Some(first) = demos.first() else {
            return Err(FieldError::new("demonstrations", "needs at least one"));
        };
        for (i, d) in demos.iter().enumerate() {
            d.validate(&format!("demonstrations[{i}]"))?;
            if (d.duration() - first.duration()).abs() > d.dt.max(first.dt) {
                return Err(FieldError::new(
                    format!("demonstrations[{i}]"),
                    "all demonstrations must last as long as the first",
                ));
            }
        }
        let duration = first.duration();
        let centres: Vec<f64> = (0..KERNELS)
            .map(|i| (-PHASE_DECAY * i as f64 / (KERNELS - 1) as f64).exp())
            .collect();
        // Neighbouring kernels cross at about half their height.
        let widths: Vec<f64> = (0..KERNELS)
            .map(|i| {
                let gap = if i + 1 < KERNELS {
                    centres[i] - centres[i + 1]
                } else {
                    centres[i - 1] - centres[i]
                };
                1.4 / (gap * gap)
            })
            .collect();
        let mut num = vec![Vector3::zeros(); KERNELS];
        let mut den = vec![0.0; KERNELS];
        for d in demos {
            let p = &d.positions;
            let (start, goal) = (p[0], p[p.len() - 1]);
            let length = (goal - start).norm();
            let to_unit = reach_frame(&(goal - start), up).inverse();
            let unit: Vec<Vector3<f64>> =
                p.iter().map(|x| to_unit * (x - start) / length).collect();
            let g = Vector3::x();
            for k in 0..unit.len() {
                // Central differences inside, one-sided at the ends (the reach starts and ends
                // at rest in a demonstration).
                let (v, a) = if k == 0 || k + 1 == unit.len() {
                    (Vector3::zeros(), Vector3::zeros())
                } else {
                    (
                        (unit[k + 1] - unit[k - 1]) / (2.0 * d.dt),
                        (unit[k + 1] - 2.0 * unit[k] + unit[k - 1]) / (d.dt * d.dt),
                    )
                };
                let target = model.mass * a + model.damping * v + model.stiffness * (unit[k] - g);
                let s = phase(k as f64 * d.dt, duration, 1.0);
                for i in 0..KERNELS {
                    let psi = kernel(s, centres[i], widths[i]);
                    num[i] += psi * s * target;
                    den[i] += psi * s * s;
                }
            }
        }
        let weights = num
            .iter()
            .zip(&den)
            .map(|(n, d)| if *d > 1e-12 { n / *d } else { Vector3::zeros() })
            .collect();
        Ok(Self {
            centres,
            widths,
            weights,
            duration,
        })
    }

    /// f(s) in the unit reach frame.
    pub fn at_phase(&self, s: f64) -> Vector3<f64> {
        let mut num = Vector3::zeros();
        let mut den = 0.0;
        for i in 0..self.centres.len() {
            let psi = kernel(s, self.centres[i], self.widths[i]);
            num += psi * self.weights[i];
            den += psi;
        }
        if den < 1e-300 {
            return Vector3::zeros();
        }
        s * num / den
    }
}

/// The phase at time `t` of a movement of `duration` s at time scale `tau`.
pub fn phase(t: f64, duration: f64, tau: f64) -> f64 {
    (-PHASE_DECAY * t / (tau * duration)).exp()
}

fn kernel(s: f64, centre: f64, width: f64) -> f64 {
    (-width * (s - centre).powi(2)).exp()
}

#[cfg(test)]
mod tests {
    use super::super::impedance::{State, StepInput};
    use super::*;

    /// The model driven by the learned f alone (u = 0) retraces the demonstration: within 1 %
    /// of the reach everywhere, within 3 mm of the goal at the end of a 1 m reach (f has not
    /// quite vanished at s = e⁻⁴; the reach's end cost takes up the rest).
    #[test]
    fn the_learned_forcing_term_reproduces_the_demonstration() {
        let model = ImpedanceModel::default();
        let demo = Demonstration::minimum_jerk();
        let f = ForcingTerm::learn(&model, std::slice::from_ref(&demo), &Vector3::z()).unwrap();
        let mut z = State::zeros();
        let mut worst: f64 = 0.0;
        for (k, p) in demo.positions.iter().enumerate().skip(1) {
            let t = (k - 1) as f64 * demo.dt;
            let s = StepInput {
                u: Vector3::zeros(),
                f: f.at_phase(phase(t, f.duration, 1.0)),
                goal: Vector3::x(),
                tau: 1.0,
                dt: demo.dt,
            };
            z = model.step(&z, &s);
            worst = worst.max((z.fixed_rows::<3>(0) - p).norm());
        }
        let end = (z.fixed_rows::<3>(0) - Vector3::x()).norm();
        println!("strays {worst} m at most, ends {end} m from the goal");
        assert!(worst < 0.01, "strays {worst} m from the demonstration");
        assert!(end < 0.003, "ends {end} m from the goal");
    }

    #[test]
    fn bad_demonstrations_are_refused_naming_the_field() {
        let model = ImpedanceModel::default();
        let mut d = Demonstration::minimum_jerk();
        d.positions[7].y = f64::NAN;
        let e = ForcingTerm::learn(&model, &[d], &Vector3::z()).unwrap_err();
        assert_eq!(e.field, "demonstrations[0].positions[7]");
        let still = Demonstration {
            dt: 0.01,
            positions: vec![Vector3::zeros(); 10],
        };
        let e = ForcingTerm::learn(&model, &[still], &Vector3::z()).unwrap_err();
        assert_eq!(e.field, "demonstrations[0].positions");
        assert!(ForcingTerm::learn(&model, &[], &Vector3::z()).is_err());
    }
}
