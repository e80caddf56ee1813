//! Tactile calibrations (issue 16): fitted from a user's labelled recordings, kept by name
//! like registered hands (in memory, and in the calibrations directory when one is
//! configured), listed, deleted, and named by sessions (`detector.calibration`).

use super::{GraspService, ServiceError, guarded};
use crate::calibration_store;
use crate::hand_store::check_name;
pub use graspd_api::request::{CalibrationInfo, CalibrationUpload, RecordingUpload};
use graspd_core::FieldError;
use graspd_core::tactile::{
    Calibration, CalibrationRecording, CalibrationSettings, ContactEvent, Recording, SlipDirection,
    StabilizerConfig,
};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

/// The calibrations by name, and where they persist.
#[derive(Debug, Default)]
pub(super) struct Calibrations {
    by_name: BTreeMap<String, Arc<Calibration>>,
    dir: Option<PathBuf>,
}

impl GraspService {
    /// Loads the calibrations of `dir` and stores new ones there (at start, before the
    /// service is shared).
    pub fn with_calibrations_dir(self, dir: PathBuf) -> Result<Self, String> {
        let loaded = calibration_store::load_dir(&dir)?;
        {
            let mut c = self.calibrations_mut();
            for cal in loaded {
                c.by_name.insert(cal.name.clone(), Arc::new(cal));
            }
            c.dir = Some(dir);
        }
        Ok(self)
    }

    /// Fits a calibration on the uploaded recordings and stores it (errors name the field:
    /// `name`, `recordings[3].bio_csv`, `recordings[].material`, …; nothing is stored on
    /// error). CPU-bound and blocking.
    pub fn calibrate(&self, upload: CalibrationUpload) -> Result<CalibrationInfo, ServiceError> {
        check_name(&upload.name, "name")?;
        let bytes: usize = upload
            .recordings
            .iter()
            .map(|r| {
                r.bio_csv.len()
                    + r.cw_csv.as_ref().map_or(0, String::len)
                    + r.cv_csv.as_ref().map_or(0, String::len)
            })
            .sum();
        let limit = self.inner.limits.max_message_bytes;
        if bytes > limit {
            return Err(ServiceError::TooLarge(FieldError::new(
                "recordings",
                format!(
                    "the recordings take {bytes} bytes, over the configured limit of {limit} bytes (max_message_bytes)"
                ),
            )));
        }
        let taken = |c: &Calibrations| -> Result<(), ServiceError> {
            if !upload.replace && c.by_name.contains_key(&upload.name) {
                return Err(ServiceError::AlreadyExists(FieldError::new(
                    "name",
                    format!(
                        "calibration '{}' exists (set replace to replace it)",
                        upload.name
                    ),
                )));
            }
            Ok(())
        };
        taken(&self.calibrations())?;
        let parsed = upload
            .recordings
            .iter()
            .enumerate()
            .map(|(i, r)| parse_recording(r, &format!("recordings[{i}]")))
            .collect::<Result<Vec<_>, FieldError>>()?;
        // One sensor: every recording with the first one's layout.
        let electrodes_only = parsed.first().is_some_and(|(_, e)| *e);
        if let Some(i) = parsed.iter().position(|(_, e)| *e != electrodes_only) {
            let (this, first) = if electrodes_only {
                (
                    "has pdc, pac and the thermal channels",
                    "gives electrodes only",
                )
            } else {
                (
                    "gives electrodes only",
                    "has pdc, pac and the thermal channels",
                )
            };
            return Err(FieldError::new(
                format!("recordings[{i}].bio_csv"),
                format!(
                    "the recording {this}; recordings[0] {first}: one calibration is of one sensor"
                ),
            )
            .into());
        }
        let recordings: Vec<CalibrationRecording> = parsed.into_iter().map(|(r, _)| r).collect();
        let d = CalibrationSettings::default();
        let settings = CalibrationSettings {
            window_length: upload.window_length.unwrap_or(d.window_length),
            stride: upload.stride.unwrap_or(d.stride),
            tare: upload.tare,
            electrodes_only,
        };
        let calibration = guarded("fitting the calibration", || {
            Calibration::fit(&upload.name, &recordings, settings).map_err(ServiceError::from)
        })?;
        let calibration = Arc::new(calibration);
        let mut c = self.calibrations_mut();
        taken(&c)?;
        if let Some(dir) = &c.dir {
            calibration_store::save(dir, &calibration).map_err(|e| {
                ServiceError::Internal(format!("cannot store the calibration: {e}"))
            })?;
        }
        c.by_name.insert(upload.name, calibration.clone());
        Ok(CalibrationInfo {
            calibration,
            persisted: c.dir.is_some(),
        })
    }

