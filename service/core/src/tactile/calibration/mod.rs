//! Calibrations (issue 16): a detector fitted in the server on a user's own labelled
//! recordings, in seconds and without retraining a network. The recordings run through the
//! session's own pipeline (taring and the window t_seq, `readings::SampleSource`,
//! `detector::WindowSampler`), each full window becomes the hand features of [`features`], and a
//! [`classifier::LinearDiscriminant`] is fitted for the material (labels per recording: one of
//! paper, foam, plastic, metal — the classes of Eq 6.4 the desired-force law knows — optionally
//! with a kind, `plastic/eva`) and for the contact event (labels per frame). A session that
//! names the calibration gets a [`CalibratedDetector`].

pub mod classifier;
pub mod features;

use super::detector::{
    ContactEvent, Detection, DetectorSample, EventDetector, Material, ModelFreeDetector,
    ModelFreeThresholds, SlipDirection, WindowSampler, check_window,
};
use super::layout::MAX_ELECTRODES;
use super::readings::{FingerReading, SampleSource};
use super::taring::TareConfig;
use crate::error::FieldError;
use classifier::{LinearDiscriminant, class_of};
use features::Features;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::Arc;

/// One labelled recording of one finger.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CalibrationRecording {
    /// The material touched throughout (`class` or `class/kind`), if labelled.
    pub material: Option<String>,
    pub readings: Vec<FingerReading>,
    /// The contact event of every reading, if labelled (as many as `readings`).
    pub events: Option<Vec<ContactEvent>>,
    /// The direction the recording slips in, if labelled (its slipping windows teach it).
    pub slip_direction: Option<SlipDirection>,
}

/// How recordings become windows: as a session with these settings would see them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CalibrationSettings {
    /// l of t_seq.
    pub window_length: usize,
    /// k: every k-th reading.
    pub stride: usize,
    /// The fingers' taring (a session using the calibration must tare alike).
    pub tare: TareConfig,
    /// The sensor gives only its electrodes (its fingers are `electrodes_only` in a session):
    /// no pac, pdc or thermal channel is read, and the features are the electrodes' own
    /// ([`features::Features::electrodes_only`]).
    #[serde(default)]
    pub electrodes_only: bool,
}

impl Default for CalibrationSettings {
    /// Table 6.1's window (l = 32, k = 3) and the sessions' default taring.
    fn default() -> Self {
        Self {
            window_length: 32,
            stride: 3,
            tare: TareConfig::default(),
            electrodes_only: false,
        }
    }
}

/// What a calibration was fitted on.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct CalibrationSummary {
    pub recordings: usize,
    /// Windows per material label (class or class/kind), sorted by label.
    pub material_windows: Vec<(String, usize)>,
    /// Windows per event: non-contact, contact, slip.
    pub event_windows: [usize; 3],
    /// Windows per slip direction, sorted by label.
    #[serde(default)]
    pub direction_windows: Vec<(String, usize)>,
    /// Wall time of the fit, ms.
    pub fit_ms: f64,
}

/// A fitted calibration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    pub name: String,
    /// Electrodes per reading.
    pub electrodes: usize,
    pub settings: CalibrationSettings,
    /// The material classifier, when recordings were labelled with two or more materials.
    pub material: Option<LinearDiscriminant>,
    /// The event classifier (labels non_contact, contact, slip), when frames were labelled.
    pub events: Option<LinearDiscriminant>,
    /// The slip-direction classifier, when recordings were labelled with two or more
    /// directions.
    #[serde(default)]
    pub slip_direction: Option<LinearDiscriminant>,
    pub summary: CalibrationSummary,
}

