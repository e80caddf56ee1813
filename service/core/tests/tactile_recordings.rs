//! Replays a sample of the real BioTac recordings (../shared/testdata/tactile/biotac_slide,
//! dexrob/BioTac_slide_20_50; see its README for the licence note: measurement only, no training)
//! through the stabilizer with the model-free detector and with the shipped LSTM model
//! (models/tactile), and reports contact / slip accuracy against the labels derived from the
//! arm's wrench and velocity (`tactile::recording`), and for the model the material accuracy.
//!
//! The model was trained on generated data only; samples 1–10 of each material were used to
//! calibrate the generator's statistics (models/tactile/calibrate.py), so the model's numbers
//! here are over the held-out samples 11–20 (`GRASPD_TACTILE_SAMPLES=1-20` for all).
//!
//! Run with `cargo test -p graspd-core --test tactile_recordings -- --nocapture` to see the table.
//! The assertion is only a floor a little under what the detector currently achieves, so that a
//! regression fails; the thresholds were not tuned on these recordings.
//!
//! The data directory is `graspd_testkit::biotac_slide_dir` (`$GRASPD_TACTILE_DATA` or `tactile/
//! biotac_slide` of the shared testdata); the test is skipped (with a note) when neither exists.

use graspd_core::onnx_runtime::init_onnx_runtime;
use graspd_core::tactile::detector::{ContactEvent, EventDetector, Material};
use graspd_core::tactile::layout::SensorLayout;
use graspd_core::tactile::recording::Recording;
use graspd_core::tactile::stabilizer::{FingerConfig, Stabilizer, StabilizerConfig};
use graspd_core::tactile::taring::TareConfig;
use graspd_core::tactile::{LstmDetector, TactileModel};
use graspd_testkit::{BIOTAC_SLIDE_MATERIALS, biotac_slide_dir};
use std::path::PathBuf;
use std::sync::Arc;

/// Samples per material replayed (of 20): 1..=SAMPLES.
const SAMPLES: usize = 4;

fn idx(e: ContactEvent) -> usize {
    match e {
        ContactEvent::NonContact => 0,
        ContactEvent::Contact => 1,
        ContactEvent::Slip => 2,
    }
}

#[test]
fn model_free_detector_on_real_recordings() {
    let Some(dir) = biotac_slide_dir() else {
        eprintln!("tactile recordings not found; skipping (set GRASPD_TACTILE_DATA)");
        return;
    };
    // confusion[label][predicted]
    let mut confusion = [[0u64; 3]; 3];
    let mut per_material: Vec<(String, u64, u64, u64)> = Vec::new(); // (class, n, contact ok, event ok)
    let mut frames_total = 0u64;
    let started = std::time::Instant::now();
    for (mat, class) in BIOTAC_SLIDE_MATERIALS {
        let (mut n, mut contact_ok, mut event_ok) = (0u64, 0u64, 0u64);
        for s in 1..=SAMPLES {
            let base = dir.join(mat).join(format!("{mat}_{s}"));
            let read = |suffix: &str| {
                std::fs::read_to_string(format!("{}_{suffix}.csv", base.display()))
                    .unwrap_or_else(|e| panic!("{}_{suffix}.csv: {e}", base.display()))
            };
            let rec = Recording::from_csv(&read("bio"), Some(&read("cw")), Some(&read("cv")))
                .expect("recording parses");
            let labels = rec.labels.clone().expect("labels");
            let config = StabilizerConfig::for_fingers(vec![FingerConfig {
                electrodes_only: false,
                name: "ff".into(),
                layout: SensorLayout::biotac(),
                // These recordings are baseline-subtracted and clipped upstream.
                tare: TareConfig::pretared(),
            }]);
            let mut stab = Stabilizer::new(config).unwrap();
            for (frame, label) in rec.frames().iter().zip(&labels) {
                let r = stab.step(frame).expect("frame accepted");
                let got = r.fingers[0].event;
                confusion[idx(*label)][idx(got)] += 1;
                n += 1;
                contact_ok += ((*label == ContactEvent::NonContact)
                    == (got == ContactEvent::NonContact)) as u64;
                event_ok += (*label == got) as u64;
            }
        }
        frames_total += n;
        per_material.push((format!("{mat} ({class})"), n, contact_ok, event_ok));
    }
    let elapsed = started.elapsed();
    let total: u64 = confusion.iter().flatten().sum();
    let correct: u64 = (0..3).map(|i| confusion[i][i]).sum();
    let contact_correct: u64 =
        confusion[0][0] + confusion[1][1] + confusion[1][2] + confusion[2][1] + confusion[2][2];
    let slip_correct: u64 = (0..3)
        .flat_map(|l| (0..3).map(move |p| (l, p)))
        .filter(|&(l, p)| (l == 2) == (p == 2))
        .map(|(l, p)| confusion[l][p])
        .sum();
    let label_counts: Vec<u64> = (0..3).map(|l| confusion[l].iter().sum()).collect();
    let majority = *label_counts.iter().max().unwrap();
    let pct = |a: u64, b: u64| 100.0 * a as f64 / b.max(1) as f64;

    println!(
        "\nModel-free detector on {} recordings ({} frames, {:.1} s, {:.0} frames/s in this test build)",
        BIOTAC_SLIDE_MATERIALS.len() * SAMPLES,
        frames_total,
        elapsed.as_secs_f64(),
        frames_total as f64 / elapsed.as_secs_f64()
    );
    println!("confusion (rows = label from wrench/velocity, cols = detected):");
    println!(
        "{:>12} {:>12} {:>12} {:>12}",
        "", "non_contact", "contact", "slip"
    );
    for (l, name) in ["non_contact", "contact", "slip"].iter().enumerate() {
        println!(
            "{:>12} {:>12} {:>12} {:>12}",
            name, confusion[l][0], confusion[l][1], confusion[l][2]
        );
    }
    println!(
        "3-class accuracy {:.1} % | contact vs non-contact {:.1} % | slip vs not {:.1} % | majority-class baseline {:.1} % | dissertation (LSTM, own data) 98.6 %",
        pct(correct, total),
        pct(contact_correct, total),
        pct(slip_correct, total),
        pct(majority, total)
    );
    println!(
        "{:>20} {:>7} {:>10} {:>10}",
        "material", "frames", "contact %", "3-class %"
    );
    for (m, n, c, e) in &per_material {
        println!(
            "{:>20} {:>7} {:>10.1} {:>10.1}",
            m,
            n,
            pct(*c, *n),
            pct(*e, *n)
        );
    }
    // Regression floors (a little under the measured values; see the module doc).
    assert!(
        pct(contact_correct, total) >= FLOOR_CONTACT,
        "contact accuracy fell"
    );
    assert!(pct(correct, total) >= FLOOR_EVENT, "3-class accuracy fell");
}

