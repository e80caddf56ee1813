//! Hand kinematics from a robot description (issue 6): MJCF and URDF import into one
//! [`KinematicTree`], forward kinematics, per-finger inverse kinematics by damped least squares
//! (method.md §3, Eq 3.11 form) and the derivation of a [`crate::hand::HandDescription`] from the
//! reachable workspace.

pub mod forward_kinematics;
pub mod kinematic_tree;
pub mod mesh;
pub mod mjcf;
pub mod urdf;
mod xml;

pub use forward_kinematics::ForwardKinematics;
pub use kinematic_tree::{
    Body, Geom, GeomShape, Joint, JointKind, KinematicTree, LoopClosure, Site,
};
