//! Object stabilization through tactile sensing as a session (dissertation Algorithm 5): per frame
//! and finger, taring → t_seq window → contact event and material → t_img → Ψ = {p, f, C_img} →
//! f_d (Eq 6.8, 6.9) → position mode, or force mode with the PID on Δf = f_d − f.
//!
//! A [`Stabilizer`] is created from a validated [`StabilizerConfig`] and fed [`Frame`]s in
//! timestamp order. Every frame is validated completely before any state changes, so a rejected
//! frame leaves the session as it was; errors name the field (`frame.fingers[1].electrodes: 18
//! values, layout biotac has 19`).
//!
//! Detection runs when the window sampler keeps a reading (every k-th frame); the frames between
//! reuse the latest detection. While a finger's baseline is being collected its event is
//! non-contact with certainty (the session must start without contact). Material is `unknown`
//! whenever the event is non-contact. Contact location and area are reported only in contact
//! (the GMM always finds a "highest" cluster, which on an untouched sensor is noise); the force
//! estimate is always reported, it is the controller's feedback signal.

use super::centroid_slip::{CentroidTracker, contact_centroid};
use super::desired_force::{ControlMode, DesiredForceLaw};
use super::detector::{
    ContactEvent, Detection, DetectorSample, EventDetector, Material, ModelFreeDetector,
    ModelFreeThresholds, SlipDirection, WindowSampler, check_window,
};
use super::force_estimation::{EmOptions, ForceEstimator};
use super::layout::SensorLayout;
use super::pid::{Pid, PidGains};
pub use super::readings::{FingerReading, Frame, SampleSource};
use super::tactile_image::TactileImage;
use super::taring::TareConfig;
use super::taring::TaredReading;
use crate::error::FieldError;
use serde::Serialize;

/// Most fingers a session may have.
pub const MAX_FINGERS: usize = 16;
/// Most pac samples per frame (a BioTac driver delivers 22; one value is accepted too).
pub const MAX_PAC_SAMPLES: usize = 64;
/// Frame interval assumed for the first frame (100 Hz), and the clamp of later intervals, s.
const NOMINAL_DT: f64 = 0.01;
const MAX_DT: f64 = 0.1;
const MIN_DT: f64 = 1e-4;

/// One finger of the session.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FingerConfig {
    pub name: String,
    pub layout: SensorLayout,
    pub tare: TareConfig,
    /// The sensor gives only its electrodes (a BioTac SP read through its electrodes, a
    /// capacitive pad; issue 16 part 3): its frames may send no pac, and pdc, tdc and tac are
    /// not read. Contact then comes from the electrodes alone and slip from the contact
    /// centroid's motion ([`super::centroid_slip`], at the session's `centroid_slip_mm_s`, else
    /// [`ELECTRODE_SLIP_MM_S`]); the model-free detector decides.
    pub electrodes_only: bool,
}

/// The centroid speed at which an electrodes-only finger slips when the session sets none,
/// mm/s (`make sim-stabilize`: 20 catches objects rolling out of a pinch; 40 and 80 let one and
/// two of 63 go).
pub const ELECTRODE_SLIP_MM_S: f64 = 20.0;

/// Which detector produces the contact event and material.
#[derive(Debug, Clone, PartialEq)]
pub enum DetectorChoice {
    /// Whatever the host offers by default: the server's loaded model
    /// (`tactile::lstm_detector`) when it fits the session, else the model-free detector with
    /// default thresholds. [`Stabilizer::new`] uses the model-free detector.
    Default,
    /// The model-free fallback (see `detector`).
    ModelFree(ModelFreeThresholds),
    /// A learned model by name (the LSTM of Eq 6.1–6.4); the caller supplies it with
    /// [`Stabilizer::with_detectors`].
    Model(String),
    /// A calibration fitted on the user's recordings, by name (`calibration`); the caller
    /// supplies its [`super::calibration::CalibratedDetector`] with
    /// [`Stabilizer::with_detectors`].
    Calibration(String),
}

