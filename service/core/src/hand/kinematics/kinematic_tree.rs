//! The one kinematic-tree type that both MJCF and URDF documents are read into.
//!
//! Conventions follow MuJoCo, so that forward kinematics reproduces `mj_kinematics`:
//! - bodies are stored parents first; `bodies[0]` is the root (MJCF: the `world` body; URDF: the
//!   root link), posed at the identity;
//! - each body has a fixed pose relative to its parent, then zero or more joints applied in order
//!   (a URDF joint becomes the child link's single joint with its anchor at the child origin);
//! - a hinge rotates by `q − reference` about `axis` through `anchor`, a slide translates by
//!   `(q − reference)·axis`, both expressed in the body frame;
//! - the joint vector `q` lists the joints in `joints` order, which is MuJoCo's qpos order for an
//!   MJCF model made of hinges and slides (document order) and the document order of the movable
//!   joints for a URDF.

use crate::error::FieldError;
use nalgebra::{Isometry3, Point3, Unit, Vector3};
use std::f64::consts::PI;
use std::path::PathBuf;
use std::sync::Arc;

/// A joint's degree of freedom.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Revolute: rotation about the axis, radians (MJCF `hinge`, URDF `revolute`/`continuous`).
    Hinge,
    /// Prismatic: translation along the axis, metres (MJCF `slide`, URDF `prismatic`).
    Slide,
}

/// One movable joint.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub name: String,
    pub kind: JointKind,
    /// The body this joint moves (relative to its parent).
    pub body: usize,
    /// Point on the axis, in the body frame (m).
    pub anchor: Point3<f64>,
    /// Unit axis in the body frame.
    pub axis: Unit<Vector3<f64>>,
    /// Joint limits `(lower, upper)` in radians or metres; `None` when the joint is unlimited.
    pub range: Option<(f64, f64)>,
    /// The joint value at which the body sits at its modelled pose (MJCF `ref`, else 0).
    pub reference: f64,
    /// The most torque (N·m; force, N, for a slide) its actuators can apply, when they are
    /// force-limited: MJCF actuator `forcerange` × gear (through a fixed tendon × the joint's
    /// coefficient) or the joint's `actuatorfrcrange`, URDF `<limit effort>`. None when the
    /// model sets no limit or drives the joint with no actuator.
    pub effort: Option<f64>,
}

impl Joint {
    /// Limits used for sampling, clamping and IK: `range`, or `[−π, π]` for an unlimited hinge and
    /// `[−0.1, 0.1]` m for an unlimited slide.
    pub fn limits(&self) -> (f64, f64) {
        self.range.unwrap_or(match self.kind {
            JointKind::Hinge => (-PI, PI),
            JointKind::Slide => (-0.1, 0.1),
        })
    }
}

/// Shape of a geom, with MuJoCo's size conventions (half sizes, radius then half length).
#[derive(Debug, Clone, PartialEq)]
pub enum GeomShape {
    Sphere {
        radius: f64,
    },
    /// Axis along the geom's z.
    Capsule {
        radius: f64,
        half_length: f64,
    },
    /// Axis along the geom's z.
    Cylinder {
        radius: f64,
        half_length: f64,
    },
    Box {
        half_extents: Vector3<f64>,
    },
    Ellipsoid {
        radii: Vector3<f64>,
    },
    Plane,
    /// A triangle mesh from a file; `vertices` are loaded (scaled, in the geom frame) for
    /// collision geoms and left empty for visual-only ones.
    Mesh {
        name: String,
        file: Option<PathBuf>,
        vertices: Arc<Vec<Point3<f64>>>,
    },
}

/// A collision or visual shape attached to a body.
#[derive(Debug, Clone, PartialEq)]
pub struct Geom {
    pub name: Option<String>,
    pub shape: GeomShape,
    /// Pose in the body frame.
    pub pose: Isometry3<f64>,
    /// Whether the geom takes part in collisions (MJCF contype/conaffinity not both 0; URDF
    /// `<collision>`).
    pub collision: bool,
}

/// A named point/frame on a body (MJCF `<site>`).
#[derive(Debug, Clone, PartialEq)]
pub struct Site {
    pub name: String,
    pub pose: Isometry3<f64>,
}

/// A rigid body (MJCF body, URDF link).
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    pub name: String,
    pub parent: Option<usize>,
    pub children: Vec<usize>,
    /// Pose relative to the parent at q = reference.
    pub pose: Isometry3<f64>,
    /// Indices into [`KinematicTree::joints`], applied in this order.
    pub joints: Vec<usize>,
    pub geoms: Vec<Geom>,
    pub sites: Vec<Site>,
}

/// Two bodies tied together at a point by a constraint of the model (MJCF
/// `<equality><connect>`, or the position part of a `<weld>`), closing a kinematic loop: the
/// point `anchor1` of body1 must coincide with the point `anchor2` of body2. As in MuJoCo,
/// `anchor2` is where `anchor1` lies in body2's frame at the reference configuration (qpos0).
///
/// Forward kinematics ignores closures (as `mj_kinematics` does). Finger detection uses them to
/// recognise linkage bars, and workspace sampling projects configurations onto them
/// ([`KinematicTree::project_constraints`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LoopClosure {
    pub body1: usize,
    pub body2: usize,
    pub anchor1: Point3<f64>,
    pub anchor2: Point3<f64>,
}

