//! Online detection of the contact event and the material (dissertation ch. 6.3, Eq 6.3, 6.4):
//! the window sampler t_seq and the model-free detector used when no LSTM model is loaded.
//!
//! # Window (Table 6.1)
//! [`WindowSampler`] keeps every k-th reading and the last l of them: l = 32 at k = 3 (33.3 Hz
//! from 100 Hz), i.e. 0.96 s of history, the dissertation's choice. Detection runs every frame on
//! the window as it is (shorter at the start of a session).
//!
//! # Model-free detector
//! A physically motivated fallback, **not fitted on any data** (thresholds are configurable):
//! * **Contact** from the tared static pressure pdc and the electrode deviation (mean of the three
//!   largest tared electrode deviations — a touch deforms the skin over at least a few
//!   electrodes). Default thresholds 15 pdc counts and 10 electrode counts: several times the
//!   few-count at-rest noise of the 12-bit channels, well below the tens to hundreds of counts of a
//!   firm touch. The contact level x = max(pdc / pdc_threshold, electrode / electrode_threshold),
//!   averaged over the newest quarter of the window (at least one sample, to keep the delay
//!   short), gives P(contact) = σ(s·(x − 1)) with steepness s (default 6).
//! * **Slip** from the vibration of the dynamic pressure pac: sliding excites the skin at tens to
//!   hundreds of Hz, which the 2.2 kHz pac samples see as high-frequency energy. Per frame the
//!   vibration is the RMS of the second differences of the 22 pac samples divided by √6 (for white
//!   noise this equals its standard deviation; a linear drift of the AC-coupled channel within the
//!   10 ms frame contributes nothing); when a driver sends one pac value per frame it is
//!   |pac_t − pac_{t−1}|/√2 instead. The RMS over
//!   the window, v, gives P(slip | contact) = σ(s·(v / vibration_threshold − 1)); default threshold
//!   10 counts.
//! * P(non-contact) = 1 − P(contact), P(contact event) = P(contact)·(1 − P(slip | contact)),
//!   P(slip) = P(contact)·P(slip | contact); the event is the most probable.
//! * **Material**: reported as `unknown` with no probabilities. The thermal channels could support
//!   a heat-flow heuristic (metal draws heat fastest, foam slowest), but without calibration data
//!   its output would be a guess, so the model-free detector does not pretend to know; a loaded
//!   model supplies materials through [`EventDetector`].

use crate::error::FieldError;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// The contact event c^s (Eq 6.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactEvent {
    NonContact,
    Contact,
    Slip,
}

impl ContactEvent {
    pub const ALL: [ContactEvent; 3] = [Self::NonContact, Self::Contact, Self::Slip];

    pub fn name(self) -> &'static str {
        match self {
            Self::NonContact => "non_contact",
            Self::Contact => "contact",
            Self::Slip => "slip",
        }
    }

    /// An event by its name (surrounding space ignored).
    pub fn parse(text: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|e| e.name() == text.trim())
    }
}

/// The material c^m (Eq 6.4); `Unknown` while not in contact or when no model says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Material {
    Paper,
    Foam,
    Plastic,
    Metal,
    Unknown,
}

impl Material {
    /// The four classes of Eq 6.4, in the order of the probability vectors.
    pub const CLASSES: [Material; 4] = [Self::Paper, Self::Foam, Self::Plastic, Self::Metal];

    pub fn name(self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::Foam => "foam",
            Self::Plastic => "plastic",
            Self::Metal => "metal",
            Self::Unknown => "unknown",
        }
    }
}

/// The direction a held object slips in, on the sensor's own skin: four translations (north,
/// east, south, west: the sensor's own axes) and two turns — the six slip labels of the BioTac
/// SP direction-of-slip recordings (yayaneath/BioTacSP-DoS: n, e, s, w, cw, aw). Only a
/// calibration fitted on recordings labelled with directions reports one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SlipDirection {
    North,
    East,
    South,
    West,
    Clockwise,
    Anticlockwise,
}

