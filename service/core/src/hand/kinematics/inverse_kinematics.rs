//! Per-finger inverse kinematics by damped least squares (method.md §3, the Eq 3.11 form).
//!
//! For a finger with joints q (its chain from the palm), contact point p(q) in the hand frame and
//! target x*, each iteration takes
//!
//!   Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e,   e = x* − p(q),
//!
//! with J = ∂p/∂q the 3 × n positional Jacobian (hinge column u × (p − a) for axis u through
//! anchor a, slide column u), limits the step to `max_step` (norm), and clamps q into the joint
//! limits. The damping λ (metres) keeps the step bounded near singular configurations (a
//! stretched finger) and for unreachable targets, where the iteration settles on the nearest
//! reachable point instead of diverging. A start from `q0`, then seeded random restarts inside
//! the limits, are tried until the residual is below `tolerance / 4`; the best is returned. A
//! target farther from the finger's base than its reach bound ([`KinematicFinger::reach`]) gets
//! no restarts: it is unreachable whatever the start.
//! Joints outside the finger's chain keep their `q0` values.
//!
//! Coupled joints (the Shadow hand's J1/J2 tendons, the Robotiq 2F-85's linkage) are solved as
//! independent joints: the result is a valid FK configuration of the tree, not necessarily one
//! the actuators can hold.

#[cfg(doc)]
use super::hand_model::KinematicFinger;
use super::hand_model::KinematicHand;
use super::kinematic_tree::JointKind;
use crate::error::FieldError;
use nalgebra::{DMatrix, DVector, Matrix3, Point3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Settings of the damped-least-squares solver.
#[derive(Debug, Clone, PartialEq)]
pub struct IkOptions {
    /// λ of Eq 3.11, m.
    pub damping: f64,
    /// A target is reachable when the residual is at most this, m.
    pub tolerance: f64,
    /// Iterations per start.
    pub max_iterations: usize,
    /// Random restarts after the start from q0.
    pub restarts: usize,
    /// Largest joint step per iteration (Euclidean norm over the chain; rad or m).
    pub max_step: f64,
    /// Seed of the restarts.
    pub seed: u64,
}

impl Default for IkOptions {
    fn default() -> Self {
        Self {
            damping: 0.005,
            tolerance: 0.002,
            max_iterations: 100,
            restarts: 12,
            max_step: 0.3,
            seed: 0x1c_3a11,
        }
    }
}

/// The solution for one finger.
#[derive(Debug, Clone, PartialEq)]
pub struct FingerIk {
    /// The whole joint vector: the finger's joints solved, the others as in q0.
    pub joints: Vec<f64>,
    /// Distance from the reached contact point to the target, m.
    pub residual: f64,
    /// `residual ≤ tolerance`.
    pub reachable: bool,
}

/// One contact to reach: a finger's contact point at a position in the hand frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactTarget {
    pub finger: usize,
    pub position: Point3<f64>,
}

/// The solution for several contacts at once.
#[derive(Debug, Clone, PartialEq)]
pub struct HandIk {
    pub joints: Vec<f64>,
    /// Per contact, in the order given, m.
    pub residuals: Vec<f64>,
    /// Every contact within the tolerance.
    pub reachable: bool,
}

impl KinematicHand {
    /// Joints that put finger `finger`'s contact point at `target` (hand frame), starting from
    /// `q0`, with the default [`IkOptions`].
    pub fn inverse(
        &self,
        finger: usize,
        target: &Point3<f64>,
        q0: &[f64],
    ) -> Result<FingerIk, FieldError> {
        self.inverse_with(finger, target, q0, &IkOptions::default())
    }

    /// As [`Self::inverse`] with explicit options.
    pub fn inverse_with(
        &self,
        finger: usize,
        target: &Point3<f64>,
        q0: &[f64],
        opts: &IkOptions,
    ) -> Result<FingerIk, FieldError> {
        let f = self.fingers.get(finger).ok_or_else(|| {
            FieldError::new(
                "finger",
                format!(
                    "finger index {finger} out of range (the hand has {})",
                    self.fingers.len()
                ),
            )
        })?;
        if target.coords.iter().any(|v| !v.is_finite()) {
            return Err(FieldError::new("target", "must be finite"));
        }
        let mut q = q0.to_vec();
        self.tree.forward(&q)?; // length and finiteness check
        self.tree.clamp(&mut q);
        let mut rng =
            ChaCha8Rng::seed_from_u64(opts.seed ^ (finger as u64).wrapping_mul(0x9e37_79b9));
        let (mut best_q, mut best_r) = self.solve_from(finger, target, q.clone(), opts);
        // Beyond the chain's reach no restart can help: keep the start from q0's best effort.
        let base = self.hand_frame.inverse() * self.finger_bases_in_palm_one(finger, &q);
        let hopeless = (target - base).norm() > f.reach + opts.tolerance;
        let restarts = if hopeless { 0 } else { opts.restarts };
        for _ in 0..restarts {
            if best_r <= 0.25 * opts.tolerance {
                break;
            }
            let mut start = q.clone();
            for &j in &f.joints {
                let (lo, hi) = self.tree.joints[j].limits();
                start[j] = if hi > lo {
                    rng.random_range(lo..=hi)
                } else {
                    lo
                };
            }
            let (qs, r) = self.solve_from(finger, target, start, opts);
            if r < best_r {
                best_q = qs;
                best_r = r;
            }
        }
        Ok(FingerIk {
            joints: best_q,
            residual: best_r,
            reachable: best_r <= opts.tolerance,
        })
    }

