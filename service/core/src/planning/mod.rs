//! The dual-stage grasp planner with pregrasping opposition (dissertation ch. 5.4, Algorithm 4).

pub mod ferrari_canny;
pub mod quality;
pub mod types;
mod planner;

pub use planner::{PlanInput, plan};
pub use types::*;
