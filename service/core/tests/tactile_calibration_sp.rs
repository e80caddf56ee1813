//! Calibrations of a sensor that gives only its electrodes (issue 16 part 3), on the real
//! BioTac SP recordings (../shared/testdata/tactile/biotac_sp; no licence: they calibrate at test
//! time and are measured on, nothing fitted here is stored or shipped). Split by object: no
//! object is on both sides of a split (`the_splits_are_by_object` fails if one is).
//!
//! * **Stable vs slip** (the grasp-stability set, yayaneath/biotac-sp-images: one snapshot of
//!   the three fingers' 24 electrodes per grasp, 1,276 grasps of 41 objects): one calibration of
//!   the sensor, fitted on every finger's snapshot of the training grasps (windows of one
//!   reading, the raw values: a snapshot has no baseline to tare against), event `contact` for a
//!   stable grasp and `slip` for one that slipped; five folds, the objects dealt to them in
//!   name order. Each test grasp is one frame of a session of three electrodes_only fingers
//!   naming the calibration; the grasp is judged slipping when the fingers' log-odds of slip
//!   over contact add up above 0.
//! * **Touch vs slip** (the direction-of-slip set, yayaneath/BioTacSP-DoS "Basic": 111 sequences
//!   of one index finger on four objects, a held touch or one of six slides): fitted on three
//!   objects (touch → `contact`, every slide → `slip`, 50 baseline frames, windows of 32 every
//!   3rd reading), tested on the fourth through an electrodes_only session, each object in turn.
//!   The slides are labelled with their direction too (n, e, s, w, cw, aw): the session names a
//!   direction while it reports slip. The labels of this set were recorded one after another
//!   (docs/tactile-calibration.md): the figure is what its sequences support, split by object.
//!
//! `cargo test -p graspd-core --test tactile_calibration_sp -- --nocapture` prints the tables
//! (docs/tactile-calibration.md keeps them). Skipped, with a note, without the data.

use graspd_core::tactile::layout::SensorCatalog;
use graspd_core::tactile::{
    Baseline, CalibratedDetector, Calibration, CalibrationRecording, CalibrationSettings,
    ContactEvent, ElectrodePolarity, EventDetector, FingerConfig, FingerReading, Frame,
    ModelFreeThresholds, SlipDirection, Stabilizer, StabilizerConfig, TareConfig,
};
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;
use std::sync::Arc;

fn sp_dir() -> Option<PathBuf> {
    let d = graspd_testkit::testdata_dir().join("tactile/biotac_sp");
    d.is_dir().then_some(d)
}

/// One grasp of the stability set: its object, whether it slipped, and each finger's (ff, mf,
/// th) 24 electrodes.
struct Grasp {
    object: String,
    slipped: bool,
    fingers: [Vec<f64>; 3],
}

fn grasps(dir: &std::path::Path) -> Vec<Grasp> {
    let text = std::fs::read_to_string(dir.join("biotac-palmdown-grasps.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (object, slipped) = (col("object"), col("slipped"));
    let electrodes = |finger: &str| -> Vec<usize> {
        (1..=24)
            .map(|k| col(&format!("{finger}_biotac_{k}")))
            .collect()
    };
    let cols = [electrodes("ff"), electrodes("mf"), electrodes("th")];
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            Grasp {
                object: v[object].to_string(),
                slipped: v[slipped].trim() == "1",
                fingers: cols
                    .clone()
                    .map(|c| c.iter().map(|&i| v[i].trim().parse().unwrap()).collect()),
            }
        })
        .collect()
}

/// The fold of each object: objects in name order dealt to five folds in turn.
fn folds(objects: impl Iterator<Item = String>) -> BTreeMap<String, usize> {
    let names: BTreeSet<String> = objects.collect();
    names
        .into_iter()
        .enumerate()
        .map(|(i, o)| (o, i % 5))
        .collect()
}

/// One sequence of the direction-of-slip set: its label (folder), object and readings.
struct Sequence {
    label: String,
    object: String,
    readings: Vec<FingerReading>,
}

