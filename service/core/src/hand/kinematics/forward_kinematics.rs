//! Forward kinematics of a [`KinematicTree`]: body poses for a joint vector, as MuJoCo's
//! `mj_kinematics` computes them (checked against MuJoCo 3.17 in `tests/kinematics.rs`).
//!
//! For each body, parents first: T_body = T_parent · P_body · J₁(q₁) · J₂(q₂) …, with P_body the
//! body's fixed pose and, per joint, J = Trans(a)·Rot(u, q − q_ref)·Trans(−a) for a hinge with
//! anchor a and unit axis u, J = Trans((q − q_ref)·u) for a slide (both in the body frame).

use super::kinematic_tree::{JointKind, KinematicTree};
use crate::error::FieldError;
use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};

/// A projection step that leaves more than this fraction of the least violation so far makes
/// no progress.
const STALL: f64 = 0.98;
/// The projection gives up after this many such steps in a row.
const STALLED_STEPS: usize = 3;

/// The result of forward kinematics, in the tree's root frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ForwardKinematics {
    /// Pose of every body, indexed like [`KinematicTree::bodies`].
    pub body_poses: Vec<Isometry3<f64>>,
    /// Per joint: its anchor and unit axis in the root frame (the columns of the Jacobian).
    pub joint_axes: Vec<(Point3<f64>, Unit<Vector3<f64>>)>,
}

impl ForwardKinematics {
    /// World position of a point given in body `body`'s frame.
    pub fn point(&self, body: usize, local: &Point3<f64>) -> Point3<f64> {
        self.body_poses[body] * local
    }
}

impl KinematicTree {
    /// Forward kinematics for the joint vector `q` (one value per joint, in `joints` order;
    /// radians for hinges, metres for slides). Values outside the limits are used as given.
    pub fn forward(&self, q: &[f64]) -> Result<ForwardKinematics, FieldError> {
        self.forward_below(q, None)
    }

    /// [`Self::forward`] at `q` when `base` is the forward kinematics at `q` but for joint
    /// `changed`: only the bodies it moves are posed again, the rest copied — the very values a
    /// full pass gives (a finite-difference Jacobian perturbs one joint at a time).
    pub fn forward_changed(
        &self,
        q: &[f64],
        base: &ForwardKinematics,
        changed: usize,
    ) -> Result<ForwardKinematics, FieldError> {
        self.forward_from(q, base, std::slice::from_ref(&changed))
    }

    /// [`Self::forward_changed`] for several changed joints (the closing sweep moves only the
    /// fingers that take part).
    pub fn forward_from(
        &self,
        q: &[f64],
        base: &ForwardKinematics,
        changed: &[usize],
    ) -> Result<ForwardKinematics, FieldError> {
        if base.body_poses.len() != self.bodies.len()
            || changed.iter().any(|&j| j >= self.joints.len())
        {
            return self.forward(q);
        }
        let mut own = vec![false; self.bodies.len()];
        for &j in changed {
            own[self.joints[j].body] = true;
        }
        self.forward_below(q, Some((base, &own)))
    }