    /// Solves several contacts, one finger after the other (each finger's chain is independent
    /// of the others'). A finger may appear only once.
    pub fn inverse_contacts(
        &self,
        targets: &[ContactTarget],
        q0: &[f64],
        opts: &IkOptions,
    ) -> Result<HandIk, FieldError> {
        let mut q = q0.to_vec();
        let mut residuals = Vec::with_capacity(targets.len());
        for (i, t) in targets.iter().enumerate() {
            if targets[..i].iter().any(|o| o.finger == t.finger) {
                return Err(FieldError::new(
                    format!("contacts[{i}].finger"),
                    format!("finger {} has two contacts", t.finger),
                ));
            }
            let r = self
                .inverse_with(t.finger, &t.position, &q, opts)
                .map_err(|e| FieldError::new(format!("contacts[{i}].{}", e.field), e.message))?;
            q = r.joints;
            residuals.push(r.residual);
        }
        let reachable = residuals.iter().all(|r| *r <= opts.tolerance);
        Ok(HandIk {
            joints: q,
            residuals,
            reachable,
        })
    }

    /// The anchor of finger `finger`'s first joint in the palm body's frame (fixed relative to
    /// the palm: no joint of the finger moves it).
    fn finger_bases_in_palm_one(&self, finger: usize, q: &[f64]) -> Point3<f64> {
        let fk = self.tree.forward(q).expect("checked joint vector");
        let j = self.fingers[finger].joints[0];
        fk.body_poses[self.palm].inverse() * fk.joint_axes[j].0
    }

    /// The contact point of finger `finger` and its Jacobian over the finger's joints, both in
    /// the hand frame.
    fn point_and_jacobian(&self, finger: usize, q: &[f64]) -> (Point3<f64>, DMatrix<f64>) {
        let fk = self.tree.forward(q).expect("checked joint vector");
        self.point_and_jacobian_at(finger, &fk)
    }

    /// [`Self::point_and_jacobian`] from a forward-kinematics result (one FK for many fingers).
    fn point_and_jacobian_at(
        &self,
        finger: usize,
        fk: &super::ForwardKinematics,
    ) -> (Point3<f64>, DMatrix<f64>) {
        let f = &self.fingers[finger];
        let to_hand = (fk.body_poses[self.palm] * self.hand_frame).inverse();
        let p_root = fk.body_poses[f.tip] * f.tip_point;
        let mut jac = DMatrix::zeros(3, f.joints.len());
        for (c, &j) in f.joints.iter().enumerate() {
            let (anchor, axis) = fk.joint_axes[j];
            let col_root: Vector3<f64> = match self.tree.joints[j].kind {
                JointKind::Hinge => axis.cross(&(p_root - anchor)),
                JointKind::Slide => axis.into_inner(),
            };
            jac.set_column(c, &(to_hand.rotation * col_root));
        }
        (to_hand * p_root, jac)
    }

    fn solve_from(
        &self,
        finger: usize,
        target: &Point3<f64>,
        mut q: Vec<f64>,
        opts: &IkOptions,
    ) -> (Vec<f64>, f64) {
        let joints = &self.fingers[finger].joints;
        let lambda2 = opts.damping * opts.damping;
        let mut best = (q.clone(), f64::INFINITY);
        let mut stalled = 0;
        for it in 0..=opts.max_iterations {
            let (p, jac) = self.point_and_jacobian(finger, &q);
            let e = target - p;
            let r = e.norm();
            if r < best.1 - 1e-7 {
                stalled = 0;
            } else {
                stalled += 1;
            }
            if r < best.1 {
                best = (q.clone(), r);
            }
            if r < 1e-5 || stalled >= 8 || it == opts.max_iterations {
                break;
            }
            // Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e  (Eq 3.11 form).
            let jjt: Matrix3<f64> = (&jac * jac.transpose())
                .fixed_view::<3, 3>(0, 0)
                .into_owned()
                + Matrix3::identity() * lambda2;
            let Some(inv) = jjt.try_inverse() else { break };
            let w = inv * e;
            let mut dq: DVector<f64> = jac.transpose() * DVector::from_column_slice(w.as_slice());
            let n = dq.norm();
            if n > opts.max_step {
                dq *= opts.max_step / n;
            }
            for (k, &j) in joints.iter().enumerate() {
                let (lo, hi) = self.tree.joints[j].limits();
                q[j] = (q[j] + dq[k]).clamp(lo, hi);
            }
        }
        best
    }
}

