//! Hands as data (method.md §2).

pub mod catalog;
pub mod description;
pub mod kinematics;
pub mod posture_synergies;

pub use catalog::{HandCatalog, parse_hand_toml};
pub use description::{
    Finger, GraspRealisation, HandDescription, HandGeometry, PALM, ResolvedGrasp, TypeEquivalence,
};
pub use posture_synergies::{PostureSynergies, hand_based_reward};