impl SlipDirection {
    /// In the order of the probability vectors.
    pub const ALL: [SlipDirection; 6] = [
        Self::North,
        Self::East,
        Self::South,
        Self::West,
        Self::Clockwise,
        Self::Anticlockwise,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Self::North => "north",
            Self::East => "east",
            Self::South => "south",
            Self::West => "west",
            Self::Clockwise => "clockwise",
            Self::Anticlockwise => "anticlockwise",
        }
    }

    /// A name or the data's short label (n, e, s, w, cw, aw), any case.
    pub fn parse(text: &str) -> Option<Self> {
        let t = text.trim().to_ascii_lowercase();
        let short = ["n", "e", "s", "w", "cw", "aw"];
        Self::ALL
            .into_iter()
            .zip(short)
            .find(|(d, s)| d.name() == t || *s == t)
            .map(|(d, _)| d)
    }
}

/// One sampled reading of t_seq, tared ("larger = more contact", see `taring`).
#[derive(Debug, Clone, PartialEq)]
pub struct DetectorSample {
    pub pdc: f64,
    /// Mean of the frame's pac samples (the level a 23-feature model expects).
    pub pac: f64,
    /// High-frequency vibration of pac in this frame (see the module doc), counts.
    pub pac_vibration: f64,
    /// The frame's pac samples as the driver sent them (one, or a BioTac's 22): the spectrum a
    /// calibration reads (`calibration::features`).
    pub pac_samples: Vec<f64>,
    pub tdc: f64,
    pub tac: f64,
    pub electrodes: Vec<f64>,
}

/// Result of one detection.
#[derive(Debug, Clone, PartialEq)]
pub struct Detection {
    pub event: ContactEvent,
    /// P(non-contact), P(contact), P(slip).
    pub event_probabilities: [f64; 3],
    pub material: Material,
    /// P(paper), P(foam), P(plastic), P(metal); `None` when not estimated.
    pub material_probabilities: Option<[f64; 4]>,
    /// The direction a slip would take and P over [`SlipDirection::ALL`], from a calibration
    /// fitted on directions, in contact; `None` otherwise (the session reports it only while
    /// the finger slips).
    pub slip_direction: Option<(SlipDirection, [f64; 6])>,
}

/// Anything that turns a window t_seq into a detection: the model-free detector here, an LSTM
/// model (Eq 6.1–6.4) in the server when one is loaded.
pub trait EventDetector: Send {
    /// `window` is oldest first; it is never empty.
    fn detect(&mut self, window: &[DetectorSample]) -> Detection;

    /// Detectors with the same key run one model whose runs can take the windows of several
    /// sessions at once ([`Self::detect_many`], `Stabilizer::step_many`); None (the default):
    /// this detector decides alone.
    fn batch_key(&self) -> Option<usize> {
        None
    }

    /// The detections of several windows (each oldest first, never empty), of detectors that
    /// share this one's [`Self::batch_key`], in one run of their model, in the windows' order.
    /// None (the default): the detector cannot, and each detector detects its own window.
    fn detect_many(&self, windows: &[&[DetectorSample]]) -> Option<Vec<Detection>> {
        let _ = windows;
        None
    }
}

/// The window t_seq's bounds, for a session and for a calibration alike: l of 1 to 1024
/// readings, a stride k of 1 to 100 (`prefix` names where they stand, e.g. `session.`).
pub fn check_window(window_length: usize, stride: usize, prefix: &str) -> Result<(), FieldError> {
    if !(1..=1024).contains(&window_length) {
        return Err(FieldError::new(
            format!("{prefix}window_length"),
            format!("must be 1 to 1024, got {window_length}"),
        ));
    }
    if !(1..=100).contains(&stride) {
        return Err(FieldError::new(
            format!("{prefix}stride"),
            format!("must be 1 to 100, got {stride}"),
        ));
    }
    Ok(())
}

/// t_seq: every k-th reading, the last l of them (Table 6.1: l = 32, k = 3).
#[derive(Debug, Clone)]
pub struct WindowSampler<T> {
    length: usize,
    stride: usize,
    seen: usize,
    buf: VecDeque<T>,
}