    /// Forward kinematics; with `Some((base, own))`, only the bodies marked in `own` and those
    /// below them are posed, the others taken from `base`.
    fn forward_below(
        &self,
        q: &[f64],
        reuse: Option<(&ForwardKinematics, &[bool])>,
    ) -> Result<ForwardKinematics, FieldError> {
        if q.len() != self.joints.len() {
            return Err(FieldError::new(
                "joints",
                format!(
                    "expected {} joint values for '{}', got {}",
                    self.joints.len(),
                    self.name,
                    q.len()
                ),
            ));
        }
        if let Some(i) = q.iter().position(|v| !v.is_finite()) {
            return Err(FieldError::new(
                format!("joints[{}]", self.joints[i].name),
                "must be finite",
            ));
        }
        let mut body_poses = Vec::with_capacity(self.bodies.len());
        let mut joint_axes = match reuse {
            Some((base, _)) => base.joint_axes.clone(),
            None => vec![(Point3::origin(), Vector3::z_axis()); self.joints.len()],
        };
        // Per body, whether it is posed again (below a changed joint's body); only with `reuse`.
        let mut moved = vec![
            false;
            if reuse.is_some() {
                self.bodies.len()
            } else {
                0
            }
        ];
        for (i, b) in self.bodies.iter().enumerate() {
            if let Some((base, own)) = reuse {
                moved[i] = own[i] || b.parent.is_some_and(|p| moved[p]);
                if !moved[i] {
                    body_poses.push(base.body_poses[i]);
                    continue;
                }
            }
            let mut t = match b.parent {
                Some(p) => body_poses[p] * b.pose,
                None => b.pose,
            };
            for &ji in &b.joints {
                let j = &self.joints[ji];
                let value = q[ji] - j.reference;
                joint_axes[ji] = (
                    t * j.anchor,
                    Unit::new_unchecked(t.rotation * j.axis.into_inner()),
                );
                match j.kind {
                    JointKind::Hinge => {
                        let a = j.anchor.coords;
                        t = t
                            * Translation3::from(a)
                            * UnitQuaternion::from_axis_angle(&j.axis, value)
                            * Translation3::from(-a);
                    }
                    JointKind::Slide => {
                        t *= Translation3::from(j.axis.into_inner() * value);
                    }
                }
            }
            body_poses.push(t);
        }
        Ok(ForwardKinematics {
            body_poses,
            joint_axes,
        })
    }
}

impl KinematicTree {
    /// Whether joint `j` moves body `b` (sits on the path from the root to `b`).
    pub fn joint_moves(&self, j: usize, b: usize) -> bool {
        let jb = self.joints[j].body;
        let mut x = Some(b);
        while let Some(c) = x {
            if c == jb {
                return true;
            }
            x = self.bodies[c].parent;
        }
        false
    }

    /// The violation of the model's loop closures (m) and joint couplings (rad or m) at `q`: the
    /// norm of the stacked residuals. 0 for a model without either.
    pub fn constraint_violation(&self, q: &[f64]) -> Result<f64, FieldError> {
        let fk = self.forward(q)?;
        Ok(self.constraint_residual(&fk, q).norm())
    }

    fn constraint_residual(&self, fk: &ForwardKinematics, q: &[f64]) -> nalgebra::DVector<f64> {
        let m = 3 * self.loop_closures.len() + self.couplings.len();
        let mut r = nalgebra::DVector::zeros(m);
        for (k, lc) in self.loop_closures.iter().enumerate() {
            let d = fk.point(lc.body1, &lc.anchor1) - fk.point(lc.body2, &lc.anchor2);
            r.fixed_rows_mut::<3>(3 * k).copy_from(&d);
        }
        let base = 3 * self.loop_closures.len();
        for (k, c) in self.couplings.iter().enumerate() {
            let (j1, j2) = (&self.joints[c.joint1], &self.joints[c.joint2]);
            let d = q[c.joint2] - j2.reference;
            let poly = c
                .polycoef
                .iter()
                .rev()
                .fold(0.0, |acc, coef| acc * d + coef);
            r[base + k] = q[c.joint1] - j1.reference - poly;
        }
        r
    }

    /// Moves `q` to the nearest configuration (in the damped least-squares sense, starting from
    /// `q`) that satisfies the loop closures and joint couplings, keeping every joint in its
    /// limits: Δq = −Jᵀ(JJᵀ + λ²I)⁻¹ r, iterated. Returns the remaining violation; callers decide
    /// what is close enough (sampling drops configurations above 1 mm). A no-op without
    /// constraints.
    pub fn project_constraints(&self, q: &mut [f64]) -> Result<f64, FieldError> {
        self.project_constraints_holding(q, &[])
    }

    /// [`Self::project_constraints`] with the joints in `held` kept at their values (the driven
    /// joints of a linkage: the others follow them).
    pub fn project_constraints_holding(
        &self,
        q: &mut [f64],
        held: &[usize],
    ) -> Result<f64, FieldError> {
        if self.loop_closures.is_empty() && self.couplings.is_empty() {
            return Ok(0.0);
        }
        self.project_constraints_fk(q, held).map(|(v, _)| v)
    }

