//! Tactile stabilization (method.md §5, dissertation ch. 6, Algorithm 5).
//!
//! The pipeline per finger and frame: taring (`taring`) → window sampling and contact-event
//! detection (`detector`) → tactile image (`tactile_image`) → GMM force estimation
//! (`force_estimation`, Eq 6.5–6.7) → desired force (`desired_force`, Eq 6.8–6.9) → PID
//! (`pid`). `stabilizer::Stabilizer` runs it as a session on the `readings`; `recording` reads the CSV layout of the
//! real BioTac recordings. Plain Rust: no transport types.

pub mod batched_step;
pub mod calibration;
pub mod centroid_slip;
pub mod desired_force;
pub mod detector;
pub mod force_estimation;
pub mod layout;
pub mod lstm_detector;
pub mod pid;
pub mod readings;
pub mod recording;
pub mod stabilizer;
pub mod tactile_image;
pub mod taring;

pub use calibration::{
    CalibratedDetector, Calibration, CalibrationRecording, CalibrationSettings, CalibrationSummary,
};
pub use desired_force::{ControlMode, DesiredForceLaw};
pub use detector::{
    ContactEvent, Detection, EventDetector, Material, ModelFreeDetector, ModelFreeThresholds,
    SlipDirection, WindowSampler,
};
pub use force_estimation::{ContactEstimate, EmOptions, ForceEstimator, Gmm1d};
pub use layout::{LayoutSpec, SensorCatalog, SensorLayout, parse_layout_toml};
pub use lstm_detector::{LstmDetector, TactileModel, TactileModelError};
pub use pid::{Pid, PidGains};
pub use recording::{LabelThresholds, Recording};
pub use stabilizer::{
    DetectorChoice, FingerConfig, FingerReading, FingerResult, ForceUnit, Frame, FrameResult,
    SampleSource, Stabilizer, StabilizerConfig, analyze, analyze_with_detectors,
};
pub use tactile_image::TactileImage;
pub use taring::{Baseline, ElectrodePolarity, TareConfig};
