//! The inverse model's update (§3.3.2, Eq 3.13–3.18): iterative LQR over an H-step horizon of
//! the impedance model, with the reach's costs — the robot's control (Eq 3.14's uᵀRu), the
//! obstacles and the table as penalties that act inside a safety distance (the soft constraint
//! of Eq 3.15), and, when the horizon reaches the end of the reach, the end point and rest
//! there (Eq 3.14's Q1 and Q2 terms at i = T).
//!
//! Eq 3.15 as printed weights an obstacle's distance by a Gaussian in time about a time t_p
//! the text never fixes; here the penalty is (d_safe − d)² wherever the hand's clearance d is
//! below d_safe, at every step, which needs no timing and is zero away from the obstacles. The
//! model is linear, so F_xx = F_ux = F_uu = 0 in the recursion; the penalties' Hessians are
//! Gauss–Newton (2∇d∇dᵀ). Controls come from the feedback law δu = K δz + k (Eq 3.17) with a
//! backtracking line search on k; Q_uu is regularised when it loses definiteness.

use super::impedance::{ImpedanceModel, State, StepInput};
use super::obstacles::Scene;
use nalgebra::{Matrix3, Matrix6, Point3, SMatrix, Vector3, Vector6};
use std::ops::AddAssign;

/// The reach's cost (module doc).
#[derive(Debug, Clone)]
pub struct ReachCost<'a> {
    pub scene: &'a Scene,
    /// R of Eq 3.14 (isotropic), per N².
    pub control: f64,
    /// Weight of a penalty, per m².
    pub penalty: f64,
    /// Clearance to an obstacle (beyond the hand's radius) under which its penalty acts, m.
    pub safe_distance: f64,
    /// Height above the table under which its penalty acts, m.
    pub table_margin: f64,
    /// The end point of the reach, with Q1 (per m²) and Q2 (per (m/s)²) of Eq 3.14.
    pub end: Point3<f64>,
    pub end_position: f64,
    pub end_velocity: f64,
}

type Gradient = Vector6<f64>;
type Hessian = Matrix6<f64>;

impl ReachCost<'_> {
    /// Penalty terms at state z: value, gradient and Gauss–Newton Hessian.
    fn penalties(&self, z: &State) -> (f64, Gradient, Hessian) {
        let p = Point3::from(z.fixed_rows::<3>(0).into_owned());
        let (mut c, mut g, mut h) = (0.0, Gradient::zeros(), Hessian::zeros());
        let mut add = |gap: f64, dir: Vector3<f64>| {
            if gap > 0.0 {
                c += self.penalty * gap * gap;
                let gx = -2.0 * self.penalty * gap * dir;
                g.fixed_rows_mut::<3>(0).add_assign(&gx);
                let hx = 2.0 * self.penalty * dir * dir.transpose();
                h.fixed_view_mut::<3, 3>(0, 0).add_assign(&hx);
            }
        };
        for o in &self.scene.obstacles {
            let (d, dir) = o.distance(&p);
            add(self.safe_distance - (d - self.scene.hand_radius), dir);
        }
        if let Some(t) = self.scene.table {
            add(self.table_margin - t.distance(&p), t.normal);
        }
        (c, g, h)
    }

    /// Running cost of one step.
    fn running(&self, z: &State, u: &Vector3<f64>) -> f64 {
        self.control * u.norm_squared() + self.penalties(z).0
    }

    /// Cost at the end of the reach.
    fn terminal(&self, z: &State) -> (f64, Gradient, Hessian) {
        let (mut c, mut g, mut h) = self.penalties(z);
        let dx = z.fixed_rows::<3>(0) - self.end.coords;
        let v = z.fixed_rows::<3>(3);
        c += self.end_position * dx.norm_squared() + self.end_velocity * v.norm_squared();
        g.fixed_rows_mut::<3>(0)
            .add_assign(&(2.0 * self.end_position * dx));
        g.fixed_rows_mut::<3>(3)
            .add_assign(&(2.0 * self.end_velocity * v));
        let i = Matrix3::<f64>::identity();
        h.fixed_view_mut::<3, 3>(0, 0)
            .add_assign(&(2.0 * self.end_position * i));
        h.fixed_view_mut::<3, 3>(3, 3)
            .add_assign(&(2.0 * self.end_velocity * i));
        (c, g, h)
    }
}