impl<T> WindowSampler<T> {
    /// `length` l ≥ 1, `stride` k ≥ 1 (validated by the stabilizer config).
    pub fn new(length: usize, stride: usize) -> Self {
        Self {
            length: length.max(1),
            stride: stride.max(1),
            seen: 0,
            buf: VecDeque::with_capacity(length.max(1)),
        }
    }

    /// Offers a reading; it is kept when it is the 1st, (k+1)-th, (2k+1)-th … Returns whether it
    /// was kept.
    pub fn push(&mut self, x: T) -> bool {
        let keep = self.seen.is_multiple_of(self.stride);
        self.seen += 1;
        if keep {
            if self.buf.len() == self.length {
                self.buf.pop_front();
            }
            self.buf.push_back(x);
        }
        keep
    }

    pub fn is_full(&self) -> bool {
        self.buf.len() == self.length
    }

    pub fn len(&self) -> usize {
        self.buf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.buf.is_empty()
    }

    /// The window, oldest first.
    pub fn window(&mut self) -> &[T] {
        self.buf.make_contiguous()
    }

    /// The window without making it contiguous: the readings in their first run only, all of
    /// them once [`Self::window`] ran after the last push.
    pub fn window_ref(&self) -> &[T] {
        self.buf.as_slices().0
    }
}

/// Thresholds of the model-free detector (see the module doc for their physical meaning).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ModelFreeThresholds {
    /// Tared pdc at which P(contact) = ½, counts.
    pub pdc_contact: f64,
    /// Mean of the three largest tared electrode deviations at which P(contact) = ½, counts.
    pub electrode_contact: f64,
    /// Window RMS of the pac vibration at which P(slip | contact) = ½, counts.
    pub slip_vibration: f64,
    /// Steepness s of the logistic curves (per threshold unit).
    pub steepness: f64,
}

impl Default for ModelFreeThresholds {
    fn default() -> Self {
        Self {
            pdc_contact: 15.0,
            electrode_contact: 10.0,
            slip_vibration: 10.0,
            steepness: 6.0,
        }
    }
}

impl ModelFreeThresholds {
    /// Checks that every threshold is positive and finite; errors name `prefix.field`.
    pub fn validate(&self, prefix: &str) -> Result<(), crate::error::FieldError> {
        for (name, v) in [
            ("pdc_contact", self.pdc_contact),
            ("electrode_contact", self.electrode_contact),
            ("slip_vibration", self.slip_vibration),
            ("steepness", self.steepness),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(crate::error::FieldError::new(
                    format!("{prefix}.{name}"),
                    format!("must be a positive number, got {v}"),
                ));
            }
        }
        Ok(())
    }
}

/// The model-free detector (module doc).
#[derive(Debug, Clone, Default)]
pub struct ModelFreeDetector {
    pub thresholds: ModelFreeThresholds,
}

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// Mean of the three largest values (fewer when there are fewer).
fn top3_mean(e: &[f64]) -> f64 {
    let mut top = [f64::NEG_INFINITY; 3];
    for &v in e {
        if v > top[0] {
            top[0] = v;
            top.sort_by(f64::total_cmp);
        }
    }
    let got: Vec<f64> = top.into_iter().filter(|v| v.is_finite()).collect();
    if got.is_empty() {
        0.0
    } else {
        got.iter().sum::<f64>() / got.len() as f64
    }
}

impl ModelFreeDetector {
    pub fn new(thresholds: ModelFreeThresholds) -> Self {
        Self { thresholds }
    }

    /// Contact level x in threshold units for one sample.
    pub fn contact_level(&self, s: &DetectorSample) -> f64 {
        let t = &self.thresholds;
        (s.pdc / t.pdc_contact).max(top3_mean(&s.electrodes) / t.electrode_contact)
    }
}

