//! The per-finger force controller (dissertation ch. 6.5): a PID on the force error
//! Δf = f_d − f whose output is the setpoint streamed to the finger's low-level controller.
//!
//! * Derivative on the measurement (−df/dt) so that steps of f_d (material or slip updates) do not
//!   kick the output; optional first-order filter on it.
//! * Output limits [u_min, u_max] and **anti-windup by conditional integration (clamping)**: the
//!   integral is not advanced while the output is saturated and the error would drive it further
//!   into saturation.
//! * `reset` clears the state; the stabilizer resets when a finger goes to position mode.

use crate::error::FieldError;
use serde::{Deserialize, Serialize};

/// Gains and limits. Output units are whatever the low-level controller takes (joint torque or
/// position offset); force units are those of the estimated force.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PidGains {
    pub kp: f64,
    pub ki: f64,
    pub kd: f64,
    pub output_min: f64,
    pub output_max: f64,
    /// Time constant of the derivative filter, s (0 = unfiltered).
    pub derivative_filter_s: f64,
}

impl Default for PidGains {
    fn default() -> Self {
        Self {
            kp: 0.5,
            ki: 2.0,
            kd: 0.0,
            output_min: -1.0,
            output_max: 1.0,
            derivative_filter_s: 0.02,
        }
    }
}

impl PidGains {
    pub fn validate(&self, prefix: &str) -> Result<(), FieldError> {
        for (name, v) in [
            ("kp", self.kp),
            ("ki", self.ki),
            ("kd", self.kd),
            ("derivative_filter_s", self.derivative_filter_s),
        ] {
            if !v.is_finite() || v < 0.0 {
                return Err(FieldError::new(
                    format!("{prefix}.{name}"),
                    format!("must be a finite number ≥ 0, got {v}"),
                ));
            }
        }
        if !self.output_min.is_finite()
            || !self.output_max.is_finite()
            || self.output_min >= self.output_max
        {
            return Err(FieldError::new(
                format!("{prefix}.output_min"),
                format!(
                    "output_min ({}) must be below output_max ({})",
                    self.output_min, self.output_max
                ),
            ));
        }
        Ok(())
    }
}

/// PID state.
#[derive(Debug, Clone)]
pub struct Pid {
    pub gains: PidGains,
    integral: f64,
    prev_measurement: Option<f64>,
    derivative: f64,
}

impl Pid {
    pub fn new(gains: PidGains) -> Self {
        Self {
            gains,
            integral: 0.0,
            prev_measurement: None,
            derivative: 0.0,
        }
    }

    pub fn reset(&mut self) {
        self.integral = 0.0;
        self.prev_measurement = None;
        self.derivative = 0.0;
    }

    /// One control step: error Δf = setpoint − measurement, time step `dt` > 0 s. Returns the
    /// limited output.
    pub fn step(&mut self, setpoint: f64, measurement: f64, dt: f64) -> f64 {
        let g = self.gains;
        let e = setpoint - measurement;
        if let Some(prev) = self.prev_measurement {
            let raw = -(measurement - prev) / dt;
            let a = if g.derivative_filter_s > 0.0 {
                dt / (g.derivative_filter_s + dt)
            } else {
                1.0
            };
            self.derivative += a * (raw - self.derivative);
        }
        self.prev_measurement = Some(measurement);
        let candidate_integral = self.integral + g.ki * e * dt;
        let unclamped = g.kp * e + candidate_integral + g.kd * self.derivative;
        let out = unclamped.clamp(g.output_min, g.output_max);
        // Conditional integration: accept the new integral unless it pushes further into the
        // saturated side.
        let saturated_high = unclamped > g.output_max && e > 0.0;
        let saturated_low = unclamped < g.output_min && e < 0.0;
        if !(saturated_high || saturated_low) {
            self.integral = candidate_integral;
        }
        out
    }

    pub fn integral(&self) -> f64 {
        self.integral
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A finger pressing on an object: the PID output u commands the fingertip position (mm past
    /// first touch), a first-order actuator follows it (time constant τ), the object is a spring:
    /// f = k · max(x, 0). Returns the force trace at 100 Hz.
    fn simulate(gains: PidGains, f_d: f64, k: f64, tau: f64, steps: usize) -> Vec<f64> {
        let dt = 0.01;
        let mut pid = Pid::new(gains);
        let (mut x, mut f) = (0.0, 0.0);
        let mut trace = Vec::with_capacity(steps);
        for _ in 0..steps {
            let u = pid.step(f_d, f, dt);
            // Exact discretisation of ẋ = (u − x)/τ over dt.
            x = u + (x - u) * (-dt / tau).exp();
            f = k * x.max(0.0);
            trace.push(f);
        }
        trace
    }

    #[test]
    fn pid_tracks_a_force_step_without_sustained_oscillation() {
        // Object stiffness 1 N/mm, actuator τ = 50 ms, output limited to ±10 mm.
        let gains = PidGains {
            kp: 0.3,
            ki: 4.0,
            kd: 0.0,
            output_min: -10.0,
            output_max: 10.0,
            derivative_filter_s: 0.02,
        };
        let f_d = 2.0;
        let trace = simulate(gains, f_d, 1.0, 0.05, 300);
        let peak = trace.iter().cloned().fold(0.0, f64::max);
        let overshoot = (peak - f_d) / f_d;
        assert!(overshoot < 0.2, "overshoot {:.1} %", overshoot * 100.0);
        // Settled within 2 % after 1.5 s and stays there (no sustained oscillation).
        let settle = trace
            .iter()
            .rposition(|f| (f - f_d).abs() > 0.02 * f_d)
            .map_or(0, |i| i + 1);
        assert!(settle <= 150, "settles after {} steps", settle);
        let tail = &trace[200..];
        let swing = tail.iter().cloned().fold(f64::MIN, f64::max)
            - tail.iter().cloned().fold(f64::MAX, f64::min);
        assert!(swing < 0.01, "tail swing {swing}");
    }

    #[test]
    fn anti_windup_limits_the_integral_while_saturated() {
        // Unreachable set-point with a tight output limit: without anti-windup the integral grows
        // without bound; with clamping it stops growing once the output saturates.
        let gains = PidGains {
            kp: 0.1,
            ki: 5.0,
            kd: 0.0,
            output_min: -1.0,
            output_max: 1.0,
            derivative_filter_s: 0.0,
        };
        let mut pid = Pid::new(gains);
        for _ in 0..1000 {
            assert!(pid.step(100.0, 0.0, 0.01) <= 1.0);
        }
        assert!(pid.integral() <= 1.0, "integral {}", pid.integral());
        // When the set-point drops, the output leaves saturation immediately.
        let u = pid.step(0.0, 10.0, 0.01);
        assert!(u < 0.0, "{u}");
        // The response to a reachable step after saturation still settles.
        let trace = simulate(gains, 0.5, 1.0, 0.05, 600);
        assert!((trace[599] - 0.5).abs() < 0.01);
    }

    #[test]
    fn gains_validation_names_fields() {
        let g = PidGains {
            ki: -1.0,
            ..Default::default()
        };
        assert_eq!(
            g.validate("session.pid").unwrap_err().field,
            "session.pid.ki"
        );
        let g = PidGains {
            output_min: 2.0,
            ..Default::default()
        };
        assert_eq!(
            g.validate("session.pid").unwrap_err().field,
            "session.pid.output_min"
        );
    }
}