/// With the latch ([`DesiredForceLaw::latch_slip`]), a slip that goes on counts as one more
/// episode every this many seconds: an object still slipping at the raised force needs more.
pub const LATCH_STEP_S: f64 = 0.1;

/// Session parameters (issue 5 point 1).
#[derive(Debug, Clone, PartialEq)]
pub struct StabilizerConfig {
    pub fingers: Vec<FingerConfig>,
    /// l of t_seq (Table 6.1: 32).
    pub window_length: usize,
    /// k: every k-th reading (Table 6.1: 3, i.e. 33.3 Hz from 100 Hz).
    pub stride: usize,
    /// f0, δf_m, δf_s, f_min, f_max (Eq 6.8, 6.9).
    pub law: DesiredForceLaw,
    pub pid: PidGains,
    /// α of Eq 6.6.
    pub alpha: f64,
    /// Newtons per raw unit of Eq 6.7; `None` = raw units.
    pub calibration_gain: Option<f64>,
    pub detector: DetectorChoice,
    /// Slip from the contact centroid's motion ([`super::centroid_slip`]): a finger in contact
    /// whose centroid moves faster than this (mm/s) slips, whatever the detector says. `None`
    /// (the default): slip is the detector's alone, as in the dissertation.
    pub centroid_slip_mm_s: Option<f64>,
}

impl Default for StabilizerConfig {
    fn default() -> Self {
        Self {
            fingers: Vec::new(),
            window_length: 32,
            stride: 3,
            law: DesiredForceLaw::default(),
            pid: PidGains::default(),
            alpha: 0.5,
            calibration_gain: None,
            detector: DetectorChoice::Default,
            centroid_slip_mm_s: None,
        }
    }
}

impl StabilizerConfig {
    /// A session of the given fingers with every other parameter at its default.
    pub fn for_fingers(fingers: Vec<FingerConfig>) -> Self {
        Self {
            fingers,
            ..Default::default()
        }
    }

    /// Checks every parameter; errors name `session.<field>`.
    pub fn validate(&self) -> Result<(), FieldError> {
        if self.fingers.is_empty() || self.fingers.len() > MAX_FINGERS {
            return Err(FieldError::new(
                "session.fingers",
                format!(
                    "must list 1 to {MAX_FINGERS} fingers, got {}",
                    self.fingers.len()
                ),
            ));
        }
        for (i, f) in self.fingers.iter().enumerate() {
            if f.name.trim().is_empty() || f.name.len() > 64 {
                return Err(FieldError::new(
                    format!("session.fingers[{i}].name"),
                    "must be 1 to 64 characters",
                ));
            }
            if self.fingers[..i].iter().any(|g| g.name == f.name) {
                return Err(FieldError::new(
                    format!("session.fingers[{i}].name"),
                    format!("finger '{}' is listed twice", f.name),
                ));
            }
            if let super::taring::Baseline::FirstFrames(n) = f.tare.baseline
                && !(1..=10_000).contains(&n)
            {
                return Err(FieldError::new(
                    format!("session.fingers[{i}].tare.baseline"),
                    format!("must use 1 to 10000 frames, got {n}"),
                ));
            }
        }
        check_window(self.window_length, self.stride, "session.")?;
        self.law.validate("session")?;
        self.pid.validate("session.pid")?;
        if !(self.alpha > 0.0 && self.alpha <= 1.0) {
            return Err(FieldError::new(
                "session.alpha",
                format!("must be in (0, 1], got {}", self.alpha),
            ));
        }
        if let Some(g) = self.calibration_gain
            && !(g.is_finite() && g > 0.0)
        {
            return Err(FieldError::new(
                "session.calibration_gain",
                format!("must be a positive number, got {g}"),
            ));
        }
        if let DetectorChoice::ModelFree(t) = &self.detector {
            t.validate("session.detector")?;
        }
        if let Some(v) = self.centroid_slip_mm_s
            && !(v.is_finite() && v > 0.0)
        {
            return Err(FieldError::new(
                "session.centroid_slip_mm_s",
                format!("must be a positive number, got {v}"),
            ));
        }
        Ok(())
    }
}

