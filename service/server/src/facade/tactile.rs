//! Tactile stabilization: sessions, their layouts and detectors, and analysis of recordings.

use super::{GraspService, ServiceError, guarded};
pub use graspd_api::request::{LayoutChoice, TactileFingerRequest, TactileSessionRequest};
use graspd_core::FieldError;
use graspd_core::tactile::{
    CalibratedDetector, DetectorChoice, EventDetector, FingerConfig, Frame, FrameResult,
    LstmDetector, ModelFreeThresholds, SensorLayout, Stabilizer, StabilizerConfig, TactileModel,
};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// An open tactile session: a [`Stabilizer`] holding one of the `max_tactile_sessions` slots,
/// released when this is dropped (e.g. the moment a stream's client disconnects).
#[derive(Debug)]
pub struct TactileSession {
    stabilizer: Stabilizer,
    _slot: SessionSlot,
}

#[derive(Debug)]
struct SessionSlot(Arc<AtomicUsize>);

impl Drop for SessionSlot {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

impl TactileSession {
    /// Processes one frame. A frame that does not fit the session (finger or electrode count,
    /// out-of-order timestamp, non-finite value) is `InvalidArgument` naming `frame.…` and
    /// changes nothing.
    pub fn step(&mut self, frame: &Frame) -> Result<FrameResult, ServiceError> {
        let stabilizer = &mut self.stabilizer;
        guarded("the stabilizer", || {
            stabilizer.step(frame).map_err(ServiceError::from)
        })
    }

    /// Frames accepted so far.
    pub fn frames(&self) -> u64 {
        self.stabilizer.frames()
    }

    pub fn config(&self) -> &StabilizerConfig {
        self.stabilizer.config()
    }
}

impl GraspService {
    /// Resolves the layouts and validates the parameters (errors name `session.…`).
    pub fn tactile_config(
        &self,
        request: TactileSessionRequest,
    ) -> Result<StabilizerConfig, ServiceError> {
        let mut config = request.config;
        config.fingers = request
            .fingers
            .into_iter()
            .enumerate()
            .map(|(i, f)| {
                let field = format!("session.fingers[{i}].layout");
                let layout = match f.layout {
                    LayoutChoice::Name(name) => {
                        self.inner.sensors.get(&name).cloned().ok_or_else(|| {
                            FieldError::new(
                                &field,
                                format!(
                                    "unknown layout '{}' (built-in: {}; or give the electrode coordinates)",
                                    name.escape_debug(),
                                    self.inner.sensors.names().join(", ")
                                ),
                            )
                        })?
                    }
                    LayoutChoice::Custom(spec) => SensorLayout::from_spec(spec).map_err(|e| {
                        let rest = e.field.strip_prefix("layout").unwrap_or("");
                        FieldError::new(format!("{field}{rest}"), e.message)
                    })?,
                };
                Ok(FingerConfig {
                    name: f.name,
                    layout,
                    tare: f.tare,
                    electrodes_only: f.electrodes_only,
                })
            })
            .collect::<Result<_, FieldError>>()?;
        config.validate()?;
        Ok(config)
    }

    /// Opens a session (one slot of `max_tactile_sessions`; `Exhausted` when none is free).
    pub fn open_tactile_session(
        &self,
        request: TactileSessionRequest,
    ) -> Result<TactileSession, ServiceError> {
        let own = finger_calibrations(&request);
        let config = self.tactile_config(request)?;
        let detectors = self.detectors(&config, &own)?;
        let stabilizer = Stabilizer::with_detectors(config, detectors)?;
        let slot = self.take_tactile_slot()?;
        Ok(TactileSession {
            stabilizer,
            _slot: slot,
        })
    }

    /// Runs a whole recorded sequence through a fresh session: one result per frame; errors name
    /// the frame (`frames[12].fingers[0].electrodes`). Holds a session slot while it runs.
    /// Blocking and CPU-bound.
    pub fn analyze_tactile(
        &self,
        request: TactileSessionRequest,
        frames: &[Frame],
    ) -> Result<Vec<FrameResult>, ServiceError> {
        let own = finger_calibrations(&request);
        let config = self.tactile_config(request)?;
        let detectors = self.detectors(&config, &own)?;
        let _slot = self.take_tactile_slot()?;
        guarded("the stabilizer", || {
            graspd_core::tactile::analyze_with_detectors(config, detectors, frames)
                .map_err(ServiceError::from)
        })
    }

