//! Tactile calibrations: Calibrate requests and the calibrations' descriptions.

use super::tactile::{tare_from_proto, tare_to_proto};
use crate::request::{CalibrationInfo, CalibrationUpload, RecordingUpload};
use graspd_core::FieldError;
use graspd_proto::v1 as pb;

/// A Calibrate request in domain terms (the CSVs are parsed, and the labels checked, by the
/// facade; errors name `recordings[i].…`).
pub fn calibrate_request_from_proto(
    r: pb::CalibrateRequest,
) -> Result<CalibrationUpload, FieldError> {
    let text = |s: String| (!s.is_empty()).then_some(s);
    Ok(CalibrationUpload {
        name: r.name,
        replace: r.replace,
        window_length: r.window_length.map(|v| v as usize),
        stride: r.stride.map(|v| v as usize),
        tare: tare_from_proto(r.tare, "tare")?,
        recordings: r
            .recordings
            .into_iter()
            .map(|c| RecordingUpload {
                material: text(c.material),
                bio_csv: c.bio_csv,
                cw_csv: text(c.cw_csv),
                cv_csv: text(c.cv_csv),
                event: text(c.event),
                slip_direction: text(c.slip_direction),
            })
            .collect(),
    })
}

/// The client's side: an upload as the proto message.
pub fn calibrate_request_to_proto(u: &CalibrationUpload) -> pb::CalibrateRequest {
    pb::CalibrateRequest {
        name: u.name.clone(),
        replace: u.replace,
        window_length: u.window_length.map(|v| v.min(u32::MAX as usize) as u32),
        stride: u.stride.map(|v| v.min(u32::MAX as usize) as u32),
        tare: Some(tare_to_proto(&u.tare)),
        recordings: u
            .recordings
            .iter()
            .map(|r| pb::CalibrationRecording {
                material: r.material.clone().unwrap_or_default(),
                bio_csv: r.bio_csv.clone(),
                cw_csv: r.cw_csv.clone().unwrap_or_default(),
                cv_csv: r.cv_csv.clone().unwrap_or_default(),
                event: r.event.clone().unwrap_or_default(),
                slip_direction: r.slip_direction.clone().unwrap_or_default(),
            })
            .collect(),
    }
}

pub fn calibration_info_to_proto(info: &CalibrationInfo) -> pb::CalibrationInfo {
    let c = &info.calibration;
    let u32_of = |v: usize| v.min(u32::MAX as usize) as u32;
    pb::CalibrationInfo {
        name: c.name.clone(),
        electrodes: u32_of(c.electrodes),
        window_length: u32_of(c.settings.window_length),
        stride: u32_of(c.settings.stride),
        tare: Some(tare_to_proto(&c.settings.tare)),
        material_windows: c
            .summary
            .material_windows
            .iter()
            .map(|(label, n)| pb::LabelCount {
                label: label.clone(),
                windows: *n as u64,
            })
            .collect(),
        event_windows: c.summary.event_windows.iter().map(|&n| n as u64).collect(),
        recordings: u32_of(c.summary.recordings),
        fit_ms: c.summary.fit_ms,
        persisted: info.persisted,
        electrodes_only: c.settings.electrodes_only,
        direction_windows: c
            .summary
            .direction_windows
            .iter()
            .map(|(label, n)| pb::LabelCount {
                label: label.clone(),
                windows: *n as u64,
            })
            .collect(),
    }
}