    /// Every calibration, by name.
    pub fn list_calibrations(&self) -> Vec<CalibrationInfo> {
        let c = self.calibrations();
        c.by_name
            .values()
            .map(|cal| CalibrationInfo {
                calibration: cal.clone(),
                persisted: c.dir.is_some(),
            })
            .collect()
    }

    /// One calibration (`NotFound` naming `name`).
    pub fn get_calibration(&self, name: &str) -> Result<CalibrationInfo, ServiceError> {
        let c = self.calibrations();
        match c.by_name.get(name) {
            Some(cal) => Ok(CalibrationInfo {
                calibration: cal.clone(),
                persisted: c.dir.is_some(),
            }),
            None => Err(ServiceError::NotFound(unknown(&c, name, "name"))),
        }
    }

    /// Deletes a calibration (from disk too). Sessions already using it keep it.
    pub fn delete_calibration(&self, name: &str) -> Result<(), ServiceError> {
        let mut c = self.calibrations_mut();
        if !c.by_name.contains_key(name) {
            return Err(ServiceError::NotFound(unknown(&c, name, "name")));
        }
        if let Some(dir) = &c.dir {
            calibration_store::remove(dir, name).map_err(|e| {
                ServiceError::Internal(format!("cannot delete the stored calibration: {e}"))
            })?;
        }
        c.by_name.remove(name);
        Ok(())
    }

    /// The calibration a session names as its detector, checked against the session: its
    /// window, stride, and the electrode count and taring of every finger that uses it (`uses`:
    /// those without a calibration of their own; errors name the field).
    pub(super) fn session_calibration(
        &self,
        name: &str,
        config: &StabilizerConfig,
        uses: &[bool],
    ) -> Result<Arc<Calibration>, ServiceError> {
        self.fitting_calibration(name, config, uses, "session.detector.calibration")
    }

    /// The calibration finger `i` names for itself (`session.fingers[i].calibration`), checked
    /// against that finger.
    pub(super) fn finger_calibration(
        &self,
        name: &str,
        config: &StabilizerConfig,
        i: usize,
    ) -> Result<Arc<Calibration>, ServiceError> {
        let uses: Vec<bool> = (0..config.fingers.len()).map(|k| k == i).collect();
        let field = format!("session.fingers[{i}].calibration");
        self.fitting_calibration(name, config, &uses, &field)
    }

    /// A calibration by name (unknown: `field`), checked against the session's window and
    /// the fingers that use it: electrodes only or not, electrode count, taring.
    fn fitting_calibration(
        &self,
        name: &str,
        config: &StabilizerConfig,
        uses: &[bool],
        field: &str,
    ) -> Result<Arc<Calibration>, ServiceError> {
        let cal = {
            let c = self.calibrations();
            c.by_name
                .get(name)
                .cloned()
                .ok_or_else(|| unknown(&c, name, field))?
        };
        let s = &cal.settings;
        if (config.window_length, config.stride) != (s.window_length, s.stride) {
            return Err(FieldError::new(
                "session.window_length",
                format!(
                    "calibration '{name}' was fitted on windows of {} with stride {}; the session has {} and {}",
                    s.window_length, s.stride, config.window_length, config.stride
                ),
            )
            .into());
        }
        for (i, f) in config.fingers.iter().enumerate() {
            if !uses.get(i).copied().unwrap_or(true) {
                continue;
            }
            if f.electrodes_only != s.electrodes_only {
                let reads = if s.electrodes_only {
                    "was fitted on electrodes only; the finger must be electrodes_only"
                } else {
                    "reads pdc, pac and the thermal channels; an electrodes-only finger needs \
                     an electrodes-only calibration or model_free"
                };
                return Err(FieldError::new(
                    format!("session.fingers[{i}].electrodes_only"),
                    format!("calibration '{name}' {reads}"),
                )
                .into());
            }
            if f.layout.electrode_count() != cal.electrodes {
                return Err(FieldError::new(
                    format!("session.fingers[{i}].layout"),
                    format!(
                        "layout {} has {} electrodes; calibration '{name}' reads {}",
                        f.layout.name,
                        f.layout.electrode_count(),
                        cal.electrodes
                    ),
                )
                .into());
            }
            if f.tare != s.tare {
                return Err(FieldError::new(
                    format!("session.fingers[{i}].tare"),
                    format!(
                        "calibration '{name}' was fitted on readings tared as {:?}; the finger is tared as {:?}",
                        s.tare, f.tare
                    ),
                )
                .into());
            }
        }
        Ok(cal)
    }

