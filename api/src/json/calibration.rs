//! `POST /v1/tactile/calibrations` and the calibrations' descriptions.

use super::tactile::{TareJson, tare_from_json};
use crate::request::{CalibrationInfo, CalibrationUpload, RecordingUpload};
use crate::schemas::TareConfigDoc;
use graspd_core::tactile::TareConfig;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// One labelled recording: the `_bio.csv` text (or an electrodes-only CSV: no pdc column),
/// its material, and optionally the arm's `_cw.csv` and `_cv.csv` texts (both, for frame
/// events) or one event for every frame.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct CalibrationRecordingJson {
    /// paper, foam, plastic or metal, optionally with a kind after a slash (plastic/eva).
    #[serde(default)]
    pub material: Option<String>,
    pub bio_csv: String,
    #[serde(default)]
    pub cw_csv: Option<String>,
    #[serde(default)]
    pub cv_csv: Option<String>,
    /// non_contact, contact or slip: the event of every frame, for a recording labelled as a
    /// whole (instead of cw_csv and cv_csv).
    #[serde(default)]
    pub event: Option<String>,
    /// The direction the recording slips in: north, east, south, west, clockwise,
    /// anticlockwise (or n, e, s, w, cw, aw).
    #[serde(default)]
    pub slip_direction: Option<String>,
}

/// The body of `POST /v1/tactile/calibrations` (the proto's CalibrateRequest).
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct CalibrateJson {
    pub name: String,
    #[serde(default)]
    pub replace: bool,
    #[serde(default)]
    pub window_length: Option<usize>,
    #[serde(default)]
    pub stride: Option<usize>,
    /// How the readings are tared; sessions using the calibration must tare alike.
    #[serde(default)]
    pub tare: Option<TareJson>,
    pub recordings: Vec<CalibrationRecordingJson>,
}

impl From<CalibrateJson> for CalibrationUpload {
    fn from(c: CalibrateJson) -> Self {
        Self {
            name: c.name,
            replace: c.replace,
            window_length: c.window_length,
            stride: c.stride,
            tare: tare_from_json(c.tare),
            recordings: c
                .recordings
                .into_iter()
                .map(|r| RecordingUpload {
                    material: r.material,
                    bio_csv: r.bio_csv,
                    cw_csv: r.cw_csv,
                    cv_csv: r.cv_csv,
                    event: r.event,
                    slip_direction: r.slip_direction,
                })
                .collect(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct LabelCountJson {
    pub label: String,
    pub windows: usize,
}

#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct EventWindowsJson {
    pub non_contact: usize,
    pub contact: usize,
    pub slip: usize,
}

/// A calibration (the proto's CalibrationInfo).
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct CalibrationJson {
    pub name: String,
    pub electrodes: usize,
    pub window_length: usize,
    pub stride: usize,
    #[schema(value_type = TareConfigDoc)]
    pub tare: TareConfig,
    /// The material labels fitted with their training windows; empty without a material
    /// classifier.
    pub material_windows: Vec<LabelCountJson>,
    /// Training windows per event; null without an event classifier.
    pub event_windows: Option<EventWindowsJson>,
    pub recordings: usize,
    pub fit_ms: f64,
    /// Stored in the calibrations directory (else in memory until the server stops).
    pub persisted: bool,
    /// Fitted on electrodes-only recordings: sessions use it on electrodes_only fingers.
    pub electrodes_only: bool,
    /// The slip directions fitted with their training windows; empty without a direction
    /// classifier.
    pub direction_windows: Vec<LabelCountJson>,
}

impl From<&CalibrationInfo> for CalibrationJson {
    fn from(info: &CalibrationInfo) -> Self {
        let c = &info.calibration;
        let [non_contact, contact, slip] = c.summary.event_windows;
        Self {
            name: c.name.clone(),
            electrodes: c.electrodes,
            window_length: c.settings.window_length,
            stride: c.settings.stride,
            tare: c.settings.tare,
            material_windows: c
                .summary
                .material_windows
                .iter()
                .map(|(label, n)| LabelCountJson {
                    label: label.clone(),
                    windows: *n,
                })
                .collect(),
            event_windows: c.events.as_ref().map(|_| EventWindowsJson {
                non_contact,
                contact,
                slip,
            }),
            recordings: c.summary.recordings,
            fit_ms: c.summary.fit_ms,
            persisted: info.persisted,
            electrodes_only: c.settings.electrodes_only,
            direction_windows: c
                .summary
                .direction_windows
                .iter()
                .map(|(label, n)| LabelCountJson {
                    label: label.clone(),
                    windows: *n,
                })
                .collect(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct CalibrationsJson {
    pub calibrations: Vec<CalibrationJson>,
}
