//! Per-frame latency of the tactile stabilizer's domain core (model-free detector, GMM force
//! estimation, PID), single thread: p50, p99 and frames/s for 1 and 3 classic-BioTac fingers on a
//! synthetic raw stream (baseline, press, slide with pac vibration), and for one finger on the
//! real BioTac recordings of ../shared/testdata/tactile (pre-tared; the GMM's EM needs more
//! iterations on their images than on the synthetic ones). Each case runs twice: with the
//! model-free detector and with the shipped LSTM model (models/tactile/tactile_detector.onnx,
//! ONNX Runtime from `$ORT_DYLIB_PATH` or .tools/onnxruntime; skipped when neither exists). The
//! model runs on every k-th frame (k = 3), so its cost per frame is about a third of a run. The
//! real recordings run a third time with a calibration (`tactile::calibration`) fitted at start
//! on samples 2–5 of each of the ten materials (40 recordings; the fit's time is printed): its
//! features and discriminant also run on every k-th frame.
//! `cargo bench -p graspd-core --bench tactile_frame`.

use graspd_core::onnx_runtime::init_onnx_runtime;
use graspd_core::tactile::detector::EventDetector;
use graspd_core::tactile::layout::SensorLayout;
use graspd_core::tactile::stabilizer::{
    FingerConfig, FingerReading, Frame, Stabilizer, StabilizerConfig,
};
use graspd_core::tactile::taring::TareConfig;
use graspd_core::tactile::{
    CalibratedDetector, Calibration, CalibrationRecording, CalibrationSettings, LstmDetector,
    ModelFreeThresholds, Recording, TactileModel,
};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

fn reading(i: usize) -> FingerReading {
    // 0–1 s rest, 1–3 s press, 3–5 s slide, repeating every 5 s at 100 Hz.
    let phase = i % 500;
    let press = if phase >= 100 { 80.0 } else { 0.0 };
    let mut electrodes = vec![3000.0 + (i % 7) as f64; 19];
    if phase >= 100 {
        for e in [16, 17, 1, 9] {
            electrodes[e] -= 150.0 + (i % 13) as f64;
        }
    }
    let amp = if phase >= 300 { 60.0 } else { 2.0 };
    FingerReading {
        pdc: 2000.0 + press + (i % 3) as f64,
        pac: (0..22)
            .map(|j| 2000.0 + if (i + j).is_multiple_of(2) { amp } else { -amp })
            .collect(),
        tdc: 2500.0,
        tac: 2000.0,
        electrodes,
    }
}

/// Which detector a case runs.
#[derive(Clone, Copy)]
enum Detector<'a> {
    ModelFree,
    Lstm(&'a Arc<TactileModel>),
    Calibrated(&'a Arc<Calibration>),
}

fn run(fingers: usize, frames: usize, model: Detector) {
    let input: Vec<Frame> = (0..frames)
        .map(|i| Frame {
            timestamp: i as f64 * 0.01,
            fingers: (0..fingers).map(|_| reading(i)).collect(),
        })
        .collect();
    measure(
        &format!("{fingers} finger(s), synthetic"),
        fingers,
        TareConfig::default(),
        &input,
        model,
    );
}

/// One finger over the real recordings (every `mat*/mat*_1_bio.csv`), one after the other.
fn run_recordings(limit: usize, model: Detector) {
    let (input, recordings) = real_frames(limit);
    if input.is_empty() {
        println!("1 finger, real recordings: not found, skipped");
        return;
    }
    let label = format!("1 finger, {recordings} real recordings");
    measure(&label, 1, TareConfig::pretared(), &input, model);
}

/// The frames of every `mat*/mat*_1_bio.csv`, one recording after the other, timestamps every
/// 10 ms, at most `limit`, and how many recordings they came from; empty without ../shared.
fn real_frames(limit: usize) -> (Vec<Frame>, usize) {
    let dir = graspd_testkit::testdata_dir().join("tactile/biotac_slide");
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return (Vec::new(), 0);
    };
    let mut paths: Vec<_> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .map(|d| {
            let name = d.file_name().unwrap().to_string_lossy().into_owned();
            d.join(format!("{name}_1_bio.csv"))
        })
        .collect();
    paths.sort();
    let mut input = Vec::new();
    for path in &paths {
        let Ok(text) = std::fs::read_to_string(path) else {
            continue;
        };
        let recording = Recording::from_csv(&text, None, None).expect("recording parses");
        for mut f in recording.frames() {
            f.timestamp = input.len() as f64 * 0.01;
            input.push(f);
        }
    }
    input.truncate(limit);
    (input, paths.len())
}