/// Unit of the reported forces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ForceUnit {
    /// Raw tared sensor units of Eq 6.7.
    Raw,
    /// Newtons (a calibration gain is configured).
    Newton,
}

/// Per-finger result of one frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FingerResult {
    pub finger: String,
    /// False while the baseline is still being collected.
    pub tared: bool,
    pub event: ContactEvent,
    /// P(non-contact), P(contact), P(slip).
    pub event_probabilities: [f64; 3],
    pub material: Material,
    /// P(paper), P(foam), P(plastic), P(metal), when known and in contact.
    pub material_probabilities: Option<[f64; 4]>,
    /// The direction of the slip, while slipping, when the session's calibration was fitted
    /// on directions.
    pub slip_direction: Option<SlipDirection>,
    /// P over [`SlipDirection::ALL`] (north, east, south, west, clockwise, anticlockwise) with
    /// `slip_direction`.
    pub slip_direction_probabilities: Option<[f64; 6]>,
    /// Estimated normal force f (Eq 6.7).
    pub force: f64,
    pub force_unit: ForceUnit,
    /// Contact centre on the tactile image (row, col), in contact only.
    pub contact_location: Option<[f64; 2]>,
    pub contact_area_pixels: usize,
    pub contact_area_mm2: f64,
    /// f_d (Eq 6.8, 6.9, clipped).
    pub desired_force: f64,
    pub mode: ControlMode,
    /// PID output in force mode; `None` in position mode.
    pub setpoint: Option<f64>,
}

/// Result of one frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameResult {
    pub timestamp: f64,
    pub fingers: Vec<FingerResult>,
}

pub(super) struct FingerState {
    config: FingerConfig,
    source: SampleSource,
    sampler: WindowSampler<DetectorSample>,
    detector: Box<dyn EventDetector>,
    last_detection: Option<Detection>,
    pid: Pid,
    /// Slip episodes since this contact began (a slip lasting longer counts again every
    /// [`LATCH_STEP_S`]), whether the last frame slipped, and when the count last rose (the
    /// latch of [`DesiredForceLaw::latch_slip`]).
    slip_episodes: u32,
    slipping: bool,
    raised_at: f64,
    centroid: CentroidTracker,
}

/// A stabilization session (module doc).
pub struct Stabilizer {
    config: StabilizerConfig,
    estimator: ForceEstimator,
    fingers: Vec<FingerState>,
    last_timestamp: Option<f64>,
    frames: u64,
}

impl std::fmt::Debug for Stabilizer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stabilizer")
            .field("config", &self.config)
            .field("frames", &self.frames)
            .finish()
    }
}

impl Stabilizer {
    /// A session with the model-free detector. A config that names a model is rejected here
    /// (`session.detector`); use [`Stabilizer::with_detectors`] to supply it.
    pub fn new(config: StabilizerConfig) -> Result<Self, FieldError> {
        config.validate()?;
        let t = match &config.detector {
            DetectorChoice::ModelFree(t) => *t,
            DetectorChoice::Default => ModelFreeThresholds::default(),
            DetectorChoice::Model(name) => {
                return Err(FieldError::new(
                    "session.detector",
                    format!("model '{name}' is not loaded"),
                ));
            }
            DetectorChoice::Calibration(name) => {
                return Err(FieldError::new(
                    "session.detector.calibration",
                    format!("calibration '{name}' is not loaded"),
                ));
            }
        };
        let detectors = config
            .fingers
            .iter()
            .map(|_| Box::new(ModelFreeDetector::new(t)) as Box<dyn EventDetector>)
            .collect();
        Self::with_detectors(config, detectors)
    }