fn sequences(dir: &std::path::Path) -> Vec<Sequence> {
    let mut out = Vec::new();
    let root = dir.join("dos_basic");
    let mut labels: Vec<_> = std::fs::read_dir(&root).unwrap().flatten().collect();
    labels.sort_by_key(|e| e.file_name());
    for label in labels {
        let mut files: Vec<_> = std::fs::read_dir(label.path()).unwrap().flatten().collect();
        files.sort_by_key(|e| e.file_name());
        for file in files {
            let name = file.file_name().to_string_lossy().into_owned();
            let object: String = name
                .chars()
                .take_while(|c| c.is_ascii_alphabetic())
                .collect();
            let text = std::fs::read_to_string(file.path()).unwrap();
            let rec = graspd_core::tactile::Recording::from_csv(&text, None, None).unwrap();
            assert!(rec.electrodes_only);
            out.push(Sequence {
                label: label.file_name().to_string_lossy().into_owned(),
                object,
                readings: rec.rows.iter().map(|r| r.reading()).collect(),
            });
        }
    }
    out
}

fn finger(tare: TareConfig) -> FingerConfig {
    FingerConfig {
        electrodes_only: true,
        name: "ff".into(),
        layout: SensorCatalog::builtin().get("biotac_sp").unwrap().clone(),
        tare,
    }
}

fn session(c: &Arc<Calibration>, fingers: usize) -> Stabilizer {
    session_of(&vec![c.clone(); fingers])
}

/// A session whose finger k detects with `calibrations[k]` (as `fingers[k].calibration` asks).
fn session_of(calibrations: &[Arc<Calibration>]) -> Stabilizer {
    let c = &calibrations[0];
    let mut config = StabilizerConfig::for_fingers(
        (0..calibrations.len())
            .map(|k| FingerConfig {
                name: format!("f{k}"),
                ..finger(c.settings.tare)
            })
            .collect(),
    );
    (config.window_length, config.stride) = (c.settings.window_length, c.settings.stride);
    let detectors = calibrations
        .iter()
        .map(|c| {
            Box::new(CalibratedDetector::new(
                c.clone(),
                ModelFreeThresholds::default(),
            )) as Box<dyn EventDetector>
        })
        .collect();
    Stabilizer::with_detectors(config, detectors).unwrap()
}

fn pct(a: usize, b: usize) -> f64 {
    100.0 * a as f64 / b.max(1) as f64
}

#[test]
fn the_splits_are_by_object() {
    let Some(dir) = sp_dir() else {
        eprintln!("skipped: no BioTac SP recordings");
        return;
    };
    let g = grasps(&dir);
    let fold = folds(g.iter().map(|x| x.object.clone()));
    assert_eq!(fold.len(), 41);
    for k in 0..5 {
        let train: BTreeSet<&str> = g
            .iter()
            .filter(|x| fold[&x.object] != k)
            .map(|x| x.object.as_str())
            .collect();
        let test: BTreeSet<&str> = g
            .iter()
            .filter(|x| fold[&x.object] == k)
            .map(|x| x.object.as_str())
            .collect();
        assert!(!test.is_empty() && train.is_disjoint(&test), "fold {k}");
    }
    let s = sequences(&dir);
    let objects: BTreeSet<&str> = s.iter().map(|x| x.object.as_str()).collect();
    assert_eq!(objects, BTreeSet::from(["case", "hd", "pen", "sponge"]));
    assert_eq!(s.len(), 111);
}

