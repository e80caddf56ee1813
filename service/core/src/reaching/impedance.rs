//! The impedance model of the reaching hand (dissertation §3.3.1, Eq 3.7, 3.8 and 3.10):
//! τ²M ẍ + τC ẋ + K(x − x_g) = f_t + u_t, with the dissertation's M = 2I, C = 25I,
//! K = 156.5I (critically damped within 1 %: ζ = C / 2√(KM) = 0.707, ω = 8.8 rad/s).
//!
//! τ scales time as in Ijspeert's dynamic movement primitives, which the dissertation's model
//! follows ([77]): a forcing term learned from a demonstration of duration T reproduces it in
//! τT. Eq 3.10 as printed has the continuous-time matrices with the wrong signs on the spring
//! and damper blocks; the discrete model here is the semi-implicit Euler step of Eq 3.8
//! (v' = v + Δt·ẍ, x' = x + Δt·v'), stable for Δt·ω < 2 — the 10 ms default is 0.09.

use nalgebra::{Matrix3, Matrix6, SMatrix, Vector3, Vector6};

/// z = [x, ẋ] (Eq 3.10).
pub type State = Vector6<f64>;

/// ∂z'/∂u of one step.
pub type ControlJacobian = SMatrix<f64, 6, 3>;

/// M, C and K, isotropic (Eq 3.7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpedanceModel {
    pub mass: f64,
    pub damping: f64,
    pub stiffness: f64,
}

impl Default for ImpedanceModel {
    /// The dissertation's values (§3.4).
    fn default() -> Self {
        Self {
            mass: 2.0,
            damping: 25.0,
            stiffness: 156.5,
        }
    }
}

/// One step's inputs besides the state: the robot's control u, the learned human control f,
/// the attractor x_g, the time scale τ and the step Δt.
#[derive(Debug, Clone, Copy)]
pub struct StepInput {
    pub u: Vector3<f64>,
    pub f: Vector3<f64>,
    pub goal: Vector3<f64>,
    pub tau: f64,
    pub dt: f64,
}

impl ImpedanceModel {
    /// ẍ of Eq 3.8 at state `z`.
    pub fn acceleration(&self, z: &State, s: &StepInput) -> Vector3<f64> {
        let x = z.fixed_rows::<3>(0);
        let v = z.fixed_rows::<3>(3);
        (s.f + s.u - self.damping * s.tau * v - self.stiffness * (x - s.goal))
            / (self.mass * s.tau * s.tau)
    }

    /// z_{t+1} (Eq 3.10, semi-implicit Euler).
    pub fn step(&self, z: &State, s: &StepInput) -> State {
        let a = self.acceleration(z, s);
        let v = z.fixed_rows::<3>(3) + s.dt * a;
        let x = z.fixed_rows::<3>(0) + s.dt * v;
        let mut next = State::zeros();
        next.fixed_rows_mut::<3>(0).copy_from(&x);
        next.fixed_rows_mut::<3>(3).copy_from(&v);
        next
    }

    /// ∂z_{t+1}/∂z_t and ∂z_{t+1}/∂u_t: constant, the model being linear.
    pub fn jacobians(&self, tau: f64, dt: f64) -> (Matrix6<f64>, ControlJacobian) {
        let m = self.mass * tau * tau;
        let i = Matrix3::<f64>::identity();
        let dv_dx = -dt * self.stiffness / m * i;
        let dv_dv = (1.0 - dt * self.damping * tau / m) * i;
        let dv_du = dt / m * i;
        let mut a = Matrix6::zeros();
        a.fixed_view_mut::<3, 3>(0, 0).copy_from(&(i + dt * dv_dx));
        a.fixed_view_mut::<3, 3>(0, 3).copy_from(&(dt * dv_dv));
        a.fixed_view_mut::<3, 3>(3, 0).copy_from(&dv_dx);
        a.fixed_view_mut::<3, 3>(3, 3).copy_from(&dv_dv);
        let mut b = ControlJacobian::zeros();
        b.fixed_view_mut::<3, 3>(0, 0).copy_from(&(dt * dv_du));
        b.fixed_view_mut::<3, 3>(3, 0).copy_from(&dv_du);
        (a, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// From rest 1 m short of the goal along x, no forcing, τ = 1, Δt = 0.01: ẍ = K·1/M =
    /// 78.25 m/s², so v' = 0.7825 m/s and x' = −1 + 0.007825 m (hand-computed).
    #[test]
    fn one_step_from_rest_follows_the_spring() {
        let m = ImpedanceModel::default();
        let z = State::new(-1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let s = StepInput {
            u: Vector3::zeros(),
            f: Vector3::zeros(),
            goal: Vector3::zeros(),
            tau: 1.0,
            dt: 0.01,
        };
        let n = m.step(&z, &s);
        assert!((n[3] - 0.7825).abs() < 1e-12, "{n}");
        assert!((n[0] - (-1.0 + 0.007825)).abs() < 1e-12, "{n}");
        // The Jacobians reproduce the step from any state (the model is affine in z and u).
        let (a, b) = m.jacobians(1.0, 0.01);
        let z2 = State::new(0.3, -0.2, 0.1, 0.5, 0.0, -0.4);
        let u = Vector3::new(2.0, -1.0, 0.5);
        let s2 = StepInput { u, ..s };
        let d = m.step(&z2, &s2) - n - a * (z2 - z) - b * u;
        assert!(d.norm() < 1e-12, "{d}");
    }
}
