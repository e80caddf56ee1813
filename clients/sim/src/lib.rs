//! graspd-sim: drives real hand models in MuJoCo through a running graspd (gRPC only) and scores
//! the plans: scenes of YCB objects on a table, a CPU RGB-D camera, grasp trials with classified
//! failures, and the Table 5.2 benchmark.

pub mod bench;
pub mod camera;
pub mod closing;
pub mod clutter;
pub mod compare;
pub mod completion;
mod debug;
pub mod gravity;
pub mod grip_reflex;
pub mod hand;
pub mod in_hand;
pub mod labels;
pub mod object;
pub mod record;
pub mod scene;
pub mod service;
pub mod tactile;
pub mod trial;

/// Errors of graspd-sim; each names what it is about.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// Bad input: a file, a name, an option.
    #[error("{0}")]
    Input(String),
    /// MuJoCo refused the scene.
    #[error("simulation: {0}")]
    Sim(String),
    /// graspd could not be reached or refused a request.
    #[error("graspd: {0}")]
    Service(String),
}
