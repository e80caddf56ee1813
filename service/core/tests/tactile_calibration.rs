//! Calibration on the real BioTac slides, issue 16's protocol: fitted on samples 1–10 of each
//! material, tested on samples 11–20 — split by recording, never windows of one recording on
//! both sides — by running each test recording through a stabilizer session whose detector is
//! the calibration (`CalibratedDetector`), exactly as the server serves it. Material labels are
//! the data README's classes with the material as the kind (`plastic/mat13`); events come from
//! the arm's wrench and velocity (`tactile::recording`). The recordings carry no licence: they
//! calibrate at test time and are measured on; nothing fitted here is stored or shipped.
//!
//! `cargo test -p graspd-core --test tactile_calibration -- --nocapture` prints the tables
//! (docs/tactile-calibration.md keeps them). The data directory is
//! `graspd_testkit::biotac_slide_dir` (`$GRASPD_TACTILE_DATA` or the shared testdata's
//! `tactile/biotac_slide`); the test is skipped (with a note) when neither exists.

use graspd_core::tactile::layout::SensorCatalog;
use graspd_core::tactile::recording::Recording;
use graspd_core::tactile::{
    CalibratedDetector, Calibration, CalibrationRecording, CalibrationSettings, ContactEvent,
    EventDetector, FingerConfig, Frame, Material, ModelFreeThresholds, Stabilizer,
    StabilizerConfig, TareConfig,
};
use graspd_testkit::{BIOTAC_SLIDE_MATERIALS, biotac_slide_dir};
use std::collections::BTreeSet;
use std::sync::Arc;

/// One recording: its material, sample number and its labelled readings.
struct Sample {
    material: &'static str,
    class: &'static str,
    sample: usize,
    frames: Vec<Frame>,
    events: Vec<ContactEvent>,
}

fn load(dir: &std::path::Path) -> Vec<Sample> {
    let mut out = Vec::new();
    for (mat, class) in BIOTAC_SLIDE_MATERIALS {
        for sample in 1..=20 {
            let read = |kind: &str| {
                std::fs::read_to_string(dir.join(mat).join(format!("{mat}_{sample}_{kind}.csv")))
                    .unwrap()
            };
            let rec =
                Recording::from_csv(&read("bio"), Some(&read("cw")), Some(&read("cv"))).unwrap();
            out.push(Sample {
                material: mat,
                class,
                sample,
                frames: rec.frames(),
                events: rec.labels.clone().unwrap(),
            });
        }
    }
    out
}

/// Samples 1–10 of each material calibrate, 11–20 test: whole recordings on one side each.
fn split(samples: &[Sample]) -> (Vec<&Sample>, Vec<&Sample>) {
    samples.iter().partition(|s| s.sample <= 10)
}

fn class_only() -> bool {
    std::env::var("GRASPD_CALIBRATION_LABELS").is_ok_and(|v| v == "class")
}

/// The label of a recording: its class with the material as the kind, or (with
/// `GRASPD_CALIBRATION_LABELS=class`) the class alone, one Gaussian over unlike materials.
fn recording(s: &Sample) -> CalibrationRecording {
    CalibrationRecording {
        material: Some(if class_only() {
            s.class.to_string()
        } else {
            format!("{}/{}", s.class, s.material)
        }),
        readings: s.frames.iter().map(|f| f.fingers[0].clone()).collect(),
        events: Some(s.events.clone()),
        slip_direction: None,
    }
}

fn settings() -> CalibrationSettings {
    CalibrationSettings {
        tare: TareConfig::pretared(),
        ..CalibrationSettings::default()
    }
}

#[test]
fn the_split_is_by_recording() {
    let Some(dir) = biotac_slide_dir() else {
        eprintln!("skipped: no BioTac recordings (set GRASPD_TACTILE_DATA)");
        return;
    };
    let samples = load(&dir);
    let (train, test) = split(&samples);
    let ids = |v: &[&Sample]| -> BTreeSet<(&str, usize)> {
        v.iter().map(|s| (s.material, s.sample)).collect()
    };
    let (a, b) = (ids(&train), ids(&test));
    assert_eq!((a.len(), b.len()), (100, 100));
    assert!(a.is_disjoint(&b), "a recording on both sides");
}

