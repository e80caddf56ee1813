//! Hand kinematics from a robot description (issue 6): MJCF and URDF import into one
//! [`KinematicTree`], forward kinematics, per-finger inverse kinematics by damped least squares
//! (method.md §3, Eq 3.11 form) and the derivation of a [`crate::hand::HandDescription`] from the
//! reachable workspace.
//!
//! ```no_run
//! use graspd_core::hand::kinematics::KinematicHand;
//! let hand = KinematicHand::from_mjcf_file("../shared/testdata/hands/wonik_allegro/right_hand.xml")?;
//! let description = hand.describe()?; // validated HandDescription, hand frame as in description.rs
//! let q = hand.tree.mid_configuration();
//! let tips = hand.fingertips(&q)?; // contact points in the hand frame
//! let ik = hand.inverse(0, &tips[0], &q)?; // joints, residual, reachable
//! # Ok::<(), graspd_core::FieldError>(())
//! ```

pub mod closing;
pub mod collision_model;
pub mod convex_faces;
pub mod describe;
pub mod forward_kinematics;
pub mod hand_model;
pub mod inverse_kinematics;
pub mod kinematic_tree;
pub mod mesh;
pub mod mjcf;
pub mod projection_memo;
pub mod urdf;
mod xml;

pub use closing::{FingerSynergy, FlexionJoint, HandSynergy, PreShape};
pub use collision_model::{CollisionPiece, HandCollision, PosedCollision};
pub use forward_kinematics::ForwardKinematics;
pub use hand_model::{HandOverrides, KinematicFinger, KinematicHand};
pub use inverse_kinematics::{ContactTarget, FingerIk, HandIk, IkOptions, PalmFreedom, PalmIk};
pub use kinematic_tree::{
    Body, Geom, GeomShape, Joint, JointCoupling, JointKind, KinematicTree, LoopClosure, Site,
};
pub use projection_memo::ProjectionMemo;