    /// A session with one caller-supplied detector per finger (e.g. an LSTM model).
    pub fn with_detectors(
        config: StabilizerConfig,
        detectors: Vec<Box<dyn EventDetector>>,
    ) -> Result<Self, FieldError> {
        config.validate()?;
        if detectors.len() != config.fingers.len() {
            return Err(FieldError::new(
                "session.detector",
                format!(
                    "{} detectors for {} fingers",
                    detectors.len(),
                    config.fingers.len()
                ),
            ));
        }
        let fingers = config
            .fingers
            .iter()
            .cloned()
            .zip(detectors)
            .map(|(f, detector)| FingerState {
                source: SampleSource::new(f.tare, f.layout.electrode_count())
                    .electrodes_only(f.electrodes_only),
                sampler: WindowSampler::new(config.window_length, config.stride),
                detector,
                last_detection: None,
                pid: Pid::new(config.pid),
                slip_episodes: 0,
                slipping: false,
                raised_at: f64::NEG_INFINITY,
                centroid: CentroidTracker::default(),
                config: f,
            })
            .collect();
        let estimator = ForceEstimator {
            alpha: config.alpha,
            em: EmOptions::default(),
            calibration_gain: config.calibration_gain,
        };
        Ok(Self {
            config,
            estimator,
            fingers,
            last_timestamp: None,
            frames: 0,
        })
    }

    pub fn config(&self) -> &StabilizerConfig {
        &self.config
    }