    /// One detector per finger for a validated config: a finger that names its own
    /// calibration (`own[i]`) detects with it (it must fit the finger: errors name
    /// `session.fingers[i].calibration`), the others with the session's detector.
    fn detectors(
        &self,
        config: &StabilizerConfig,
        own: &[Option<String>],
    ) -> Result<Vec<Box<dyn EventDetector>>, ServiceError> {
        let shared: Vec<bool> = own.iter().map(Option::is_none).collect();
        let mut detectors = self.session_detectors(config, &shared)?;
        for (i, name) in own.iter().enumerate() {
            if let Some(name) = name {
                let cal = self.finger_calibration(name, config, i)?;
                detectors[i] =
                    Box::new(CalibratedDetector::new(cal, ModelFreeThresholds::default()));
            }
        }
        Ok(detectors)
    }

    /// One detector per finger from the session's choice: `model`/`lstm` needs the loaded
    /// model and a session that fits it, a calibration one that fits it (errors name the
    /// field); the default takes the model when the session fits it, else the model-free
    /// detector. Only the `shared` fingers (those without a calibration of their own) must fit.
    fn session_detectors(
        &self,
        config: &StabilizerConfig,
        shared: &[bool],
    ) -> Result<Vec<Box<dyn EventDetector>>, ServiceError> {
        let model_free = |t: ModelFreeThresholds| -> Vec<Box<dyn EventDetector>> {
            config
                .fingers
                .iter()
                .map(|_| {
                    Box::new(graspd_core::tactile::ModelFreeDetector::new(t))
                        as Box<dyn EventDetector>
                })
                .collect()
        };
        let with_model = |m: &Arc<TactileModel>| -> Vec<Box<dyn EventDetector>> {
            config
                .fingers
                .iter()
                .map(|_| Box::new(LstmDetector::new(m.clone())) as Box<dyn EventDetector>)
                .collect()
        };
        let model = self.inner.tactile_model.as_ref();
        match &config.detector {
            DetectorChoice::Calibration(name) => {
                let cal = self.session_calibration(name, config, shared)?;
                Ok(config
                    .fingers
                    .iter()
                    .map(|_| {
                        Box::new(CalibratedDetector::new(
                            cal.clone(),
                            ModelFreeThresholds::default(),
                        )) as Box<dyn EventDetector>
                    })
                    .collect())
            }
            DetectorChoice::ModelFree(t) => Ok(model_free(*t)),
            DetectorChoice::Default => Ok(match model {
                Some(m) if tactile_fit(config, m, shared).is_ok() => with_model(m),
                _ => model_free(ModelFreeThresholds::default()),
            }),
            DetectorChoice::Model(name) => {
                let wanted = name.trim().to_ascii_lowercase();
                if wanted != "lstm" && wanted != "model" {
                    return Err(FieldError::new(
                        "session.detector.model",
                        format!(
                            "unknown model '{}'; the learned detector is 'lstm' (or 'model')",
                            name.escape_debug()
                        ),
                    )
                    .into());
                }
                let m = model.ok_or_else(|| {
                    FieldError::new(
                        "session.detector.model",
                        "no tactile model is loaded on this server (start graspd with \
                         --tactile-model FILE, or use model_free)",
                    )
                })?;
                tactile_fit(config, m, shared)?;
                Ok(with_model(m))
            }
        }
    }

    /// Tactile sessions open now.
    pub fn tactile_sessions_open(&self) -> usize {
        self.inner.tactile_sessions.load(Ordering::Acquire)
    }

    fn take_tactile_slot(&self) -> Result<SessionSlot, ServiceError> {
        let max = self.inner.limits.max_tactile_sessions;
        let count = &self.inner.tactile_sessions;
        count
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| {
                (n < max).then_some(n + 1)
            })
            .map_err(|_| {
                ServiceError::Exhausted(format!(
                    "{max} tactile sessions are open, the configured limit (max_tactile_sessions); retry when one has closed"
                ))
            })?;
        Ok(SessionSlot(count.clone()))
    }
}