/// Measured 2026-11-22 with the default thresholds: contact vs non-contact 73.3 %, 3-class 10.9 %
/// (the labels are 98 % slip: the arm slides the sensor during almost the whole recording, and
/// the recordings' pdc/electrodes are baseline-subtracted upstream and decay toward 0 while still
/// pressed, while their pac vibration, median 6 counts, sits under the 10-count slip threshold).
const FLOOR_CONTACT: f64 = 70.0;
const FLOOR_EVENT: f64 = 9.0;

/// Samples 11–20 (held out from the generator's calibration) unless `GRASPD_TACTILE_SAMPLES`
/// says `A-B`.
fn model_samples() -> std::ops::RangeInclusive<usize> {
    std::env::var("GRASPD_TACTILE_SAMPLES")
        .ok()
        .and_then(|s| {
            let (a, b) = s.split_once('-')?;
            Some(a.trim().parse().ok()?..=b.trim().parse().ok()?)
        })
        .unwrap_or(11..=20)
}

fn class_index(class: &str) -> usize {
    Material::CLASSES
        .iter()
        .position(|m| m.name() == class)
        .expect("a material class")
}

/// The shipped model on the real recordings (Tables 6.1 / 6.2 layout): contact and slip
/// accuracy per frame, material accuracy per frame (over frames labelled in contact; a frame
/// the detector calls non-contact counts as wrong) and per recording (the most frequent
/// material graspd reported while in contact).
#[test]
fn lstm_model_on_real_recordings() {
    let Some(dir) = biotac_slide_dir() else {
        eprintln!("tactile recordings not found; skipping (set GRASPD_TACTILE_DATA)");
        return;
    };
    let lib = std::env::var_os("ORT_DYLIB_PATH")
        .filter(|p| !p.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../.tools/onnxruntime/libonnxruntime.so.1.31.1")
        });
    init_onnx_runtime(Some(&lib)).unwrap_or_else(|e| panic!("{e}"));
    let model = Arc::new(
        TactileModel::load(
            &PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../models/tactile/tactile_detector.onnx"),
        )
        .unwrap_or_else(|e| panic!("{e}")),
    );
    let samples = model_samples();
    let mut confusion = [[0u64; 3]; 3];
    let mut mat_frames = [[0u64; 5]; 4]; // [label][reported: 4 classes + unknown]
    let mut mat_recordings = [[0u64; 5]; 4];
    let started = std::time::Instant::now();
    let mut recordings = 0;
    for (mat, class) in BIOTAC_SLIDE_MATERIALS {
        let c = class_index(class);
        for s in samples.clone() {
            let base = dir.join(mat).join(format!("{mat}_{s}"));
            let read = |suffix: &str| {
                std::fs::read_to_string(format!("{}_{suffix}.csv", base.display()))
                    .unwrap_or_else(|e| panic!("{}_{suffix}.csv: {e}", base.display()))
            };
            let rec = Recording::from_csv(&read("bio"), Some(&read("cw")), Some(&read("cv")))
                .expect("recording parses");
            let labels = rec.labels.clone().expect("labels");
            let config = StabilizerConfig::for_fingers(vec![FingerConfig {
                electrodes_only: false,
                name: "ff".into(),
                layout: SensorLayout::biotac(),
                tare: TareConfig::pretared(),
            }]);
            let detector: Box<dyn EventDetector> = Box::new(LstmDetector::new(model.clone()));
            let mut stab = Stabilizer::with_detectors(config, vec![detector]).unwrap();
            let mut votes = [0u64; 5];
            for (frame, label) in rec.frames().iter().zip(&labels) {
                let r = &stab.step(frame).expect("frame accepted").fingers[0];
                confusion[idx(*label)][idx(r.event)] += 1;
                let reported = Material::CLASSES
                    .iter()
                    .position(|m| *m == r.material)
                    .unwrap_or(4);
                if *label != ContactEvent::NonContact {
                    mat_frames[c][reported] += 1;
                }
                if r.event != ContactEvent::NonContact {
                    votes[reported] += 1;
                }
            }
            let vote = (0..5).max_by_key(|&k| votes[k]).unwrap();
            mat_recordings[c][vote] += 1;
            recordings += 1;
        }
    }
    let elapsed = started.elapsed();
    let total: u64 = confusion.iter().flatten().sum();
    let pct = |a: u64, b: u64| 100.0 * a as f64 / b.max(1) as f64;
    let correct: u64 = (0..3).map(|i| confusion[i][i]).sum();
    let contact_correct = confusion[0][0]
        + (1..3)
            .flat_map(|l| (1..3).map(move |p| (l, p)))
            .map(|(l, p)| confusion[l][p])
            .sum::<u64>();
    let slip_correct: u64 = (0..3)
        .flat_map(|l| (0..3).map(move |p| (l, p)))
        .filter(|&(l, p)| (l == 2) == (p == 2))
        .map(|(l, p)| confusion[l][p])
        .sum();
    let majority = (0..3)
        .map(|l| confusion[l].iter().sum::<u64>())
        .max()
        .unwrap();
    let diag = |m: &[[u64; 5]; 4]| (0..4).map(|i| m[i][i]).sum::<u64>();
    let sum = |m: &[[u64; 5]; 4]| m.iter().flatten().sum::<u64>();
    println!(
        "\nLSTM model on {recordings} real recordings (samples {:?}; {total} frames, {:.1} s)",
        samples,
        elapsed.as_secs_f64()
    );
    println!("event confusion (rows = label from wrench/velocity, cols = detected):");
    println!(
        "{:>12} {:>12} {:>12} {:>12}",
        "", "non_contact", "contact", "slip"
    );
    for (l, name) in ["non_contact", "contact", "slip"].iter().enumerate() {
        println!(
            "{:>12} {:>12} {:>12} {:>12}",
            name, confusion[l][0], confusion[l][1], confusion[l][2]
        );
    }
    println!(
        "3-class {:.1} % | contact vs non-contact {:.1} % | slip vs not {:.1} % | majority-class baseline {:.1} %",
        pct(correct, total),
        pct(contact_correct, total),
        pct(slip_correct, total),
        pct(majority, total)
    );
    for (title, m) in [
        ("frames labelled in contact", &mat_frames),
        ("recordings (majority of reports)", &mat_recordings),
    ] {
        println!("material confusion over {title} (cols: paper foam plastic metal unknown):");
        for (i, row) in m.iter().enumerate() {
            println!(
                "{:>8} {:>7} {:>7} {:>7} {:>7} {:>7}   {:.1} %",
                Material::CLASSES[i].name(),
                row[0],
                row[1],
                row[2],
                row[3],
                row[4],
                pct(row[i], row.iter().sum())
            );
        }
        println!("material accuracy: {:.1} %", pct(diag(m), sum(m)));
    }
    // Regression floors a little under the measured values (MODEL_CARD.md); not targets.
    assert!(
        pct(contact_correct, total) >= MODEL_FLOOR_CONTACT,
        "contact accuracy fell"
    );
    assert!(
        pct(slip_correct, total) >= MODEL_FLOOR_SLIP,
        "slip accuracy fell"
    );
}

/// Measured with the shipped model on samples 11–20 (MODEL_CARD.md, "Real recordings"):
/// contact vs non-contact 94.6 %, slip vs not 86.0 % (3-class 85.7 %, material 30.0 % of frames
/// labelled in contact). Regression floors only: the targets (95 % / 85 %) are not met.
const MODEL_FLOOR_CONTACT: f64 = 93.0;
const MODEL_FLOOR_SLIP: f64 = 84.0;
