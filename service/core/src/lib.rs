//! graspd domain: hands, point clouds, RGB-D perception and the dual-stage
//! pregrasping-opposition planner of the dissertation (method.md). Plain Rust: no transport,
//! async runtime or proto types here.

pub mod cloud;
pub mod error;
pub mod grasp_type;
pub mod hand;
pub mod onnx_runtime;
pub mod perception;
pub mod plan_overlay;
pub mod plan_scene;
pub mod planning;
pub mod reaching;
pub mod tactile;

pub use error::{FieldError, PlanError};
pub use grasp_type::{GraspType, HandPart};
pub use hand::{HandCatalog, HandDescription};
pub use planning::{GraspPlan, PlanHints, PlanInput, PlannerOptions, plan};