fn measure(label: &str, fingers: usize, tare: TareConfig, input: &[Frame], model: Detector) {
    let config = StabilizerConfig::for_fingers(
        (0..fingers)
            .map(|f| FingerConfig {
                electrodes_only: false,
                name: format!("f{f}"),
                layout: SensorLayout::biotac(),
                tare,
            })
            .collect(),
    );
    let detector = |_| -> Box<dyn EventDetector> {
        match model {
            Detector::ModelFree => Box::new(graspd_core::tactile::ModelFreeDetector::new(
                ModelFreeThresholds::default(),
            )),
            Detector::Lstm(m) => Box::new(LstmDetector::new(m.clone())),
            Detector::Calibrated(c) => Box::new(CalibratedDetector::new(
                c.clone(),
                ModelFreeThresholds::default(),
            )),
        }
    };
    let detectors = (0..fingers).map(detector).collect();
    let mut stab = Stabilizer::with_detectors(config, detectors).unwrap();
    let label = format!(
        "{label}, {}",
        match model {
            Detector::ModelFree => "model-free",
            Detector::Lstm(_) => "LSTM model",
            Detector::Calibrated(_) => "calibration",
        }
    );
    let frames = input.len();
    let mut lat = Vec::with_capacity(frames);
    let all = Instant::now();
    for f in input {
        let t = Instant::now();
        black_box(stab.step(black_box(f)).unwrap());
        lat.push(t.elapsed().as_secs_f64() * 1e6);
    }
    let total = all.elapsed().as_secs_f64();
    lat.sort_by(f64::total_cmp);
    let q = |p: f64| lat[((p * (lat.len() - 1) as f64) as usize).min(lat.len() - 1)];
    println!(
        "{label}: p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs per frame; {:.0} frames/s on one core",
        q(0.5),
        q(0.99),
        lat[lat.len() - 1],
        frames as f64 / total
    );
}

/// `sessions` one-finger sessions (the real recordings, each session starting `i·37` frames in,
/// so their detections fall on different ticks), stepped tick by tick: one after the other with
/// `Stabilizer::step`, and together with `Stabilizer::step_many` (one model run per tick for the
/// windows due). CPU per frame of each, for a process that steps many sessions in one loop.
fn run_sessions(sessions: usize, ticks: usize, model: &Arc<TactileModel>) {
    let (recordings, _) = real_frames(ticks + sessions * 37);
    if recordings.is_empty() {
        println!("{sessions} sessions: real recordings not found, skipped");
        return;
    }
    let config = || {
        StabilizerConfig::for_fingers(vec![FingerConfig {
            electrodes_only: false,
            name: "f0".into(),
            layout: SensorLayout::biotac(),
            tare: TareConfig::pretared(),
        }])
    };
    let open = || {
        (0..sessions)
            .map(|_| {
                Stabilizer::with_detectors(
                    config(),
                    vec![Box::new(LstmDetector::new(model.clone()))],
                )
                .unwrap()
            })
            .collect::<Vec<_>>()
    };
    let frame = |i: usize, t: usize| {
        let mut f = recordings[(i * 37 + t) % recordings.len()].clone();
        f.timestamp = t as f64 * 0.01;
        f
    };
    let input: Vec<Vec<Frame>> = (0..ticks)
        .map(|t| (0..sessions).map(|i| frame(i, t)).collect())
        .collect();
    let mut alone = open();
    let t0 = Instant::now();
    for tick in &input {
        for (s, f) in alone.iter_mut().zip(tick) {
            black_box(s.step(f).unwrap());
        }
    }
    let one_by_one = t0.elapsed().as_secs_f64();
    let mut together = open();
    let t0 = Instant::now();
    for tick in &input {
        let mut work: Vec<(&mut Stabilizer, &Frame)> = together.iter_mut().zip(tick).collect();
        black_box(Stabilizer::step_many(&mut work));
    }
    let batched = t0.elapsed().as_secs_f64();
    let per = |s: f64| s * 1e6 / (ticks * sessions) as f64;
    println!(
        "{sessions} sessions × 1 finger, real recordings, LSTM model: {:.1} µs per frame one by \
         one (Stabilizer::step), {:.1} µs per frame together (Stabilizer::step_many, one run per \
         tick); {:.0} against {:.0} frames/s on one core",
        per(one_by_one),
        per(batched),
        (ticks * sessions) as f64 / one_by_one,
        (ticks * sessions) as f64 / batched
    );
}