/// Stable vs slip on the grasp-stability set (module doc): well above the majority answer.
#[test]
fn a_calibration_tells_stable_grasps_from_slipping_ones() {
    let Some(dir) = sp_dir() else {
        eprintln!("skipped: no BioTac SP recordings");
        return;
    };
    let g = grasps(&dir);
    let fold = folds(g.iter().map(|x| x.object.clone()));
    let settings = CalibrationSettings {
        window_length: 1,
        stride: 1,
        tare: TareConfig::pretared(),
        electrodes_only: true,
    };
    // The training grasps' snapshots of the fingers in `which` as recordings.
    let recordings = |k: usize, which: &[usize]| -> Vec<CalibrationRecording> {
        g.iter()
            .filter(|x| fold[&x.object] != k)
            .flat_map(|x| {
                let event = if x.slipped {
                    ContactEvent::Slip
                } else {
                    ContactEvent::Contact
                };
                which.iter().map(move |&f| CalibrationRecording {
                    material: None,
                    readings: vec![FingerReading {
                        electrodes: x.fingers[f].clone(),
                        ..FingerReading::default()
                    }],
                    events: Some(vec![event]),
                    slip_direction: None,
                })
            })
            .collect()
    };
    // Right answers: the grasp by the fingers' log-odds added (one calibration for the
    // sensor; one per finger), each finger alone (one calibration for the sensor).
    let (mut right, mut right_own, mut per_finger, mut fit_ms) = (0, 0, [0usize; 3], 0.0);
    let fit = |recs: &[CalibrationRecording]| {
        Arc::new(Calibration::fit("grasps", recs, settings).unwrap())
    };
    for k in 0..5 {
        let c = fit(&recordings(k, &[0, 1, 2]));
        fit_ms += c.summary.fit_ms;
        let own: Vec<Arc<Calibration>> = (0..3).map(|f| fit(&recordings(k, &[f]))).collect();
        for x in g.iter().filter(|x| fold[&x.object] == k) {
            let frame = Frame {
                timestamp: 0.0,
                fingers: x
                    .fingers
                    .iter()
                    .map(|e| FingerReading {
                        electrodes: e.clone(),
                        ..FingerReading::default()
                    })
                    .collect(),
            };
            let log_odds = |out: &graspd_core::tactile::FrameResult| -> f64 {
                out.fingers
                    .iter()
                    .map(|r| {
                        let [_, contact, slip] = r.event_probabilities;
                        (slip.max(1e-12) / contact.max(1e-12)).ln()
                    })
                    .sum()
            };
            let out = session(&c, 3).step(&frame).unwrap();
            for (f, r) in out.fingers.iter().enumerate() {
                per_finger[f] += usize::from((r.event == ContactEvent::Slip) == x.slipped);
            }
            right += usize::from((log_odds(&out) > 0.0) == x.slipped);
            let out = session_of(&own).step(&frame).unwrap();
            right_own += usize::from((log_odds(&out) > 0.0) == x.slipped);
        }
    }
    let n = g.len();
    let slipped = g.iter().filter(|x| x.slipped).count();
    let majority = slipped.max(n - slipped);
    eprintln!("| grasps (41 objects, 5 folds by object) | stable vs slip |");
    eprintln!("|---|---:|");
    for (f, name) in ["index (ff)", "middle (mf)", "thumb (th)"]
        .iter()
        .enumerate()
    {
        eprintln!("| one finger, {name} | {:.1} % |", pct(per_finger[f], n));
    }
    eprintln!(
        "| **the three fingers' log-odds added** | **{:.1} %** ({right}/{n}) |",
        pct(right, n)
    );
    eprintln!(
        "| the same, one calibration per finger (`fingers[i].calibration`) | {:.1} % ({right_own}/{n}) |",
        pct(right_own, n)
    );
    eprintln!(
        "| majority answer (stable) | {:.1} % |\nfitted five times in {:.0} ms in all",
        pct(majority, n),
        fit_ms
    );
    assert!(
        pct(right, n) >= 80.0 && right > majority + n / 4,
        "{right} of {n} grasps (majority {majority})"
    );
    assert!(pct(right_own, n) >= 80.0, "{right_own} of {n} grasps");
}