/// A joint whose value follows another's (MJCF `<equality><joint>`): with q₀ the reference
/// values, q₁ − q₁₀ = c₀ + c₁ d + c₂ d² + c₃ d³ + c₄ d⁴, d = q₂ − q₂₀.
#[derive(Debug, Clone, PartialEq)]
pub struct JointCoupling {
    pub joint1: usize,
    pub joint2: usize,
    pub polycoef: [f64; 5],
}

/// A kinematic tree of bodies and hinge/slide joints.
#[derive(Debug, Clone, PartialEq)]
pub struct KinematicTree {
    /// Model name (MJCF `model`, URDF `name`).
    pub name: String,
    pub bodies: Vec<Body>,
    pub joints: Vec<Joint>,
    pub loop_closures: Vec<LoopClosure>,
    pub couplings: Vec<JointCoupling>,
}

impl KinematicTree {
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }

    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Degrees of freedom (length of the joint vector).
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Bodies from `ancestor` (exclusive) down to `body` (inclusive), or `None` when `ancestor`
    /// is not an ancestor of `body`.
    pub fn path(&self, ancestor: usize, body: usize) -> Option<Vec<usize>> {
        let mut path = Vec::new();
        let mut b = body;
        while b != ancestor {
            path.push(b);
            b = self.bodies[b].parent?;
        }
        path.reverse();
        Some(path)
    }

    /// The reference configuration (MuJoCo's qpos0): every joint at its reference value.
    pub fn reference_configuration(&self) -> Vec<f64> {
        self.joints.iter().map(|j| j.reference).collect()
    }

    /// The modelled ("home") pose: the reference configuration clamped into the limits. Hand
    /// models are drawn open in it.
    pub fn home_configuration(&self) -> Vec<f64> {
        let mut q = self.reference_configuration();
        self.clamp(&mut q);
        q
    }

    /// A joint vector at the middle of every joint's limits.
    pub fn mid_configuration(&self) -> Vec<f64> {
        self.joints
            .iter()
            .map(|j| {
                let (lo, hi) = j.limits();
                0.5 * (lo + hi)
            })
            .collect()
    }

    /// Clamps each joint value into its limits.
    pub fn clamp(&self, q: &mut [f64]) {
        for (v, j) in q.iter_mut().zip(&self.joints) {
            let (lo, hi) = j.limits();
            *v = v.clamp(lo, hi);
        }
    }

    /// Checks the structural rules every tree must meet: parents before children, consistent
    /// child lists, unique body and joint names, and sane joint limits (see [`check_limits`]).
    /// `field` prefixes the error field (`hand.mjcf`, `hand.urdf`).
    pub fn validate(&self, field: &str) -> Result<(), FieldError> {
        if self.bodies.is_empty() || self.bodies[0].parent.is_some() {
            return Err(FieldError::new(field, "the tree has no root body"));
        }
        for (i, b) in self.bodies.iter().enumerate() {
            if i > 0 && b.parent.is_none_or(|p| p >= i) {
                return Err(FieldError::new(
                    field,
                    format!("body '{}' is not below the root", b.name),
                ));
            }
            if self.bodies[..i].iter().any(|o| o.name == b.name) {
                return Err(FieldError::new(
                    format!("{field}.body[{}]", b.name),
                    "duplicate body name",
                ));
            }
        }
        for (i, j) in self.joints.iter().enumerate() {
            if self.joints[..i].iter().any(|o| o.name == j.name) {
                return Err(FieldError::new(
                    format!("{field}.joint[{}]", j.name),
                    "duplicate joint name",
                ));
            }
            check_limits(j, field)?;
        }
        Ok(())
    }
}

/// Joint-limit rules: both bounds finite, lower ≤ upper, a hinge spanning at most 2π (plus 1e-6
/// rad of rounding) and a slide at most 1 m — a hand with a longer stroke is a unit error.
pub fn check_limits(j: &Joint, field: &str) -> Result<(), FieldError> {
    let f = || format!("{field}.joint[{}].range", j.name);
    if let Some((lo, hi)) = j.range {
        if !lo.is_finite() || !hi.is_finite() {
            return Err(FieldError::new(
                f(),
                format!("limits must be finite, got [{lo}, {hi}]"),
            ));
        }
        if lo > hi {
            return Err(FieldError::new(
                f(),
                format!("lower limit {lo} is above upper limit {hi}"),
            ));
        }
        match j.kind {
            JointKind::Hinge if hi - lo > 2.0 * PI + 1e-6 => {
                return Err(FieldError::new(
                    f(),
                    format!(
                        "a hinge spanning {:.4} rad (> 2π) is absurd; were the limits written in \
                         degrees while the model reads radians?",
                        hi - lo
                    ),
                ));
            }
            JointKind::Slide if hi - lo > 1.0 => {
                return Err(FieldError::new(
                    f(),
                    format!(
                        "a slide spanning {:.4} m (> 1 m) is absurd for a hand",
                        hi - lo
                    ),
                ));
            }
            _ => {}
        }
    }
    if !j.reference.is_finite() {
        return Err(FieldError::new(
            format!("{field}.joint[{}].ref", j.name),
            "must be finite",
        ));
    }
    Ok(())
}