impl Calibration {
    /// Fits `recordings` (errors name `recordings[i]…`): every reading finite and with the
    /// same electrode count; at least one recording labelled; material labels of two or more
    /// classes of [`Material::CLASSES`] (by name, optionally `/kind`); event labels, where
    /// given, one per reading and of two or more events. Windows are every full t_seq a session
    /// would see; a material window counts only where its newest frame is not labelled
    /// non-contact (a session reports no material out of contact).
    pub fn fit(
        name: &str,
        recordings: &[CalibrationRecording],
        settings: CalibrationSettings,
    ) -> Result<Self, FieldError> {
        let start = std::time::Instant::now();
        check_window(settings.window_length, settings.stride, "")?;
        let Some(electrodes) = recordings
            .iter()
            .find_map(|r| r.readings.first())
            .map(|r| r.electrodes.len())
        else {
            return Err(FieldError::new("recordings", "no recordings with readings"));
        };
        // A session's layout has 2 to MAX_ELECTRODES electrodes; a calibration for more could
        // never be used, and its covariance grows with their square.
        if !(2..=MAX_ELECTRODES).contains(&electrodes) {
            let i = recordings
                .iter()
                .position(|r| !r.readings.is_empty())
                .unwrap_or(0);
            return Err(FieldError::new(
                format!("recordings[{i}].readings[0].electrodes"),
                format!("{electrodes} electrodes; a sensor layout has 2 to {MAX_ELECTRODES}"),
            ));
        }
        for (i, rec) in recordings.iter().enumerate() {
            validate_recording(
                rec,
                electrodes,
                settings.electrodes_only,
                &format!("recordings[{i}]"),
            )?;
        }
        let features = Features::for_sensor(settings.electrodes_only);
        let mut material_examples: Vec<(String, Vec<f64>)> = Vec::new();
        let mut event_examples: Vec<(String, Vec<f64>)> = Vec::new();
        let mut direction_examples: Vec<(String, Vec<f64>)> = Vec::new();
        for rec in recordings {
            let mut source = SampleSource::new(settings.tare, electrodes)
                .electrodes_only(settings.electrodes_only);
            let mut sampler: WindowSampler<DetectorSample> =
                WindowSampler::new(settings.window_length, settings.stride);
            for (j, reading) in rec.readings.iter().enumerate() {
                let Some(sample) = source.next(reading).1 else {
                    continue;
                };
                if !sampler.push(sample) || !sampler.is_full() {
                    continue;
                }
                let x = features.of(sampler.window());
                let event = rec.events.as_ref().map(|e| e[j]);
                if let Some(m) = &rec.material
                    && event != Some(ContactEvent::NonContact)
                {
                    material_examples.push((m.clone(), x.clone()));
                }
                // A direction is taught by the recording's slipping windows (all of them when
                // its frames carry no events).
                if let Some(d) = rec.slip_direction
                    && event.is_none_or(|e| e == ContactEvent::Slip)
                {
                    direction_examples.push((d.name().to_string(), x.clone()));
                }
                if let Some(e) = event {
                    event_examples.push((e.name().to_string(), x));
                }
            }
        }
        let labelled_materials = recordings.iter().any(|r| r.material.is_some());
        let labelled_events = recordings.iter().any(|r| r.events.is_some());
        let labelled_directions = recordings.iter().any(|r| r.slip_direction.is_some());
        if !labelled_materials && !labelled_events && !labelled_directions {
            return Err(FieldError::new(
                "recordings",
                "no labels: give each recording its material, its frames' events or its slip \
                 direction",
            ));
        }
        let fit = |examples: &[(String, Vec<f64>)], field: &str| {
            if examples.is_empty() {
                return Err(FieldError::new(
                    field,
                    format!(
                        "no full window: recordings need more than {} readings after taring",
                        settings.window_length * settings.stride
                    ),
                ));
            }
            LinearDiscriminant::fit(examples, field).map(Some)
        };
        let material = if labelled_materials {
            fit(&material_examples, "recordings[].material")?
        } else {
            None
        };
        let events = if labelled_events {
            fit(&event_examples, "recordings[].events")?
        } else {
            None
        };
        let slip_direction = if labelled_directions {
            fit(&direction_examples, "recordings[].slip_direction")?
        } else {
            None
        };
        let mut direction_windows: BTreeMap<String, usize> = BTreeMap::new();
        for (l, _) in &direction_examples {
            *direction_windows.entry(l.clone()).or_default() += 1;
        }
        let mut material_windows: BTreeMap<String, usize> = BTreeMap::new();
        for (l, _) in &material_examples {
            *material_windows.entry(l.clone()).or_default() += 1;
        }
        let mut event_windows = [0; 3];
        for (l, _) in &event_examples {
            if let Some(k) = ContactEvent::ALL.iter().position(|e| e.name() == l) {
                event_windows[k] += 1;
            }
        }
        Ok(Self {
            name: name.to_string(),
            electrodes,
            settings,
            material,
            events,
            slip_direction,
            summary: CalibrationSummary {
                recordings: recordings.len(),
                material_windows: material_windows.into_iter().collect(),
                event_windows,
                direction_windows: direction_windows.into_iter().collect(),
                fit_ms: start.elapsed().as_secs_f64() * 1e3,
            },
        })
    }
}

