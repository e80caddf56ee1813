//! The dual-stage grasp planner with pregrasping opposition (dissertation ch. 5.4, Algorithm 4).

pub mod annealing;
pub mod bayesian_search;
pub mod collision;
pub mod dense_simplex;
pub mod dual_stage;
pub mod evaluation;
pub mod ferrari_canny;
pub mod final_configuration;
pub mod grasp_plan;
pub mod grasp_quality;
pub mod grip_forces;
pub mod hand_pose;
pub mod kinematic_model;
mod learned_planner;
pub mod moveit_grasp;
pub mod moveit_layout;
pub mod object_shape;
pub mod opposition;
pub mod parallel_grasp;
mod plan_assembly;
mod planner;
pub mod quality;
pub mod request;
pub mod robustness;
mod scene;
pub mod slot_set;
pub mod synergy_postures;
#[cfg(test)]
mod test_scene;
pub mod type_choice;
pub mod type_rule;

pub use grasp_plan::*;
pub use kinematic_model::KinematicModel;
pub use planner::{MAX_ITERATIONS, PlanInput, plan};
pub use request::*;