#[test]
fn a_calibration_on_other_recordings_tells_the_materials() {
    let Some(dir) = biotac_slide_dir() else {
        eprintln!("skipped: no BioTac recordings (set GRASPD_TACTILE_DATA)");
        return;
    };
    let samples = load(&dir);
    let (train, test) = split(&samples);
    let recordings: Vec<CalibrationRecording> = train.iter().map(|s| recording(s)).collect();
    let calibration = Arc::new(Calibration::fit("biotac_slide", &recordings, settings()).unwrap());
    eprintln!(
        "fitted on {} recordings ({} material windows, events {:?}) in {:.0} ms",
        calibration.summary.recordings,
        calibration
            .summary
            .material_windows
            .iter()
            .map(|(_, n)| n)
            .sum::<usize>(),
        calibration.summary.event_windows,
        calibration.summary.fit_ms
    );
    let layout = SensorCatalog::builtin().get("biotac").unwrap().clone();
    // Per class: frames right / in contact, recordings right / all; per event: frames right /
    // labelled, and the same for the majority answer.
    let classes = Material::CLASSES;
    let mut frames = [(0usize, 0usize); 4];
    let mut recs = [(0usize, 0usize); 4];
    let mut events = [(0usize, 0usize); 3];
    let (mut contact_ok, mut slip_ok, mut n) = (0, 0, 0);
    let mut label_counts = [0usize; 3];
    // The model-free detector on the same frames: what a session without the calibration says.
    let (mut mf_contact_ok, mut mf_slip_ok) = (0, 0);
    for s in &test {
        let config = StabilizerConfig {
            fingers: vec![FingerConfig {
                electrodes_only: false,
                name: "biotac".into(),
                layout: layout.clone(),
                tare: TareConfig::pretared(),
            }],
            ..StabilizerConfig::default()
        };
        let detector: Box<dyn EventDetector> = Box::new(CalibratedDetector::new(
            calibration.clone(),
            ModelFreeThresholds::default(),
        ));
        let mut session = Stabilizer::with_detectors(config.clone(), vec![detector]).unwrap();
        let mut model_free = Stabilizer::new(config).unwrap();
        let k = classes.iter().position(|m| m.name() == s.class).unwrap();
        let mut votes = [0usize; 4];
        for (f, label) in s.frames.iter().zip(&s.events) {
            let out = session.step(f).unwrap();
            let r = &out.fingers[0];
            let mf = model_free.step(f).unwrap().fingers[0].event;
            mf_contact_ok +=
                ((mf != ContactEvent::NonContact) == (*label != ContactEvent::NonContact)) as usize;
            mf_slip_ok += ((mf == ContactEvent::Slip) == (*label == ContactEvent::Slip)) as usize;
            if let Some(m) = classes.iter().position(|&m| m == r.material) {
                votes[m] += 1;
                frames[k].1 += 1;
                frames[k].0 += (m == k) as usize;
            }
            let e = ContactEvent::ALL.iter().position(|x| x == label).unwrap();
            label_counts[e] += 1;
            events[e].1 += 1;
            events[e].0 += (r.event == *label) as usize;
            n += 1;
            contact_ok += ((r.event != ContactEvent::NonContact)
                == (*label != ContactEvent::NonContact)) as usize;
            slip_ok += ((r.event == ContactEvent::Slip) == (*label == ContactEvent::Slip)) as usize;
        }
        let best = (0..4).max_by_key(|&m| votes[m]).unwrap();
        recs[k].1 += 1;
        recs[k].0 += (votes[best] > 0 && best == k) as usize;
    }
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    eprintln!("| material | frames in contact | recordings |");
    eprintln!("|---|---:|---:|");
    for (k, m) in classes.iter().enumerate() {
        eprintln!(
            "| {} | {:.1} % ({}/{}) | {}/{} |",
            m.name(),
            pct(frames[k].0, frames[k].1),
            frames[k].0,
            frames[k].1,
            recs[k].0,
            recs[k].1
        );
    }
    let (fa, fb) = frames.iter().fold((0, 0), |a, f| (a.0 + f.0, a.1 + f.1));
    let (ra, rb) = recs.iter().fold((0, 0), |a, f| (a.0 + f.0, a.1 + f.1));
    let majority_class = recs.iter().map(|r| r.1).max().unwrap();
    eprintln!(
        "| **all** | **{:.1} %** | **{:.0} %** ({ra}/{rb}) |\n| majority class (plastic) | {:.1} % | {:.0} % |",
        pct(fa, fb),
        pct(ra, rb),
        pct(frames[2].1, fb),
        pct(majority_class, rb)
    );
    let majority_event = *label_counts.iter().max().unwrap();
    eprintln!("| event | frames right |\n|---|---:|");
    for (e, ev) in ContactEvent::ALL.iter().enumerate() {
        eprintln!(
            "| {} | {:.1} % ({}/{}) |",
            ev.name(),
            pct(events[e].0, events[e].1),
            events[e].0,
            events[e].1
        );
    }
    eprintln!(
        "contact (touching or not) {:.1} %, slip (slipping or not) {:.1} % of {n} frames; \
         majority answer (slip) {:.1} %",
        pct(contact_ok, n),
        pct(slip_ok, n),
        pct(majority_event, n)
    );
    eprintln!(
        "model-free detector: contact {:.1} %, slip {:.1} %",
        pct(mf_contact_ok, n),
        pct(mf_slip_ok, n)
    );
    // Floors a little under what this measured with the kinds (issue 16's targets: material
    // ≥ 85 %), so that a regression fails; far above the majority class (40 % of recordings).
    // Labelled by class only (85.2 % / 81 of 100 when measured) the run only reports.
    if class_only() {
        return;
    }
    assert!(
        pct(fa, fb) >= 80.0,
        "material per frame {:.1} %",
        pct(fa, fb)
    );
    assert!(
        pct(ra, rb) >= 85.0,
        "material per recording {:.1} %",
        pct(ra, rb)
    );
}