    /// Frames accepted so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Checks a frame against the session without changing anything.
    pub fn validate_frame(&self, frame: &Frame) -> Result<(), FieldError> {
        if !frame.timestamp.is_finite() {
            return Err(FieldError::new(
                "frame.timestamp",
                format!(
                    "must be a finite number of seconds, got {}",
                    frame.timestamp
                ),
            ));
        }
        if let Some(prev) = self.last_timestamp
            && frame.timestamp <= prev
        {
            return Err(FieldError::new(
                "frame.timestamp",
                format!(
                    "out of order: {} is not after the previous frame's {}",
                    frame.timestamp, prev
                ),
            ));
        }
        if frame.fingers.len() != self.fingers.len() {
            return Err(FieldError::new(
                "frame.fingers",
                format!(
                    "{} readings, the session has {} fingers",
                    frame.fingers.len(),
                    self.fingers.len()
                ),
            ));
        }
        for (i, (r, f)) in frame.fingers.iter().zip(&self.fingers).enumerate() {
            let layout = &f.config.layout;
            if r.electrodes.len() != layout.electrode_count() {
                return Err(FieldError::new(
                    format!("frame.fingers[{i}].electrodes"),
                    format!(
                        "{} values, layout {} has {}",
                        r.electrodes.len(),
                        layout.name,
                        layout.electrode_count()
                    ),
                ));
            }
            if (r.pac.is_empty() && !f.config.electrodes_only) || r.pac.len() > MAX_PAC_SAMPLES {
                return Err(FieldError::new(
                    format!("frame.fingers[{i}].pac"),
                    format!(
                        "{} values; send one value or the driver's samples (22 for a BioTac), at most {MAX_PAC_SAMPLES} (none: declare the finger electrodes_only)",
                        r.pac.len()
                    ),
                ));
            }
            for (name, v) in [("pdc", r.pdc), ("tdc", r.tdc), ("tac", r.tac)] {
                if !v.is_finite() {
                    return Err(FieldError::new(
                        format!("frame.fingers[{i}].{name}"),
                        format!("must be finite, got {v}"),
                    ));
                }
            }
            for (name, vals) in [("pac", &r.pac), ("electrodes", &r.electrodes)] {
                if let Some(j) = vals.iter().position(|v| !v.is_finite()) {
                    return Err(FieldError::new(
                        format!("frame.fingers[{i}].{name}[{j}]"),
                        format!("must be finite, got {}", vals[j]),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Processes one frame (Algorithm 5, one iteration for every finger).
    pub fn step(&mut self, frame: &Frame) -> Result<FrameResult, FieldError> {
        let at = self.begin(frame)?;
        let sensed: Vec<Sensed> = self
            .fingers
            .iter_mut()
            .zip(&frame.fingers)
            .map(|(f, r)| f.sense(r))
            .collect();
        for (f, s) in self.fingers.iter_mut().zip(&sensed) {
            if s.due {
                f.detect_alone();
            }
        }
        Ok(self.finish(frame, at, sensed))
    }

    /// Validates a frame and advances the session's clock: the frame's timestamp and time step.
    pub(super) fn begin(&mut self, frame: &Frame) -> Result<(f64, f64), FieldError> {
        self.validate_frame(frame)?;
        let dt = match self.last_timestamp {
            Some(prev) => (frame.timestamp - prev).clamp(MIN_DT, MAX_DT),
            None => NOMINAL_DT,
        };
        self.last_timestamp = Some(frame.timestamp);
        self.frames += 1;
        Ok((frame.timestamp, dt))
    }

    /// The frame's result once every finger due for detection has its new detection.
    pub(super) fn finish(
        &mut self,
        frame: &Frame,
        at: (f64, f64),
        sensed: Vec<Sensed>,
    ) -> FrameResult {
        let unit = if self.config.calibration_gain.is_some() {
            ForceUnit::Newton
        } else {
            ForceUnit::Raw
        };
        let law = self.config.law;
        let estimator = self.estimator;
        let moving = self.config.centroid_slip_mm_s;
        let results = self
            .fingers
            .iter_mut()
            .zip(sensed)
            .map(|(f, s)| f.act(s, at, &law, &estimator, unit, moving))
            .collect();
        FrameResult {
            timestamp: frame.timestamp,
            fingers: results,
        }
    }

    pub(super) fn fingers(&self) -> &[FingerState] {
        &self.fingers
    }

    pub(super) fn fingers_mut(&mut self) -> &mut [FingerState] {
        &mut self.fingers
    }
}

/// Runs a whole recorded sequence through a fresh session (the REST analyze endpoint): one
/// result per frame. An error names the frame by index (`frames[12].fingers[0].electrodes: …`).
pub fn analyze(config: StabilizerConfig, frames: &[Frame]) -> Result<Vec<FrameResult>, FieldError> {
    analyze_session(Stabilizer::new(config)?, frames)
}

/// [`analyze`] with caller-supplied detectors (one per finger, see
/// [`Stabilizer::with_detectors`]).
pub fn analyze_with_detectors(
    config: StabilizerConfig,
    detectors: Vec<Box<dyn EventDetector>>,
    frames: &[Frame],
) -> Result<Vec<FrameResult>, FieldError> {
    analyze_session(Stabilizer::with_detectors(config, detectors)?, frames)
}

fn analyze_session(mut s: Stabilizer, frames: &[Frame]) -> Result<Vec<FrameResult>, FieldError> {
    frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            s.step(f).map_err(|e| {
                let field = match e.field.strip_prefix("frame") {
                    Some(rest) => format!("frames[{i}]{rest}"),
                    None => e.field,
                };
                FieldError::new(field, e.message)
            })
        })
        .collect()
}

/// One finger's frame up to detection ([`FingerState::sense`]).
pub(super) struct Sensed {
    tared: TaredReading,
    /// Whether the baseline was complete (the reading gave a detector sample).
    sampled: bool,
    /// Whether the finger's detector is to run on its window for this frame.
    pub due: bool,
}

impl FingerState {
    /// Taring and the window t_seq (Algorithm 5, line 4 up to the detector): detection is due
    /// when the sampler kept the reading, or when the finger has none yet.
    pub(super) fn sense(&mut self, r: &FingerReading) -> Sensed {
        let (tared, sample) = self.source.next(r);
        let sampled = sample.is_some();
        let due = match sample {
            Some(sample) => {
                let kept = self.sampler.push(sample);
                // Contiguous now, for the detectors that borrow it (`window_ref`).
                self.sampler.window();
                kept || self.last_detection.is_none()
            }
            None => false,
        };
        Sensed {
            tared,
            sampled,
            due,
        }
    }

    /// The finger's window t_seq, oldest first (contiguous since [`Self::sense`]).
    pub(super) fn window_ref(&self) -> &[DetectorSample] {
        self.sampler.window_ref()
    }

    pub(super) fn detector(&self) -> &dyn EventDetector {
        self.detector.as_ref()
    }

    /// Runs the finger's own detector on its window.
    pub(super) fn detect_alone(&mut self) {
        self.last_detection = Some(self.detector.detect(self.sampler.window()));
    }

    pub(super) fn set_detection(&mut self, d: Detection) {
        self.last_detection = Some(d);
    }

    /// The rest of one finger's frame (`at`: the frame's timestamp and the time step, s);
    /// `moving`: the session's `centroid_slip_mm_s`.
    fn act(
        &mut self,
        sensed: Sensed,
        at: (f64, f64),
        law: &DesiredForceLaw,
        estimator: &ForceEstimator,
        unit: ForceUnit,
        moving: Option<f64>,
    ) -> FingerResult {
        let (timestamp, dt) = at;
        let moving = moving.or(self.config.electrodes_only.then_some(ELECTRODE_SLIP_MM_S));
        let tared = sensed.tared;
        // Line 4: detection on t_seq (only once the baseline is complete).
        let mut detection = if sensed.sampled {
            self.last_detection.clone().expect("detected when due")
        } else {
            Detection {
                event: ContactEvent::NonContact,
                event_probabilities: [1.0, 0.0, 0.0],
                material: Material::Unknown,
                material_probabilities: None,
                slip_direction: None,
            }
        };
        let in_contact = detection.event != ContactEvent::NonContact;
        // Slip the contact's motion shows (module doc of centroid_slip), tracked only when the
        // session asks for it: the contact's and the slip's probabilities become slip's.
        if let Some(limit) = moving
            && let Some(v) = self.centroid.push(
                timestamp,
                in_contact
                    .then(|| {
                        let noise = self.source.electrode_noise();
                        contact_centroid(&self.config.layout, &tared.electrodes, noise)
                    })
                    .flatten(),
            )
            && v > limit
        {
            let p = detection.event_probabilities;
            detection.event = ContactEvent::Slip;
            detection.event_probabilities = [p[0], 0.0, p[1] + p[2]];
        }
        let (material, material_probabilities) = if in_contact {
            (detection.material, detection.material_probabilities)
        } else {
            (Material::Unknown, None)
        };
        // Line 5: Ψ = {p, f, C_img} from t_img.
        let img = TactileImage::from_electrodes(&self.config.layout, &tared.electrodes);
        let psi = estimator.estimate(&img, &self.config.layout);
        // Lines 6–10.
        match detection.event {
            ContactEvent::NonContact => self.slip_episodes = 0,
            ContactEvent::Slip if !self.slipping || timestamp - self.raised_at >= LATCH_STEP_S => {
                self.slip_episodes += 1;
                self.raised_at = timestamp;
            }
            _ => {}
        }
        self.slipping = detection.event == ContactEvent::Slip;
        let (desired_force, mode) = law.desired(detection.event, material, self.slip_episodes);
        let setpoint = match mode {
            ControlMode::Position => {
                self.pid.reset();
                None
            }
            ControlMode::Force => Some(self.pid.step(desired_force, psi.force, dt)),
        };
        let direction = detection
            .slip_direction
            .filter(|_| detection.event == ContactEvent::Slip);
        FingerResult {
            finger: self.config.name.clone(),
            tared: self.source.is_ready(),
            event: detection.event,
            event_probabilities: detection.event_probabilities,
            material,
            material_probabilities,
            slip_direction: direction.map(|(d, _)| d),
            slip_direction_probabilities: direction.map(|(_, p)| p),
            force: psi.force,
            force_unit: unit,
            contact_location: if in_contact { psi.location } else { None },
            contact_area_pixels: if in_contact { psi.area_pixels } else { 0 },
            contact_area_mm2: if in_contact { psi.area_mm2 } else { 0.0 },
            desired_force,
            mode,
            setpoint,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tactile::taring::{Baseline, ElectrodePolarity};

    fn finger(name: &str, layout: SensorLayout) -> FingerConfig {
        FingerConfig {
            electrodes_only: false,
            name: name.into(),
            layout,
            tare: TareConfig {
                baseline: Baseline::FirstFrames(5),
                electrode_polarity: ElectrodePolarity::Falling,
            },
        }
    }

    fn session() -> Stabilizer {
        Stabilizer::new(StabilizerConfig::for_fingers(vec![
            finger("th", SensorLayout::biotac()),
            finger("ff", SensorLayout::biotac()),
        ]))
        .unwrap()
    }

    fn reading(n: usize, pdc: f64, ele: f64) -> FingerReading {
        FingerReading {
            pdc,
            pac: vec![2000.0; 22],
            tdc: 2500.0,
            tac: 2000.0,
            electrodes: vec![ele; n],
        }
    }

    #[test]
    fn stabilizer_rejects_mismatched_frames_with_field_named_errors() {
        let mut s = session();
        let ok = Frame {
            timestamp: 1.0,
            fingers: vec![reading(19, 2000.0, 3000.0), reading(19, 2000.0, 3000.0)],
        };
        s.step(&ok).unwrap();
        let mut bad = ok.clone();
        bad.timestamp = 1.01;
        bad.fingers[1].electrodes.pop();
        let e = s.step(&bad).unwrap_err();
        assert_eq!(
            e.to_string(),
            "frame.fingers[1].electrodes: 18 values, layout biotac has 19"
        );
        let e = s
            .step(&Frame {
                timestamp: 1.02,
                fingers: vec![reading(19, 2000.0, 3000.0)],
            })
            .unwrap_err();
        assert_eq!(e.field, "frame.fingers");
        assert!(e.message.contains("1 readings, the session has 2 fingers"));
        let mut late = ok.clone();
        late.timestamp = 0.5;
        let e = s.step(&late).unwrap_err();
        assert_eq!(e.field, "frame.timestamp");
        assert!(e.message.contains("out of order"));
        let mut nan = ok.clone();
        nan.timestamp = 1.03;
        nan.fingers[0].electrodes[4] = f64::NAN;
        assert_eq!(
            s.step(&nan).unwrap_err().field,
            "frame.fingers[0].electrodes[4]"
        );
        let mut nopac = ok.clone();
        nopac.timestamp = 1.04;
        nopac.fingers[0].pac.clear();
        assert_eq!(s.step(&nopac).unwrap_err().field, "frame.fingers[0].pac");
        // Rejected frames changed nothing: the next good frame is accepted.
        let mut next = ok.clone();
        next.timestamp = 1.05;
        s.step(&next).unwrap();
        assert_eq!(s.frames(), 2);
    }

    #[test]
    fn biotac_sp_fingers_take_24_electrodes_and_analyze_names_the_frame() {
        let mut c = StabilizerConfig::for_fingers(vec![finger("th", SensorLayout::biotac_sp())]);
        c.window_length = 4;
        let good = |t: f64| Frame {
            timestamp: t,
            fingers: vec![reading(24, 2000.0, 3000.0)],
        };
        let out = analyze(c.clone(), &[good(0.0), good(0.01)]).unwrap();
        assert_eq!(out.len(), 2);
        let mut bad = good(0.02);
        bad.fingers[0].electrodes.truncate(19);
        let e = analyze(c, &[good(0.0), good(0.01), bad]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "frames[2].fingers[0].electrodes: 19 values, layout biotac_sp has 24"
        );
    }

    #[test]
    fn frames_read_from_json() {
        let f: Frame = serde_json::from_str(
            r#"{"timestamp": 1.5, "fingers": [{"pdc": 1, "pac": [2], "tdc": 3, "tac": 4,
                "electrodes": [5, 6]}]}"#,
        )
        .unwrap();
        assert_eq!(f.fingers[0].electrodes, vec![5.0, 6.0]);
        assert!(
            serde_json::from_str::<Frame>(r#"{"timestamp": 1, "fingers": [], "x": 1}"#).is_err()
        );
    }

    #[test]
    fn session_config_validation_names_fields() {
        let e = Stabilizer::new(StabilizerConfig::default()).unwrap_err();
        assert_eq!(e.field, "session.fingers");
        let mut c = StabilizerConfig::for_fingers(vec![finger("a", SensorLayout::biotac())]);
        c.stride = 0;
        assert_eq!(
            Stabilizer::new(c.clone()).unwrap_err().field,
            "session.stride"
        );
        c.stride = 3;
        c.alpha = 1.5;
        assert_eq!(
            Stabilizer::new(c.clone()).unwrap_err().field,
            "session.alpha"
        );
        c.alpha = 0.5;
        c.detector = DetectorChoice::Model("lstm".into());
        assert_eq!(
            Stabilizer::new(c.clone()).unwrap_err().field,
            "session.detector"
        );
        c.detector = DetectorChoice::ModelFree(Default::default());
        c.fingers.push(finger("a", SensorLayout::biotac_sp()));
        assert_eq!(
            Stabilizer::new(c).unwrap_err().field,
            "session.fingers[1].name"
        );
    }

    #[test]
    fn press_and_slide_switch_modes_and_raise_the_desired_force() {
        // One classic BioTac with raw counts: 5 baseline frames, then a press (pdc +80, three
        // electrodes −150: impedance falls), then the same press with strong pac vibration.
        let mut c = StabilizerConfig::for_fingers(vec![finger("th", SensorLayout::biotac())]);
        c.window_length = 8;
        c.stride = 1;
        let law = c.law;
        let mut s = Stabilizer::new(c).unwrap();
        let mut t = 0.0;
        let mut run = |s: &mut Stabilizer, n: usize, pdc: f64, press: bool, vib: bool| {
            let mut last = None;
            for i in 0..n {
                t += 0.01;
                let mut r = reading(19, 2000.0 + pdc, 3000.0);
                if press {
                    for e in [16, 17, 1] {
                        r.electrodes[e] -= 150.0;
                    }
                }
                if vib {
                    r.pac = (0..22)
                        .map(|j| 2000.0 + if (i + j) % 2 == 0 { 60.0 } else { -60.0 })
                        .collect();
                }
                last = Some(
                    s.step(&Frame {
                        timestamp: t,
                        fingers: vec![r],
                    })
                    .unwrap(),
                );
            }
            last.unwrap().fingers.remove(0)
        };
        let rest = run(&mut s, 10, 0.0, false, false);
        assert!(rest.tared);
        assert_eq!(rest.event, ContactEvent::NonContact);
        assert_eq!(rest.mode, ControlMode::Position);
        assert_eq!(rest.setpoint, None);
        assert_eq!(rest.material, Material::Unknown);
        let press = run(&mut s, 10, 80.0, true, false);
        assert_eq!(press.event, ContactEvent::Contact);
        assert_eq!(press.mode, ControlMode::Force);
        assert_eq!(press.desired_force, law.f0);
        assert!(press.setpoint.is_some());
        assert!(press.force > 100.0, "force {}", press.force);
        // The three pressed electrodes plus the empty pixels whose only filled neighbours are
        // pressed ones (they take the value 150 too): every contact pixel reads 150, P_c ≈ 1.
        assert!(press.contact_area_pixels >= 3);
        assert!((press.force - 150.0 * press.contact_area_pixels as f64).abs() < 1e-3);
        let p = press.contact_location.unwrap();
        assert!(
            (0.0..=7.0).contains(&p[0]) && (0.0..=4.0).contains(&p[1]),
            "{p:?}"
        );
        let slide = run(&mut s, 10, 80.0, true, true);
        assert_eq!(slide.event, ContactEvent::Slip);
        assert_eq!(slide.desired_force, law.f0 + law.delta_slip);
    }
}
