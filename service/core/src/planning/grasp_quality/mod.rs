//! The learned grasp-quality metric of a parallel-jaw gripper (dissertation §3.2.2, Eq 3.1)
//! and what the Bayesian search of §3.2.3 ([`super::bayesian_search`]) evaluates it on: the
//! candidate grasps g = {x, y, z, θ} sampled from the object's visible points
//! ([`candidates`]), the network's view of each ([`crop`]).

pub mod candidates;
pub mod crop;
pub mod model;

pub use model::GraspQualityModel;
