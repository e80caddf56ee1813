//! Forward kinematics of a [`KinematicTree`]: body poses for a joint vector, as MuJoCo's
//! `mj_kinematics` computes them (checked against MuJoCo 3.17 in `tests/kinematics.rs`).
//!
//! For each body, parents first: T_body = T_parent · P_body · J₁(q₁) · J₂(q₂) …, with P_body the
//! body's fixed pose and, per joint, J = Trans(a)·Rot(u, q − q_ref)·Trans(−a) for a hinge with
//! anchor a and unit axis u, J = Trans((q − q_ref)·u) for a slide (both in the body frame).

use super::kinematic_tree::{JointKind, KinematicTree};
use crate::error::FieldError;
use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};

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
        let mut joint_axes = vec![(Point3::origin(), Vector3::z_axis()); self.joints.len()];
        for b in &self.bodies {
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