fn main() {
    // `cargo bench` passes `--bench`; `cargo test --benches` runs a short smoke pass.
    let quick = !std::env::args().any(|a| a == "--bench");
    let frames = if quick { 2_000 } else { 50_000 };
    let model = load_model();
    if model.is_none() {
        println!("LSTM model cases skipped: no ONNX Runtime library");
    }
    for m in std::iter::once(Detector::ModelFree).chain(model.as_ref().map(Detector::Lstm)) {
        for fingers in [1, 3] {
            run(fingers, frames, m);
        }
        run_recordings(frames, m);
    }
    if let Some(m) = &model {
        run_sessions(50, if quick { 30 } else { 600 }, m);
    }
    if let Some(c) = fit_calibration() {
        run_recordings(frames, Detector::Calibrated(&c));
    }
}

/// A calibration on samples 2–5 of each material (the bench's recordings are samples 1).
fn fit_calibration() -> Option<Arc<Calibration>> {
    let dir = graspd_testkit::biotac_slide_dir()?;
    let mut recordings = Vec::new();
    for (mat, class) in graspd_testkit::BIOTAC_SLIDE_MATERIALS {
        for sample in 2..=5 {
            let path = dir.join(mat).join(format!("{mat}_{sample}_bio.csv"));
            let text = std::fs::read_to_string(path).ok()?;
            let rec = Recording::from_csv(&text, None, None).expect("recording parses");
            recordings.push(CalibrationRecording {
                material: Some(format!("{class}/{mat}")),
                readings: rec.rows.iter().map(|r| r.reading()).collect(),
                events: None,
                slip_direction: None,
            });
        }
    }
    let settings = CalibrationSettings {
        tare: TareConfig::pretared(),
        ..CalibrationSettings::default()
    };
    let c = Calibration::fit("bench", &recordings, settings).expect("the calibration fits");
    println!(
        "calibration: {} recordings ({} windows) fitted in {:.0} ms on one core",
        c.summary.recordings,
        c.summary
            .material_windows
            .iter()
            .map(|(_, n)| n)
            .sum::<usize>(),
        c.summary.fit_ms
    );
    Some(Arc::new(c))
}

fn load_model() -> Option<Arc<TactileModel>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let lib = std::env::var_os("ORT_DYLIB_PATH")
        .filter(|p| !p.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join(".tools/onnxruntime/libonnxruntime.so.1.31.1"));
    if !lib.is_file() {
        return None;
    }
    init_onnx_runtime(Some(&lib)).expect("ONNX Runtime loads");
    let m = TactileModel::load(&root.join("models/tactile/tactile_detector.onnx"))
        .unwrap_or_else(|e| panic!("{e}"));
    Some(Arc::new(m))
}