/// Whether a session fits the tactile model: its window and stride, and the electrode count of
/// every finger that uses it (`uses`).
fn tactile_fit(
    config: &StabilizerConfig,
    m: &TactileModel,
    uses: &[bool],
) -> Result<(), FieldError> {
    if config.window_length != m.window_length() {
        return Err(FieldError::new(
            "session.window_length",
            format!(
                "the tactile model was trained on windows of {}; got {} (use model_free for \
                 other windows)",
                m.window_length(),
                config.window_length
            ),
        ));
    }
    if config.stride != m.stride() {
        return Err(FieldError::new(
            "session.stride",
            format!(
                "the tactile model was trained with stride {}; got {} (use model_free \
                 for other strides)",
                m.stride(),
                config.stride
            ),
        ));
    }
    for (i, f) in config.fingers.iter().enumerate() {
        if !uses.get(i).copied().unwrap_or(true) {
            continue;
        }
        if f.electrodes_only {
            return Err(FieldError::new(
                format!("session.fingers[{i}].electrodes_only"),
                "the tactile model reads pdc, pac and the thermal channels; an electrodes-only \
                 finger needs model_free",
            ));
        }
        if f.layout.electrode_count() != m.electrode_count() {
            return Err(FieldError::new(
                format!("session.fingers[{i}].layout"),
                format!(
                    "layout {} has {} electrodes; the tactile model reads {} (a classic \
                     BioTac); use model_free for this finger's sensor",
                    f.layout.name,
                    f.layout.electrode_count(),
                    m.electrode_count()
                ),
            ));
        }
    }
    Ok(())
}

/// Each finger's own calibration, if it names one (before the request is consumed).
fn finger_calibrations(request: &TactileSessionRequest) -> Vec<Option<String>> {
    request
        .fingers
        .iter()
        .map(|f| f.calibration.clone())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::facade::Limits;
    use graspd_core::tactile::{LayoutSpec, TareConfig};

    fn tactile_request(layout: LayoutChoice) -> TactileSessionRequest {
        TactileSessionRequest {
            fingers: vec![TactileFingerRequest {
                name: "th".into(),
                layout,
                tare: TareConfig::pretared(),
                electrodes_only: false,
                calibration: None,
            }],
            config: StabilizerConfig::default(),
        }
    }

    #[test]
    fn tactile_sessions_are_limited_and_free_their_slot_on_drop() {
        let s = GraspService::builtin(Limits {
            max_tactile_sessions: 2,
            ..Limits::default()
        });
        let biotac = || tactile_request(LayoutChoice::Name("biotac".into()));
        let a = s.open_tactile_session(biotac()).unwrap();
        let _b = s.open_tactile_session(biotac()).unwrap();
        assert_eq!(s.tactile_sessions_open(), 2);
        let e = s.open_tactile_session(biotac()).unwrap_err();
        assert!(matches!(&e, ServiceError::Exhausted(m) if m.contains("max_tactile_sessions")));
        assert!(matches!(
            s.analyze_tactile(biotac(), &[]),
            Err(ServiceError::Exhausted(_))
        ));
        drop(a);
        assert_eq!(s.tactile_sessions_open(), 1);
        assert!(s.analyze_tactile(biotac(), &[]).unwrap().is_empty());
        assert_eq!(s.tactile_sessions_open(), 1);
        // A refused (invalid) session takes no slot.
        let e = s
            .open_tactile_session(tactile_request(LayoutChoice::Name("nope".into())))
            .unwrap_err();
        assert_eq!(e.field(), Some("session.fingers[0].layout"));
        assert_eq!(s.tactile_sessions_open(), 1);
    }

    #[test]
    fn tactile_layouts_resolve_by_name_or_coordinates() {
        let s = GraspService::builtin(Limits::default());
        let c = s
            .tactile_config(tactile_request(LayoutChoice::Name("biotac_sp".into())))
            .unwrap();
        assert_eq!(c.fingers[0].layout.electrode_count(), 24);
        let spec = |electrodes: Vec<[f64; 2]>| {
            LayoutChoice::Custom(LayoutSpec {
                name: "pad".into(),
                description: String::new(),
                electrodes,
            })
        };
        let c = s
            .tactile_config(tactile_request(spec(vec![
                [0.0, 0.0],
                [1.0, 0.0],
                [0.0, 1.0],
            ])))
            .unwrap();
        assert_eq!(c.fingers[0].layout.electrode_count(), 3);
        let e = s
            .tactile_config(tactile_request(spec(vec![[0.0, 0.0], [f64::NAN, 0.0]])))
            .unwrap_err();
        assert_eq!(e.field(), Some("session.fingers[0].layout.electrodes[1]"));
    }
}