/// The checks of [`Calibration::fit`] on one recording (of a sensor with pac, pdc and the
/// thermal channels unless `electrodes_only`, whose other channels are not read).
fn validate_recording(
    rec: &CalibrationRecording,
    electrodes: usize,
    electrodes_only: bool,
    field: &str,
) -> Result<(), FieldError> {
    if rec.readings.is_empty() {
        return Err(FieldError::new(format!("{field}.readings"), "no readings"));
    }
    for (j, r) in rec.readings.iter().enumerate() {
        let at = format!("{field}.readings[{j}]");
        if r.electrodes.len() != electrodes {
            return Err(FieldError::new(
                format!("{at}.electrodes"),
                format!(
                    "{} electrodes; the calibration's first reading has {electrodes}",
                    r.electrodes.len()
                ),
            ));
        }
        if electrodes_only {
            if r.electrodes.iter().any(|v| !v.is_finite()) {
                return Err(FieldError::new(at, "a value is not finite"));
            }
            continue;
        }
        if r.pac.is_empty() {
            return Err(FieldError::new(
                format!("{at}.pac"),
                "no pac sample (a sensor that gives only its electrodes is calibrated \
                 electrodes_only)",
            ));
        }
        let values = [r.pdc, r.tdc, r.tac]
            .into_iter()
            .chain(r.pac.iter().copied())
            .chain(r.electrodes.iter().copied());
        if values.into_iter().any(|v| !v.is_finite()) {
            return Err(FieldError::new(at, "a value is not finite"));
        }
    }
    if let Some(m) = &rec.material {
        let class = class_of(m);
        let kind = m.split_once(classifier::KIND_SEPARATOR).map(|(_, k)| k);
        if !Material::CLASSES.iter().any(|c| c.name() == class) || kind == Some("") {
            return Err(FieldError::new(
                format!("{field}.material"),
                format!(
                    "unknown material '{}': one of paper, foam, plastic, metal, optionally with a \
                     kind after a slash (plastic/eva)",
                    m.escape_debug()
                ),
            ));
        }
    }
    if let Some(e) = &rec.events
        && e.len() != rec.readings.len()
    {
        return Err(FieldError::new(
            format!("{field}.events"),
            format!("{} events for {} readings", e.len(), rec.readings.len()),
        ));
    }
    Ok(())
}

/// The detector of a session that names a calibration: the calibration's classifiers on every
/// full window; until the window is full, and for the event when the calibration has no event
/// classifier, the model-free detector (`detector`), with no material; P(non-contact) from the
/// model-free detector too when the calibration saw no window out of contact.
#[derive(Debug, Clone)]
pub struct CalibratedDetector {
    calibration: Arc<Calibration>,
    features: Features,
    fallback: ModelFreeDetector,
}

impl CalibratedDetector {
    pub fn new(calibration: Arc<Calibration>, fallback: ModelFreeThresholds) -> Self {
        Self {
            features: Features::for_sensor(calibration.settings.electrodes_only),
            calibration,
            fallback: ModelFreeDetector::new(fallback),
        }
    }
}