    fn calibrations(&self) -> std::sync::RwLockReadGuard<'_, Calibrations> {
        self.inner
            .calibrations
            .read()
            .unwrap_or_else(|e| e.into_inner())
    }

    fn calibrations_mut(&self) -> std::sync::RwLockWriteGuard<'_, Calibrations> {
        self.inner
            .calibrations
            .write()
            .unwrap_or_else(|e| e.into_inner())
    }
}

/// An unknown calibration, naming the known ones.
fn unknown(c: &Calibrations, name: &str, field: &str) -> FieldError {
    let known: Vec<&str> = c.by_name.keys().map(String::as_str).collect();
    let known = if known.is_empty() {
        "none yet: POST /v1/tactile/calibrations".to_string()
    } else {
        known.join(", ")
    };
    FieldError::new(
        field,
        format!(
            "unknown calibration '{}' (known: {known})",
            name.escape_debug()
        ),
    )
}

/// One upload as core's recording (errors renamed under `field`): the CSVs parsed, events
/// when both arm files are given or the whole recording's event; and whether it gave
/// electrodes only.
fn parse_recording(
    r: &RecordingUpload,
    field: &str,
) -> Result<(CalibrationRecording, bool), FieldError> {
    if r.cw_csv.is_some() != r.cv_csv.is_some() {
        return Err(FieldError::new(
            format!("{field}.cw_csv"),
            "frame events need both the wrench (cw_csv) and the velocity (cv_csv) files",
        ));
    }
    let event = match r.event.as_deref() {
        None => None,
        Some(_) if r.cw_csv.is_some() => {
            return Err(FieldError::new(
                format!("{field}.event"),
                "give the recording's event or the arm's files (cw_csv, cv_csv), not both",
            ));
        }
        Some(name) => Some(ContactEvent::parse(name).ok_or_else(|| {
            FieldError::new(
                format!("{field}.event"),
                format!(
                    "unknown event '{}': one of non_contact, contact, slip",
                    name.escape_debug()
                ),
            )
        })?),
    };
    let slip_direction = r
        .slip_direction
        .as_deref()
        .map(|name| {
            SlipDirection::parse(name).ok_or_else(|| {
                FieldError::new(
                    format!("{field}.slip_direction"),
                    format!(
                        "unknown slip direction '{}': one of north, east, south, west, \
                         clockwise, anticlockwise (or n, e, s, w, cw, aw)",
                        name.escape_debug()
                    ),
                )
            })
        })
        .transpose()?;
    let rec = Recording::from_csv(&r.bio_csv, r.cw_csv.as_deref(), r.cv_csv.as_deref())
        .map_err(|e| FieldError::new(format!("{field}.{}", e.field), e.message))?;
    let events = event.map(|e| vec![e; rec.rows.len()]).or(rec.labels);
    Ok((
        CalibrationRecording {
            material: r.material.clone(),
            readings: rec.rows.iter().map(|row| row.reading()).collect(),
            events,
            slip_direction,
        },
        rec.electrodes_only,
    ))
}
