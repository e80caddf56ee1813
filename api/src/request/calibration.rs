//! A calibration request in domain terms, and a stored calibration as the answers describe it.

use graspd_core::tactile::{Calibration, TareConfig};
use std::sync::Arc;

/// One labelled recording as the transports receive it: the `_bio.csv` text (or an
/// electrodes-only CSV, `tactile::recording`) and, for frame events, the arm's `_cw.csv` and
/// `_cv.csv` (`tactile::recording` derives them) or one event for the whole recording.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RecordingUpload {
    /// The material touched (`paper`, `foam`, `plastic`, `metal`, optionally `/kind`).
    pub material: Option<String>,
    pub bio_csv: String,
    pub cw_csv: Option<String>,
    pub cv_csv: Option<String>,
    /// The contact event of every frame (`non_contact`, `contact` or `slip`), for a recording
    /// labelled as a whole (a held touch, a slide) instead of by the arm's files.
    pub event: Option<String>,
    /// The direction the recording slips in (north, east, south, west, clockwise,
    /// anticlockwise, or the BioTac SP data's n, e, s, w, cw, aw).
    pub slip_direction: Option<String>,
}

/// A calibration request in domain terms.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationUpload {
    pub name: String,
    /// Replace a calibration of this name.
    pub replace: bool,
    pub window_length: Option<usize>,
    pub stride: Option<usize>,
    pub tare: TareConfig,
    pub recordings: Vec<RecordingUpload>,
}

/// A stored calibration and whether it is on disk.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationInfo {
    pub calibration: Arc<Calibration>,
    pub persisted: bool,
}