impl EventDetector for CalibratedDetector {
    fn detect(&mut self, window: &[DetectorSample]) -> Detection {
        let mut d = self.fallback.detect(window);
        let c = &self.calibration;
        if window.len() < c.settings.window_length {
            return d;
        }
        let x = self.features.of(window);
        if let Some(events) = &c.events {
            let (_, mut probs) = ranked(events, &x, ContactEvent::ALL, ContactEvent::name);
            // Recordings that hold no full window out of contact (a slide starts touching)
            // teach contact against slip only: whether the finger touches at all is then the
            // model-free detector's, the calibration's split applied to the rest.
            if !events
                .labels
                .iter()
                .any(|l| l == ContactEvent::NonContact.name())
            {
                let away = d.event_probabilities[0];
                probs = [away, (1.0 - away) * probs[1], (1.0 - away) * probs[2]];
            }
            let best = (0..3)
                .max_by(|&a, &b| probs[a].total_cmp(&probs[b]))
                .unwrap_or(0);
            d.event = ContactEvent::ALL[best];
            d.event_probabilities = probs;
        }
        if let Some(material) = &c.material {
            let (best, probs) = ranked(material, &x, Material::CLASSES, Material::name);
            d.material = best;
            d.material_probabilities = Some(probs);
        }
        // The direction a slip would take, whenever in contact: the session reports it only
        // when the finger slips, whichever rule said so (the calibration's, or the contact
        // centroid's motion).
        if let Some(directions) = &c.slip_direction
            && d.event != ContactEvent::NonContact
        {
            d.slip_direction = Some(ranked(
                directions,
                &x,
                SlipDirection::ALL,
                SlipDirection::name,
            ));
        }
        d
    }
}