/// Iterations of one horizon's optimisation.
const ITERATIONS: usize = 12;

/// The horizon's controls that minimise the cost from `z0` (Eq 3.13), starting from `u`.
/// `steps` are the horizon's inputs but u; `ends` says whether its last state is the reach's
/// end (then the end cost applies to it).
pub fn optimise(
    model: &ImpedanceModel,
    steps: &[StepInput],
    z0: &State,
    mut u: Vec<Vector3<f64>>,
    cost: &ReachCost,
    ends: bool,
) -> Vec<Vector3<f64>> {
    let h = steps.len();
    if h == 0 {
        return u;
    }
    let (a, b) = model.jacobians(steps[0].tau, steps[0].dt);
    let rollout = |u: &[Vector3<f64>]| -> (Vec<State>, f64) {
        let mut zs = Vec::with_capacity(h + 1);
        zs.push(*z0);
        let mut total = 0.0;
        for (s, ui) in steps.iter().zip(u) {
            let z = zs.last().expect("started");
            total += cost.running(z, ui);
            zs.push(model.step(z, &StepInput { u: *ui, ..*s }));
        }
        let last = zs.last().expect("started");
        total += if ends {
            cost.terminal(last).0
        } else {
            cost.penalties(last).0
        };
        (zs, total)
    };
    let (mut zs, mut best) = rollout(&u);
    let mut mu = 0.0;
    for _ in 0..ITERATIONS {
        // Backward pass (Eq 3.16–3.17 and the recursion above them).
        let last = &zs[h];
        let (_, mut vx, mut vxx) = if ends {
            cost.terminal(last)
        } else {
            cost.penalties(last)
        };
        let mut gains: Vec<(SMatrix<f64, 3, 6>, Vector3<f64>)> = vec![Default::default(); h];
        let mut ok = true;
        for i in (0..h).rev() {
            let (_, lx, lxx) = cost.penalties(&zs[i]);
            let lu = 2.0 * cost.control * u[i];
            let qx = lx + a.transpose() * vx;
            let qu = lu + b.transpose() * vx;
            let qxx = lxx + a.transpose() * vxx * a;
            let quu = Matrix3::identity() * (2.0 * cost.control + mu) + b.transpose() * vxx * b;
            let qux = b.transpose() * vxx * a;
            let Some(inv) = quu.try_inverse() else {
                ok = false;
                break;
            };
            let k_fb = -inv * qux;
            let k_ff = -inv * qu;
            vx =
                qx + k_fb.transpose() * quu * k_ff + k_fb.transpose() * qu + qux.transpose() * k_ff;
            vxx = qxx
                + k_fb.transpose() * quu * k_fb
                + k_fb.transpose() * qux
                + qux.transpose() * k_fb;
            vxx = 0.5 * (vxx + vxx.transpose());
            gains[i] = (k_fb, k_ff);
        }
        if !ok {
            mu = (mu * 10.0).max(1e-6);
            continue;
        }
        // Forward pass with a line search (Eq 3.18's mean).
        let mut improved = false;
        for alpha in [1.0, 0.5, 0.25, 0.1, 0.03] {
            let mut z = *z0;
            let mut un = Vec::with_capacity(h);
            for i in 0..h {
                let (k_fb, k_ff) = &gains[i];
                let ui = u[i] + alpha * k_ff + k_fb * (z - zs[i]);
                un.push(ui);
                z = model.step(&z, &StepInput { u: ui, ..steps[i] });
            }
            let (zn, c) = rollout(&un);
            if c < best {
                let gain = best - c;
                (u, zs, best) = (un, zn, c);
                improved = gain > 1e-9 * best.abs().max(1e-9);
                break;
            }
        }
        if !improved {
            break;
        }
    }
    u
}