impl EventDetector for ModelFreeDetector {
    fn detect(&mut self, window: &[DetectorSample]) -> Detection {
        let t = self.thresholds;
        let n = window.len().max(1);
        let recent = &window[window.len() - (n / 4).max(1).min(window.len())..];
        let x = recent.iter().map(|s| self.contact_level(s)).sum::<f64>() / recent.len() as f64;
        let p_contact = sigmoid(t.steepness * (x - 1.0));
        let v = (window.iter().map(|s| s.pac_vibration.powi(2)).sum::<f64>() / n as f64).sqrt();
        let p_slip = sigmoid(t.steepness * (v / t.slip_vibration - 1.0));
        let probs = [
            1.0 - p_contact,
            p_contact * (1.0 - p_slip),
            p_contact * p_slip,
        ];
        let best = (0..3)
            .max_by(|&a, &b| probs[a].total_cmp(&probs[b]))
            .unwrap();
        Detection {
            event: ContactEvent::ALL[best],
            event_probabilities: probs,
            material: Material::Unknown,
            material_probabilities: None,
            slip_direction: None,
        }
    }
}

/// Vibration of one frame's pac (module doc): RMS of second differences / √6 for three or more
/// samples, of first differences / √2 for two, |pac − previous| / √2 for a single value (0 without
/// a previous value).
pub fn pac_vibration(pac: &[f64], previous_single: Option<f64>) -> f64 {
    if pac.len() >= 3 {
        let ms = pac
            .windows(3)
            .map(|w| (w[2] - 2.0 * w[1] + w[0]).powi(2))
            .sum::<f64>()
            / (pac.len() - 2) as f64;
        (ms / 6.0).sqrt()
    } else if pac.len() == 2 {
        let ms =
            pac.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / (pac.len() - 1) as f64;
        (ms / 2.0).sqrt()
    } else if let (Some(&now), Some(prev)) = (pac.first(), previous_single) {
        (now - prev).abs() / std::f64::consts::SQRT_2
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(pdc: f64, vib: f64, e: f64) -> DetectorSample {
        DetectorSample {
            pdc,
            pac: 0.0,
            pac_vibration: vib,
            pac_samples: vec![0.0],
            tdc: 0.0,
            tac: 0.0,
            electrodes: vec![e; 19],
        }
    }

    #[test]
    fn sampler_keeps_every_kth_of_the_last_l() {
        let mut w = WindowSampler::new(3, 2);
        for i in 0..10 {
            w.push(i);
        }
        // Kept: 0, 2, 4, 6, 8 → last three.
        assert_eq!(w.window(), &[4, 6, 8]);
        assert!(w.is_full());
    }

    #[test]
    fn model_free_events_follow_the_physical_thresholds() {
        let mut d = ModelFreeDetector::default();
        let rest = vec![sample(1.0, 1.0, 1.0); 8];
        assert_eq!(d.detect(&rest).event, ContactEvent::NonContact);
        let press = vec![sample(60.0, 2.0, 40.0); 8];
        let r = d.detect(&press);
        assert_eq!(r.event, ContactEvent::Contact);
        assert_eq!(r.material, Material::Unknown);
        let slide = vec![sample(60.0, 40.0, 40.0); 8];
        assert_eq!(d.detect(&slide).event, ContactEvent::Slip);
        // Vibration without contact is not slip.
        let shake = vec![sample(0.0, 40.0, 0.0); 8];
        assert_eq!(d.detect(&shake).event, ContactEvent::NonContact);
        let p = d.detect(&slide).event_probabilities;
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn pac_vibration_of_both_driver_forms() {
        // Alternating ±1: second differences ±4 → RMS 4, /√6.
        let v = pac_vibration(&[1.0, -1.0, 1.0, -1.0], None);
        assert!((v - 4.0 / 6f64.sqrt()).abs() < 1e-12);
        // A linear ramp (drift) has no vibration.
        assert_eq!(pac_vibration(&[0.0, 3.0, 6.0, 9.0], None), 0.0);
        assert!((pac_vibration(&[0.0, 2.0], None) - 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(pac_vibration(&[5.0], None), 0.0);
        assert!((pac_vibration(&[5.0], Some(3.0)) - 2.0 / 2f64.sqrt()).abs() < 1e-12);
    }
}