/// A classifier's probabilities laid out over a fixed set of answers (by name; an answer it was
/// not fitted on has 0), and the most probable.
fn ranked<T: Copy, const N: usize>(
    classifier: &LinearDiscriminant,
    x: &[f64],
    answers: [T; N],
    name: fn(T) -> &'static str,
) -> (T, [f64; N]) {
    let mut probs = [0.0; N];
    for (label, q) in classifier.class_probabilities(x) {
        if let Some(k) = answers.iter().position(|&a| name(a) == label) {
            probs[k] = q;
        }
    }
    let best = (0..N)
        .max_by(|&a, &b| probs[a].total_cmp(&probs[b]))
        .unwrap_or(0);
    (answers[best], probs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tactile::{
        FingerConfig, Frame, LayoutSpec, SensorLayout, Stabilizer, StabilizerConfig,
    };

    /// A slide over a material whose texture rings at `bin` of the pac spectrum (pretared
    /// readings, 3 electrodes, 22 pac samples a frame), with a little per-recording noise.
    fn slide(bin: f64, frames: usize, seed: u64) -> Vec<FingerReading> {
        let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut noise = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % 1000) as f64 / 1000.0 - 0.5
        };
        (0..frames)
            .map(|f| FingerReading {
                pdc: 40.0 + noise(),
                pac: (0..22)
                    .map(|s| {
                        let i = (22 * f + s) as f64;
                        50.0 * (std::f64::consts::TAU * bin * i / 128.0).sin() + 5.0 * noise()
                    })
                    .collect(),
                tdc: 10.0 + noise(),
                tac: 5.0 + noise(),
                electrodes: vec![20.0 + noise(), 30.0 + noise(), 10.0 + noise()],
            })
            .collect()
    }

    fn recording(material: &str, bin: f64, seed: u64) -> CalibrationRecording {
        CalibrationRecording {
            material: Some(material.into()),
            readings: slide(bin, 200, seed),
            events: None,
            slip_direction: None,
        }
    }

    fn settings() -> CalibrationSettings {
        CalibrationSettings {
            tare: TareConfig::pretared(),
            ..CalibrationSettings::default()
        }
    }

    /// Fitted on two recordings of each of two textures, a session with the calibrated
    /// detector names the material of a third recording of each; before its window is full it
    /// names none.
    #[test]
    fn a_session_with_the_calibration_names_the_material() {
        let recs = [
            recording("foam", 5.0, 1),
            recording("foam", 5.0, 2),
            recording("metal/steel", 30.0, 3),
            recording("metal/steel", 30.0, 4),
        ];
        let c = Arc::new(Calibration::fit("bench", &recs, settings()).unwrap());
        assert!(c.events.is_none());
        assert_eq!(
            c.material.as_ref().unwrap().labels,
            vec!["foam", "metal/steel"]
        );
        // 200 readings: full windows from reading 94 on, one every third: 36 per recording.
        assert_eq!(
            c.summary.material_windows,
            vec![("foam".to_string(), 72), ("metal/steel".to_string(), 72)]
        );
        let layout = SensorLayout::from_spec(LayoutSpec {
            name: "pad".into(),
            description: String::new(),
            electrodes: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        })
        .unwrap();
        for (bin, want) in [(5.0, Material::Foam), (30.0, Material::Metal)] {
            let config = StabilizerConfig {
                fingers: vec![FingerConfig {
                    electrodes_only: false,
                    name: "ff".into(),
                    layout: layout.clone(),
                    tare: TareConfig::pretared(),
                }],
                ..StabilizerConfig::default()
            };
            let detector: Box<dyn EventDetector> = Box::new(CalibratedDetector::new(
                c.clone(),
                ModelFreeThresholds::default(),
            ));
            let mut s = Stabilizer::with_detectors(config, vec![detector]).unwrap();
            for (i, r) in slide(bin, 150, 9).into_iter().enumerate() {
                let out = s
                    .step(&Frame {
                        timestamp: i as f64 * 0.01,
                        fingers: vec![r],
                    })
                    .unwrap();
                let m = out.fingers[0].material;
                if i < 93 {
                    assert_eq!(m, Material::Unknown, "{i}: before the window is full");
                } else {
                    assert_eq!(m, want, "reading {i}");
                }
            }
        }
    }

    /// An electrodes-only finger (4 electrodes in a row, pretared): a held touch presses
    /// them in a fixed pattern; a slide moves the pressed spot along the row and back.
    fn electrodes_only(slides: bool, frames: usize, seed: u64) -> CalibrationRecording {
        let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut noise = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % 1000) as f64 / 1000.0 - 0.5
        };
        let readings = (0..frames)
            .map(|f| {
                let spot = if slides {
                    1.5 + 1.5 * (f as f64 * 0.05).sin()
                } else {
                    1.0 + 0.2 * seed as f64
                };
                FingerReading {
                    electrodes: (0..4)
                        .map(|e| 30.0 * (-(e as f64 - spot).powi(2)).exp() + noise())
                        .collect(),
                    ..FingerReading::default()
                }
            })
            .collect();
        let event = if slides {
            ContactEvent::Slip
        } else {
            ContactEvent::Contact
        };
        CalibrationRecording {
            material: None,
            readings,
            events: Some(vec![event; frames]),
            slip_direction: None,
        }
    }

    /// A session of one electrodes_only finger on the row of 4 electrodes (4 mm apart),
    /// pretared, windows of 8 every 2nd reading, detecting with `c`.
    fn row_session(c: &Arc<Calibration>) -> Stabilizer {
        let layout = SensorLayout::from_spec(LayoutSpec {
            name: "row".into(),
            description: String::new(),
            electrodes: vec![[0.0, 0.0], [4.0, 0.0], [8.0, 0.0], [12.0, 0.0]],
        })
        .unwrap();
        let mut config = StabilizerConfig::for_fingers(vec![FingerConfig {
            electrodes_only: true,
            name: "ff".into(),
            layout,
            tare: TareConfig::pretared(),
        }]);
        (config.window_length, config.stride) = (8, 2);
        let detector: Box<dyn EventDetector> = Box::new(CalibratedDetector::new(
            c.clone(),
            ModelFreeThresholds::default(),
        ));
        Stabilizer::with_detectors(config, vec![detector]).unwrap()
    }

    /// Fitted on held touches and slides of a sensor that gives only its electrodes, a session
    /// whose finger is electrodes_only names a new slide slip and a new touch contact once its
    /// window is full; the same recordings do not fit a calibration that reads pac.
    #[test]
    fn an_electrodes_only_calibration_tells_a_slide_from_a_touch() {
        let recs: Vec<CalibrationRecording> = (0..6)
            .map(|k| electrodes_only(k % 2 == 1, 150, k as u64))
            .collect();
        let settings = CalibrationSettings {
            window_length: 8,
            stride: 2,
            electrodes_only: true,
            ..settings()
        };
        let c = Arc::new(Calibration::fit("sp", &recs, settings).unwrap());
        assert!(c.material.is_none());
        assert_eq!(c.events.as_ref().unwrap().labels, vec!["contact", "slip"]);
        // 150 readings, windows of 8 every 2nd: full from reading 14 on, 68 per recording.
        assert_eq!(c.summary.event_windows, [0, 3 * 68, 3 * 68]);
        for (slides, want) in [(true, ContactEvent::Slip), (false, ContactEvent::Contact)] {
            let mut s = row_session(&c);
            let test = electrodes_only(slides, 120, 7);
            let mut named = 0;
            for (i, r) in test.readings.into_iter().enumerate() {
                let out = s
                    .step(&Frame {
                        timestamp: i as f64 * 0.01,
                        fingers: vec![r],
                    })
                    .unwrap();
                if i >= 20 {
                    named += usize::from(out.fingers[0].event == want);
                }
            }
            assert!(named >= 95, "{want:?}: {named} of 100 frames");
        }
        let e = Calibration::fit(
            "sp",
            &recs,
            CalibrationSettings {
                electrodes_only: false,
                ..settings
            },
        )
        .unwrap_err();
        assert_eq!(e.field, "recordings[0].readings[0].pac");
    }

    /// A slide whose pressed spot crosses the row of 4 electrodes east (rising index) or west,
    /// again every second.
    fn slide_towards(direction: SlipDirection, frames: usize, seed: u64) -> CalibrationRecording {
        let mut rec = electrodes_only(true, frames, seed);
        for (f, r) in rec.readings.iter_mut().enumerate() {
            let t = (f % 100) as f64 / 100.0;
            let spot = match direction {
                SlipDirection::East => 0.5 + 2.0 * t,
                _ => 2.5 - 2.0 * t,
            };
            let noise = 0.1 * ((f as u64 * 31 + seed) % 7) as f64;
            for (e, v) in r.electrodes.iter_mut().enumerate() {
                *v = 30.0 * (-(e as f64 - spot).powi(2)).exp() + noise;
            }
        }
        rec.slip_direction = Some(direction);
        rec
    }

    /// Fitted on held touches and slides labelled east and west, a session names the
    /// direction of a new slide while it slips, and names none out of slip.
    #[test]
    fn a_calibration_on_labelled_directions_names_the_slip_direction() {
        let mut recs: Vec<CalibrationRecording> =
            (0..3).map(|k| electrodes_only(false, 200, k)).collect();
        for k in 0..3 {
            recs.push(slide_towards(SlipDirection::East, 200, k));
            recs.push(slide_towards(SlipDirection::West, 200, k + 10));
        }
        let settings = CalibrationSettings {
            window_length: 8,
            stride: 2,
            electrodes_only: true,
            ..settings()
        };
        let c = Arc::new(Calibration::fit("dos", &recs, settings).unwrap());
        assert_eq!(
            c.summary.direction_windows,
            vec![("east".to_string(), 3 * 93), ("west".to_string(), 3 * 93)]
        );
        for test in [
            slide_towards(SlipDirection::East, 200, 5),
            slide_towards(SlipDirection::West, 200, 6),
            electrodes_only(false, 200, 7),
        ] {
            let mut s = row_session(&c);
            let (mut slipping, mut right) = (0, 0);
            for (i, r) in test.readings.into_iter().enumerate() {
                let out = s
                    .step(&Frame {
                        timestamp: i as f64 * 0.01,
                        fingers: vec![r],
                    })
                    .unwrap();
                let f = &out.fingers[0];
                if f.event == ContactEvent::Slip {
                    slipping += 1;
                    right += usize::from(f.slip_direction == test.slip_direction);
                } else {
                    assert_eq!(f.slip_direction, None, "frame {i}");
                }
            }
            // A window that straddles the spot's jump back (16 frames in every 100) sees the
            // opposite motion.
            match test.slip_direction {
                Some(d) => assert!(
                    slipping > 150 && right as f64 >= 0.8 * slipping as f64,
                    "{d:?}: {right} of {slipping} slipping frames"
                ),
                None => assert!(slipping < 10, "a touch slipped in {slipping} frames"),
            }
        }
    }

    #[test]
    fn bad_recordings_are_refused_naming_the_field() {
        let err =
            |recs: &[CalibrationRecording]| Calibration::fit("x", recs, settings()).unwrap_err();
        let e = err(&[recording("wood", 5.0, 1), recording("foam", 9.0, 2)]);
        assert_eq!(e.field, "recordings[0].material");
        assert!(e.message.contains("unknown material 'wood'"), "{e}");
        let e = err(&[recording("foam/", 5.0, 1), recording("metal", 9.0, 2)]);
        assert_eq!(e.field, "recordings[0].material");
        let e = err(&[recording("foam/a", 5.0, 1), recording("foam/b", 9.0, 2)]);
        assert_eq!(e.field, "recordings[].material");
        assert!(e.message.contains("one class only (foam)"), "{e}");
        let mut short = recording("metal", 9.0, 2);
        short.readings[7].electrodes.pop();
        let e = err(&[recording("foam", 5.0, 1), short]);
        assert_eq!(e.field, "recordings[1].readings[7].electrodes");
        let mut nan = recording("metal", 9.0, 2);
        nan.readings[3].pac[4] = f64::NAN;
        assert_eq!(
            err(&[recording("foam", 5.0, 1), nan]).field,
            "recordings[1].readings[3]"
        );
        let mut events = recording("metal", 9.0, 2);
        events.events = Some(vec![ContactEvent::Slip; 3]);
        let e = err(&[recording("foam", 5.0, 1), events]);
        assert_eq!(e.field, "recordings[1].events");
        let unlabelled = CalibrationRecording {
            material: None,
            ..recording("foam", 5.0, 1)
        };
        assert_eq!(err(&[unlabelled]).field, "recordings");
        // The session's window bounds: a huge window is refused, not allocated.
        let huge = CalibrationSettings {
            window_length: 1_000_000_000,
            ..settings()
        };
        let e = Calibration::fit("x", &[recording("foam", 5.0, 1)], huge).unwrap_err();
        assert_eq!(e.field, "window_length");
        let e = Calibration::fit(
            "x",
            &[recording("foam", 5.0, 1)],
            CalibrationSettings {
                stride: 0,
                ..settings()
            },
        )
        .unwrap_err();
        assert_eq!(e.field, "stride");
        let mut wide = recording("foam", 5.0, 1);
        wide.readings[0].electrodes = vec![1.0; 100_000];
        let e = err(&[wide, recording("metal", 9.0, 2)]);
        assert_eq!(e.field, "recordings[0].readings[0].electrodes");
        assert!(e.message.contains("2 to 40"), "{e}");
        assert_eq!(err(&[]).field, "recordings");
        let mut tiny = recording("foam", 5.0, 1);
        tiny.readings.truncate(50);
        let mut tiny2 = recording("metal", 9.0, 2);
        tiny2.readings.truncate(50);
        let e = err(&[tiny, tiny2]);
        assert!(e.message.contains("no full window"), "{e}");
    }
}