/// How far [`KinematicHand::inverse_with_palm`] may move the palm from its given pose.
#[derive(Debug, Clone, PartialEq)]
pub struct PalmFreedom {
    /// Largest translation of the hand frame, m.
    pub max_translation: f64,
    /// Largest rotation of the hand frame, rad.
    pub max_rotation: f64,
    /// Weight of a palm motion against a joint motion in the least-squares step (< 1 makes the
    /// solver prefer moving the fingers): palm columns of J are scaled by it.
    pub weight: f64,
}

impl Default for PalmFreedom {
    fn default() -> Self {
        Self {
            max_translation: 0.02,
            max_rotation: 0.25,
            weight: 0.5,
        }
    }
}

/// The solution of [`KinematicHand::inverse_with_palm`].
#[derive(Debug, Clone, PartialEq)]
pub struct PalmIk {
    /// Where the hand frame should be, expressed in the given (initial) hand frame: the new hand
    /// pose is `initial_pose * palm_correction`.
    pub palm_correction: nalgebra::Isometry3<f64>,
    pub joints: Vec<f64>,
    /// Per contact, in the order given, m.
    pub residuals: Vec<f64>,
    pub reachable: bool,
}

impl KinematicHand {
    /// Contacts reached jointly by the fingers and a bounded correction of the palm pose
    /// (issue 6 §2): the fingers' joints and a rigid motion T of the hand frame are solved
    /// together by damped least squares over the stacked contacts, e_k = x*_k − T·p_k(q),
    /// with the Jacobian [I, −[T·p_k]ₓ | R·J_k] (palm translation, palm rotation about the hand
    /// origin, finger joints), palm columns weighted by `palm.weight`. Joints are clamped into
    /// their limits, T into `palm`'s bounds. Targets are in the initial hand frame. Starts from
    /// q0 and from `opts.restarts` seeded random finger configurations until every residual is
    /// below the tolerance; the start with the least largest residual wins.
    pub fn inverse_with_palm(
        &self,
        targets: &[ContactTarget],
        q0: &[f64],
        opts: &IkOptions,
        palm: &PalmFreedom,
    ) -> Result<PalmIk, FieldError> {
        for (i, t) in targets.iter().enumerate() {
            if t.finger >= self.fingers.len() {
                return Err(FieldError::new(
                    format!("contacts[{i}].finger"),
                    format!("finger index {} out of range", t.finger),
                ));
            }
            if targets[..i].iter().any(|o| o.finger == t.finger) {
                return Err(FieldError::new(
                    format!("contacts[{i}].finger"),
                    format!("finger {} has two contacts", t.finger),
                ));
            }
            if t.position.coords.iter().any(|v| !v.is_finite()) {
                return Err(FieldError::new(
                    format!("contacts[{i}].position"),
                    "must be finite",
                ));
            }
        }
        let mut q = q0.to_vec();
        self.tree.forward(&q)?;
        self.tree.clamp(&mut q);
        let mut rng = ChaCha8Rng::seed_from_u64(opts.seed ^ 0x9a1d);
        let mut best = self.solve_with_palm(targets, q.clone(), opts, palm);
        for _ in 0..opts.restarts {
            if best.residuals.iter().all(|r| *r <= 0.25 * opts.tolerance) {
                break;
            }
            let mut start = q.clone();
            for t in targets {
                for &j in &self.fingers[t.finger].joints {
                    let (lo, hi) = self.tree.joints[j].limits();
                    start[j] = if hi > lo {
                        rng.random_range(lo..=hi)
                    } else {
                        lo
                    };
                }
            }
            let s = self.solve_with_palm(targets, start, opts, palm);
            let worst = |r: &PalmIk| r.residuals.iter().cloned().fold(0.0, f64::max);
            if worst(&s) < worst(&best) {
                best = s;
            }
        }
        best.reachable = best.residuals.iter().all(|r| *r <= opts.tolerance);
        Ok(best)
    }