    /// [`Self::project_constraints_holding`] for a model with constraints, with the forward
    /// kinematics at the projected `q` (the last Newton step's when it converged: the closing
    /// sweep poses the hand at every projected configuration).
    pub fn project_constraints_fk(
        &self,
        q: &mut [f64],
        held: &[usize],
    ) -> Result<(f64, ForwardKinematics), FieldError> {
        let n = self.joints.len();
        let m = 3 * self.loop_closures.len() + self.couplings.len();
        // Per loop closure and side, which joints move its anchor (the Jacobian's non-zero
        // columns), found once rather than per Newton step.
        let moves: Vec<[Vec<bool>; 2]> = self
            .loop_closures
            .iter()
            .map(|lc| {
                [lc.body1, lc.body2].map(|b| {
                    (0..n)
                        .map(|j| !held.contains(&j) && self.joint_moves(j, b))
                        .collect()
                })
            })
            .collect();
        let (mut best, mut stalled) = (f64::INFINITY, 0);
        for _ in 0..60 {
            let fk = self.forward(q)?;
            let r = self.constraint_residual(&fk, q);
            let violation = r.norm();
            if violation < 1e-7 {
                return Ok((violation, fk));
            }
            // Steps that no longer reduce the violation: the constraints cannot be met inside
            // the limits from here (a driven joint past what the linkage reaches).
            if violation > STALL * best {
                stalled += 1;
                if stalled == STALLED_STEPS {
                    return Ok((violation, fk));
                }
            } else {
                (best, stalled) = (violation, 0);
            }
            let mut jac = nalgebra::DMatrix::zeros(m, n);
            let point_col = |moving: &[bool], p: &Point3<f64>, j: usize| -> Vector3<f64> {
                if !moving[j] {
                    return Vector3::zeros();
                }
                let (anchor, axis) = fk.joint_axes[j];
                match self.joints[j].kind {
                    JointKind::Hinge => axis.cross(&(p - anchor)),
                    JointKind::Slide => axis.into_inner(),
                }
            };
            for (k, lc) in self.loop_closures.iter().enumerate() {
                let p1 = fk.point(lc.body1, &lc.anchor1);
                let p2 = fk.point(lc.body2, &lc.anchor2);
                for j in 0..n {
                    let col = point_col(&moves[k][0], &p1, j) - point_col(&moves[k][1], &p2, j);
                    jac.fixed_view_mut::<3, 1>(3 * k, j).copy_from(&col);
                }
            }
            let base = 3 * self.loop_closures.len();
            for (k, c) in self.couplings.iter().enumerate() {
                let d = q[c.joint2] - self.joints[c.joint2].reference;
                let p = &c.polycoef;
                let slope = p[1] + 2.0 * p[2] * d + 3.0 * p[3] * d * d + 4.0 * p[4] * d * d * d;
                if !held.contains(&c.joint1) {
                    jac[(base + k, c.joint1)] += 1.0;
                }
                if !held.contains(&c.joint2) {
                    jac[(base + k, c.joint2)] -= slope;
                }
            }
            // A joint at a limit that the step would push beyond it takes no part in the step
            // (its column dropped, the step solved again): clamping it instead lets only part of
            // each step through, and the iteration crawls (the 2F-85's linkage: 7 steps on
            // average, up to 60, where Newton needs 2–3).
            let mut dq = nalgebra::DVector::zeros(n);
            for _ in 0..n {
                let a = &jac * jac.transpose() + nalgebra::DMatrix::identity(m, m) * 1e-8;
                let Some(w) = a.lu().solve(&r) else { break };
                dq = -(jac.transpose() * w);
                let blocked: Vec<usize> = (0..n)
                    .filter(|&j| {
                        let (lo, hi) = self.joints[j].limits();
                        (q[j] <= lo && dq[j] < 0.0) || (q[j] >= hi && dq[j] > 0.0)
                    })
                    .collect();
                if blocked.is_empty() {
                    break;
                }
                for j in blocked {
                    jac.column_mut(j).fill(0.0);
                }
            }
            for (j, v) in q.iter_mut().enumerate() {
                let (lo, hi) = self.joints[j].limits();
                *v = (*v + dq[j]).clamp(lo, hi);
            }
        }
        let fk = self.forward(q)?;
        Ok((self.constraint_residual(&fk, q).norm(), fk))
    }
}