/// Touch vs slip on the direction-of-slip set (module doc), each object left out in turn.
#[test]
fn a_calibration_on_three_objects_tells_touch_from_slip_on_the_fourth() {
    let Some(dir) = sp_dir() else {
        eprintln!("skipped: no BioTac SP recordings");
        return;
    };
    let seqs = sequences(&dir);
    let settings = CalibrationSettings {
        tare: TareConfig {
            baseline: Baseline::FirstFrames(50),
            electrode_polarity: ElectrodePolarity::Falling,
        },
        electrodes_only: true,
        ..CalibrationSettings::default()
    };
    let event = |label: &str| {
        if label == "t" {
            ContactEvent::Contact
        } else {
            ContactEvent::Slip
        }
    };
    // Per event: windows right / all, recordings right (the majority of its frames) / all.
    let mut windows = [(0usize, 0usize); 2];
    let mut recordings = [(0usize, 0usize); 2];
    // Slides: slipping frames with the right direction / slipping frames; recordings whose
    // most named direction is right.
    let (mut dir_frames, mut dir_recordings) = ((0usize, 0usize), (0usize, 0usize));
    let objects: BTreeSet<String> = seqs.iter().map(|s| s.object.clone()).collect();
    for held_out in &objects {
        let train: Vec<CalibrationRecording> = seqs
            .iter()
            .filter(|s| &s.object != held_out)
            .map(|s| CalibrationRecording {
                material: None,
                readings: s.readings.clone(),
                events: Some(vec![event(&s.label); s.readings.len()]),
                slip_direction: SlipDirection::parse(&s.label),
            })
            .collect();
        let c = Arc::new(Calibration::fit("dos", &train, settings).unwrap());
        for s in seqs.iter().filter(|s| &s.object == held_out) {
            let want = event(&s.label);
            let k = usize::from(want == ContactEvent::Slip);
            let mut session = session(&c, 1);
            let (mut ok, mut n) = (0, 0);
            let mut named = [0usize; 6];
            for (i, r) in s.readings.iter().enumerate() {
                let out = session
                    .step(&Frame {
                        timestamp: 0.01 * i as f64,
                        fingers: vec![r.clone()],
                    })
                    .unwrap();
                // Frames with a full window (50 baseline frames, then 32 every 3rd).
                if i >= 50 + 3 * 31 {
                    n += 1;
                    ok += usize::from((out.fingers[0].event == ContactEvent::Slip) == (k == 1));
                }
                if let Some(d) = out.fingers[0].slip_direction {
                    named[SlipDirection::ALL.iter().position(|&x| x == d).unwrap()] += 1;
                }
            }
            windows[k].0 += ok;
            windows[k].1 += n;
            recordings[k].0 += usize::from(2 * ok > n);
            recordings[k].1 += 1;
            if let Some(want) = SlipDirection::parse(&s.label) {
                let w = SlipDirection::ALL.iter().position(|&x| x == want).unwrap();
                dir_frames.0 += named[w];
                dir_frames.1 += named.iter().sum::<usize>();
                let top = (0..6).max_by_key(|&j| named[j]).unwrap();
                dir_recordings.0 += usize::from(named[top] > 0 && top == w);
                dir_recordings.1 += 1;
            }
        }
    }
    let all = |v: &[(usize, usize); 2]| (v[0].0 + v[1].0, v[0].1 + v[1].1);
    let (wa, wb) = all(&windows);
    let (ra, rb) = all(&recordings);
    eprintln!("| direction-of-slip set, each object left out | frames | recordings |");
    eprintln!("|---|---:|---:|");
    for (k, name) in ["held touch (t)", "slides (n, e, s, w, cw, aw)"]
        .iter()
        .enumerate()
    {
        eprintln!(
            "| {name} | {:.1} % ({}/{}) | {}/{} |",
            pct(windows[k].0, windows[k].1),
            windows[k].0,
            windows[k].1,
            recordings[k].0,
            recordings[k].1
        );
    }
    eprintln!(
        "| **all** | **{:.1} %** | **{ra}/{rb}** |\n| majority answer (slip) | {:.1} % | {}/{rb} |",
        pct(wa, wb),
        pct(windows[1].1, wb),
        recordings[1].1
    );
    eprintln!(
        "\n| slip direction (6 labels), each object left out | slipping frames | slide recordings (most named) |\n|---|---:|---:|\n| calibration | {:.1} % ({}/{}) | {}/{} |\n| chance | 16.7 % | — |\n| published (ConvLSTM, split unknown) | 82.6 % | — |",
        pct(dir_frames.0, dir_frames.1),
        dir_frames.0,
        dir_frames.1,
        dir_recordings.0,
        dir_recordings.1
    );
    assert_eq!((rb, dir_recordings.1), (111, 95));
    assert!(
        pct(dir_frames.0, dir_frames.1) > 2.0 * 100.0 / 6.0,
        "the direction in {dir_frames:?} slipping frames: not twice chance"
    );
    // Both answers are given, and each mostly where it belongs.
    assert!(
        pct(windows[0].0, windows[0].1) > 50.0 && pct(windows[1].0, windows[1].1) > 50.0,
        "{windows:?}"
    );
}