    fn solve_with_palm(
        &self,
        targets: &[ContactTarget],
        mut q: Vec<f64>,
        opts: &IkOptions,
        palm: &PalmFreedom,
    ) -> PalmIk {
        use nalgebra::{Isometry3, Translation3, UnitQuaternion};
        let cols: Vec<usize> = targets
            .iter()
            .flat_map(|t| self.fingers[t.finger].joints.iter().copied())
            .collect();
        let m = 3 * targets.len();
        let n = 6 + cols.len();
        let mut t_palm = Isometry3::<f64>::identity();
        let evaluate = |q: &[f64], t_palm: &Isometry3<f64>| -> Vec<(Point3<f64>, DMatrix<f64>)> {
            let fk = self.tree.forward(q).expect("checked joint vector");
            targets
                .iter()
                .map(|t| {
                    let (p, j) = self.point_and_jacobian_at(t.finger, &fk);
                    (t_palm * p, j)
                })
                .collect()
        };
        let mut col_of = std::collections::HashMap::new();
        for (c, &j) in cols.iter().enumerate() {
            col_of.insert(j, 6 + c);
        }
        let mut best: Option<(f64, PalmIk)> = None;
        let mut stalled = 0;
        for it in 0..=opts.max_iterations {
            let points = evaluate(&q, &t_palm);
            let residuals: Vec<f64> = targets
                .iter()
                .zip(&points)
                .map(|(t, (p, _))| (t.position - p).norm())
                .collect();
            let total = residuals.iter().map(|r| r * r).sum::<f64>().sqrt();
            // Converged well inside the tolerance, or stalled (no gain of 1 µm in 10 steps).
            let converged = residuals.iter().all(|r| *r <= 0.05 * opts.tolerance);
            if best.as_ref().is_none_or(|b| total < b.0 - 1e-6) {
                stalled = 0;
            } else {
                stalled += 1;
            }
            if best.as_ref().is_none_or(|b| total < b.0) {
                best = Some((
                    total,
                    PalmIk {
                        palm_correction: t_palm,
                        joints: q.clone(),
                        residuals,
                        reachable: false,
                    },
                ));
            }
            if total < 1e-5 || converged || stalled >= 10 || it == opts.max_iterations {
                break;
            }
            let mut jac = DMatrix::zeros(m, n);
            let mut e = DVector::zeros(m);
            for (k, (t, (p, jk))) in targets.iter().zip(&points).enumerate() {
                let d = t.position - p;
                e.fixed_rows_mut::<3>(3 * k).copy_from(&d);
                let w = palm.weight;
                for a in 0..3 {
                    jac[(3 * k + a, a)] = w;
                }
                // d(ω × p)/dω = −[p]ₓ
                let px = p.coords.cross_matrix();
                jac.view_mut((3 * k, 3), (3, 3)).copy_from(&(-px * w));
                let rot = t_palm.rotation.to_rotation_matrix();
                for (c, &j) in self.fingers[t.finger].joints.iter().enumerate() {
                    let col = rot * jk.fixed_view::<3, 1>(0, c).into_owned();
                    jac.fixed_view_mut::<3, 1>(3 * k, col_of[&j])
                        .copy_from(&col);
                }
            }
            let a =
                &jac * jac.transpose() + DMatrix::identity(m, m) * (opts.damping * opts.damping);
            let Some(w) = a.lu().solve(&e) else { break };
            let mut dx = jac.transpose() * w;
            let norm = dx.norm();
            if norm > opts.max_step {
                dx *= opts.max_step / norm;
            }
            let v = Vector3::new(dx[0], dx[1], dx[2]) * palm.weight;
            let omega = Vector3::new(dx[3], dx[4], dx[5]) * palm.weight;
            let step = Isometry3::from_parts(
                Translation3::from(v),
                UnitQuaternion::from_scaled_axis(omega),
            );
            t_palm = step * t_palm;
            // Keep the correction inside its bounds.
            let tr = t_palm.translation.vector;
            if tr.norm() > palm.max_translation {
                t_palm.translation.vector = tr * (palm.max_translation / tr.norm());
            }
            let angle = t_palm.rotation.angle();
            if angle > palm.max_rotation {
                let axis = t_palm.rotation.axis().expect("non-zero angle");
                t_palm.rotation = UnitQuaternion::from_axis_angle(&axis, palm.max_rotation);
            }
            for (c, &j) in cols.iter().enumerate() {
                let (lo, hi) = self.tree.joints[j].limits();
                q[j] = (q[j] + dx[6 + c]).clamp(lo, hi);
            }
        }
        best.expect("at least one evaluation").1
    }
}
