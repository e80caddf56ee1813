//! The shipped tactile detector (models/tactile/tactile_detector.onnx, method.md §5) through
//! graspd's own code: the windows the stabilizer hands the detector equal the ones the training
//! script builds (taring, pac features, sampling, padding: tests/fixtures/tactile_model/
//! probe.json), the ONNX probabilities equal those ONNX Runtime gave in Python, the accuracy on
//! held-out generated sequences stays above a floor (a broken export or preprocessing fails
//! here), and malformed models are refused at load with a message naming what is wrong.
//!
//! Needs the ONNX Runtime library: `$ORT_DYLIB_PATH`, else
//! `<repo>/.tools/onnxruntime/libonnxruntime.so.1.31.1` (scripts/fetch-onnxruntime.sh).

#[path = "common/onnx_builder.rs"]
mod onnx_builder;

use graspd_core::onnx_runtime::init_onnx_runtime;
use graspd_core::tactile::detector::{
    ContactEvent, Detection, DetectorSample, EventDetector, Material,
};
use graspd_core::tactile::layout::SensorLayout;
use graspd_core::tactile::recording::Recording;
use graspd_core::tactile::stabilizer::{FingerConfig, Stabilizer, StabilizerConfig};
use graspd_core::tactile::taring::TareConfig;
use graspd_core::tactile::{LstmDetector, TactileModel};
use onnx_builder::{Dim, FLOAT, ModelBuilder, attr_ints};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

const ORT_LIB: &str = ".tools/onnxruntime/libonnxruntime.so.1.31.1";

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn init() {
    let lib = std::env::var_os("ORT_DYLIB_PATH")
        .filter(|p| !p.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join(ORT_LIB));
    assert!(
        lib.is_file(),
        "the ONNX Runtime library is missing: run scripts/fetch-onnxruntime.sh or set ORT_DYLIB_PATH"
    );
    init_onnx_runtime(Some(&lib)).unwrap_or_else(|e| panic!("{e}"));
}

fn shipped() -> Arc<TactileModel> {
    init();
    let path = repo().join("models/tactile/tactile_detector.onnx");
    Arc::new(TactileModel::load(&path).unwrap_or_else(|e| panic!("{e}")))
}

fn fixture_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/tactile_model")
}

/// A finger as the training script tares the sequence: `raw` = TareConfig::default(),
/// `pretared` = TareConfig::pretared().
fn session(style: &str) -> StabilizerConfig {
    StabilizerConfig::for_fingers(vec![FingerConfig {
        electrodes_only: false,
        name: "ff".into(),
        layout: SensorLayout::biotac(),
        tare: if style == "raw" {
            TareConfig::default()
        } else {
            TareConfig::pretared()
        },
    }])
}

/// Reads `<name>_bio.csv` and `<name>_labels.csv` (event and material per frame).
fn fixture(name: &str) -> (Recording, Vec<ContactEvent>, Material) {
    let dir = fixture_dir();
    let bio = std::fs::read_to_string(dir.join(format!("{name}_bio.csv"))).unwrap();
    let labels = std::fs::read_to_string(dir.join(format!("{name}_labels.csv"))).unwrap();
    let mut events = Vec::new();
    let mut material = Material::Unknown;
    for line in labels.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        events.push(match f[1] {
            "non_contact" => ContactEvent::NonContact,
            "contact" => ContactEvent::Contact,
            "slip" => ContactEvent::Slip,
            other => panic!("{name}: unknown event {other}"),
        });
        material = *Material::CLASSES
            .iter()
            .find(|m| m.name() == f[2])
            .unwrap_or_else(|| panic!("{name}: unknown material {}", f[2]));
    }
    let rec = Recording::from_csv(&bio, None, None).unwrap();
    assert_eq!(rec.rows.len(), events.len(), "{name}: one label per frame");
    (rec, events, material)
}

fn fixture_names() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(fixture_dir())
        .unwrap()
        .filter_map(|e| {
            let n = e.ok()?.file_name().into_string().ok()?;
            n.strip_suffix("_bio.csv").map(str::to_string)
        })
        .collect();
    names.sort();
    assert!(names.len() >= 4, "fixture sequences missing: {names:?}");
    names
}

/// Records every window the stabilizer hands its detector.
struct Recorder(Arc<Mutex<Vec<Vec<DetectorSample>>>>);

impl EventDetector for Recorder {
    fn detect(&mut self, window: &[DetectorSample]) -> Detection {
        self.0.lock().unwrap().push(window.to_vec());
        Detection {
            event: ContactEvent::NonContact,
            event_probabilities: [1.0, 0.0, 0.0],
            material: Material::Unknown,
            material_probabilities: None,
            slip_direction: None,
        }
    }
}

fn probe() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(fixture_dir().join("probe.json")).unwrap())
        .unwrap()
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// The stabilizer builds exactly the windows train.py trains on (taring, pac mean and
/// vibration, every k-th reading, the last l), and the model gives the probabilities ONNX
/// Runtime gave in Python for them.
#[test]
fn stabilizer_windows_and_probabilities_match_the_training_pipeline() {
    let probe = probe();
    let name = probe["sequence"].as_str().unwrap();
    let style = probe["style"].as_str().unwrap();
    let (rec, _, _) = fixture(name);
    let seen = Arc::new(Mutex::new(Vec::new()));
    let mut stab =
        Stabilizer::with_detectors(session(style), vec![Box::new(Recorder(seen.clone()))]).unwrap();
    // Frame index → the window handed to the detector at that frame.
    let mut at_frame = std::collections::BTreeMap::new();
    for (i, f) in rec.frames().iter().enumerate() {
        let before = seen.lock().unwrap().len();
        stab.step(f).unwrap();
        let w = seen.lock().unwrap();
        if w.len() > before {
            at_frame.insert(i as u64, w.last().unwrap().clone());
        }
    }
    let model = shipped();
    let mut detector = LstmDetector::new(model.clone());
    let mut scratch = Vec::new();
    let probes = probe["windows"].as_array().unwrap();
    assert!(probes.len() >= 3);
    for p in probes {
        let frame = p["frame"].as_u64().unwrap();
        let got = at_frame
            .get(&frame)
            .unwrap_or_else(|| panic!("no detection at frame {frame}"));
        let want: Vec<Vec<f64>> = p["window"].as_array().unwrap().iter().map(floats).collect();
        assert_eq!(got.len(), want.len(), "window length at frame {frame}");
        for (s, w) in got.iter().zip(&want) {
            let mut v = vec![s.pdc, s.pac, s.pac_vibration, s.tdc, s.tac];
            v.extend(&s.electrodes);
            assert_eq!(v.len(), w.len());
            for (a, b) in v.iter().zip(w) {
                assert!(
                    (a - b).abs() <= 1e-9 * b.abs().max(1.0),
                    "frame {frame}: graspd {a} vs training {b}"
                );
            }
        }
        let (ev, mat) = model.infer(got, &mut scratch).unwrap();
        for (a, b) in ev.iter().chain(&mat).zip(
            floats(&p["event_probabilities"])
                .iter()
                .chain(&floats(&p["material_probabilities"])),
        ) {
            assert!(
                (a - b).abs() < 1e-4,
                "frame {frame}: probability {a} vs {b}"
            );
        }
        // The detector reports material only in contact.
        let d = detector.detect(got);
        assert_eq!(
            d.material_probabilities.is_some(),
            d.event != ContactEvent::NonContact
        );
    }
}

/// Accuracy floors on held-out generated sequences run through the stabilizer with the model,
/// frame by frame as graspd reports them. Measured when the model was trained (see
/// models/tactile/metrics.json and MODEL_CARD.md); the floors sit a few points lower.
#[test]
fn shipped_model_accuracy_on_generated_fixture() {
    let model = shipped();
    assert_eq!(model.window_length(), 32);
    assert_eq!(model.stride(), 3);
    assert_eq!(model.electrode_count(), 19);
    let (mut n, mut event_ok, mut contact_ok) = (0usize, 0usize, 0usize);
    let (mut n_mat, mut mat_ok) = (0usize, 0usize);
    for name in fixture_names() {
        let style = if name.ends_with("_raw") {
            "raw"
        } else {
            "pretared"
        };
        let (rec, labels, material) = fixture(&name);
        let mut stab = Stabilizer::with_detectors(
            session(style),
            vec![Box::new(LstmDetector::new(model.clone()))],
        )
        .unwrap();
        let (mut ne, mut ok) = (0, 0);
        for (f, label) in rec.frames().iter().zip(&labels) {
            let r = &stab.step(f).unwrap().fingers[0];
            n += 1;
            ne += 1;
            event_ok += (r.event == *label) as usize;
            ok += (r.event == *label) as usize;
            contact_ok += ((r.event == ContactEvent::NonContact)
                == (*label == ContactEvent::NonContact)) as usize;
            if *label != ContactEvent::NonContact {
                n_mat += 1;
                mat_ok += (r.material == material) as usize;
            }
            if r.event == ContactEvent::NonContact {
                assert_eq!(r.material, Material::Unknown);
                assert!(r.material_probabilities.is_none());
            }
        }
        println!("{name}: event {:.1} %", 100.0 * ok as f64 / ne as f64);
    }
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    println!(
        "fixture: {n} frames, event {:.1} %, contact {:.1} %, material (labelled contact) {:.1} %",
        pct(event_ok, n),
        pct(contact_ok, n),
        pct(mat_ok, n_mat)
    );
    assert!(pct(event_ok, n) >= EVENT_FLOOR, "event accuracy fell");
    assert!(pct(contact_ok, n) >= CONTACT_FLOOR, "contact accuracy fell");
    assert!(
        pct(mat_ok, n_mat) >= MATERIAL_FLOOR,
        "material accuracy fell"
    );
}

/// Measured with the shipped model (1 200 frames, 4 sequences): event 81.2 %, contact 93.8 %,
/// material 64.9 % (held-out generated average: event 95.7 %, contact 98.5 %, material 62.1 %,
/// metrics.json; this fixture's first 3 s include short holds right after the press, where the
/// model calls the make transient of the pac level slip: gen3_metal_pretared scores 43 %).
/// Chance is 33 % / 25 %.
const EVENT_FLOOR: f64 = 79.0;
const CONTACT_FLOOR: f64 = 92.0;
const MATERIAL_FLOOR: f64 = 62.0;

/// A small model that follows the contract: mean over time, then two linear maps.
fn tiny(features: usize, window: i64) -> ModelBuilder {
    tiny_batched(features, window, Dim::Fixed(1), Dim::Fixed(1), 0.0)
}

/// [`tiny`] with the input's and the outputs' batch axes as given and weights that differ by
/// `spread` from one entry to the next (0: equal weights, uniform probabilities).
fn tiny_batched(
    features: usize,
    window: i64,
    batch_in: Dim,
    batch_out: Dim,
    spread: f32,
) -> ModelBuilder {
    let weights = |n: usize| {
        (0..n)
            .map(|k| 0.01 + spread * k as f32)
            .collect::<Vec<f32>>()
    };
    let out = |n: i64| [batch_out, n.into()];
    ModelBuilder::new("tiny_tactile")
        .input(
            "window",
            FLOAT,
            &[batch_in, window.into(), (features as i64).into()],
        )
        .initializer("we", &[features as i64, 3], weights(features * 3))
        .initializer("wm", &[features as i64, 4], weights(features * 4))
        .node(
            "ReduceMean",
            &["window"],
            &["pooled"],
            vec![
                attr_ints("axes", &[1]),
                onnx_builder::attr_int("keepdims", 0),
            ],
        )
        .node("MatMul", &["pooled", "we"], &["event_logits"], vec![])
        .node("MatMul", &["pooled", "wm"], &["material_logits"], vec![])
        .output("event_logits", FLOAT, &out(3))
        .output("material_logits", FLOAT, &out(4))
}

fn with_meta(b: ModelBuilder, skip: &str, replace: Option<(&str, &str)>) -> ModelBuilder {
    let features = "pdc,pac,pac_vibration,tdc,tac,e1,e2,e3";
    let ones = ["1"; 8].join(",");
    let zeros = ["0"; 8].join(",");
    let mut b = b;
    for (k, v) in [
        ("graspd.tactile.features", features),
        ("graspd.tactile.mean", zeros.as_str()),
        ("graspd.tactile.std", ones.as_str()),
        ("graspd.tactile.window", "32"),
        ("graspd.tactile.stride", "3"),
        ("graspd.tactile.padding", "repeat_oldest"),
        ("graspd.tactile.events", "non_contact,contact,slip"),
        ("graspd.tactile.materials", "paper,foam,plastic,metal"),
    ] {
        if k == skip {
            continue;
        }
        let v = match replace {
            Some((rk, rv)) if rk == k => rv,
            _ => v,
        };
        b = b.metadata(k, v);
    }
    b
}

fn load_err(bytes: &[u8]) -> String {
    init();
    match TactileModel::from_bytes(bytes, "test.onnx") {
        Ok(_) => panic!("a malformed model was accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn well_formed_tiny_model_loads_and_runs() {
    init();
    let m = TactileModel::from_bytes(&with_meta(tiny(8, 32), "", None).build(), "tiny").unwrap();
    assert_eq!(
        (m.window_length(), m.stride(), m.electrode_count()),
        (32, 3, 3)
    );
    let s = DetectorSample {
        pdc: 1.0,
        pac: 0.0,
        pac_vibration: 0.0,
        pac_samples: vec![0.0],
        tdc: 0.0,
        tac: 0.0,
        electrodes: vec![0.0; 3],
    };
    let (ev, mat) = m.infer(&[s], &mut Vec::new()).unwrap();
    // Equal weights: uniform probabilities.
    assert!(ev.iter().all(|p| (p - 1.0 / 3.0).abs() < 1e-6), "{ev:?}");
    assert!(mat.iter().all(|p| (p - 0.25).abs() < 1e-6), "{mat:?}");
}

#[test]
fn malformed_models_are_refused_with_a_message_naming_the_problem() {
    let e = load_err(b"not an onnx file");
    assert!(
        e.starts_with("cannot load the tactile model test.onnx"),
        "{e}"
    );
    let e = load_err(&with_meta(tiny(8, 32), "graspd.tactile.mean", None).build());
    assert!(e.contains("metadata graspd.tactile.mean is missing"), "{e}");
    assert!(e.contains("does not follow its contract"), "{e}");
    let e = load_err(
        &with_meta(
            tiny(8, 32),
            "",
            Some(("graspd.tactile.features", "pdc,pac,force")),
        )
        .build(),
    );
    assert!(e.contains("unknown feature 'force'"), "{e}");
    let e = load_err(&with_meta(tiny(8, 32), "", Some(("graspd.tactile.std", "1,1,1"))).build());
    assert!(
        e.contains("graspd.tactile.std has 3 values; it needs 8"),
        "{e}"
    );
    let e = load_err(
        &with_meta(
            tiny(8, 32),
            "",
            Some(("graspd.tactile.materials", "metal,plastic,foam,paper")),
        )
        .build(),
    );
    assert!(e.contains("reads the outputs in the order"), "{e}");
    // Input of 7 channels for 8 features.
    let e = load_err(&with_meta(tiny(7, 32), "", None).build());
    assert!(
        e.contains("input 'window'") && e.contains("[1, 32, 8]"),
        "{e}"
    );
    // Window 16 in the graph, 32 in the metadata.
    let e = load_err(&with_meta(tiny(8, 16), "", None).build());
    assert!(e.contains("[1, 16, 8]"), "{e}");
    // A missing output.
    let b = ModelBuilder::new("one_output")
        .input("window", FLOAT, &[1.into(), 32.into(), Dim::Fixed(8)])
        .initializer("we", &[8, 3], vec![0.0; 24])
        .node(
            "ReduceMean",
            &["window"],
            &["pooled"],
            vec![
                attr_ints("axes", &[1]),
                onnx_builder::attr_int("keepdims", 0),
            ],
        )
        .node("MatMul", &["pooled", "we"], &["event_logits"], vec![])
        .output("event_logits", FLOAT, &[1.into(), 3.into()]);
    let e = load_err(&with_meta(b, "", None).build());
    assert!(e.contains("no output 'material_logits'"), "{e}");
}

fn sample(pdc: f64, e: f64) -> DetectorSample {
    DetectorSample {
        pdc,
        pac: 0.5 * pdc,
        pac_vibration: 0.1 * pdc,
        pac_samples: vec![0.5 * pdc],
        tdc: 0.0,
        tac: 0.0,
        electrodes: vec![e, 2.0 * e, -e],
    }
}

/// With a dynamic batch axis, several windows go through one run and each gets what it gets
/// alone; with batch 1 the same call runs them one by one. A dynamic input with fixed outputs
/// is refused.
#[test]
fn a_batch_of_windows_gives_what_each_window_gives_alone() {
    init();
    let windows: Vec<Vec<DetectorSample>> = (0..5)
        .map(|k| {
            (0..(4 + 7 * k))
                .map(|t| sample(t as f64 * 0.3, k as f64 - t as f64 * 0.1))
                .collect()
        })
        .collect();
    let refs: Vec<&[DetectorSample]> = windows.iter().map(|w| w.as_slice()).collect();
    for (batch, batched) in [(Dim::Param("batch"), true), (Dim::Fixed(1), false)] {
        let bytes = with_meta(tiny_batched(8, 32, batch, batch, 0.003), "", None).build();
        let m = TactileModel::from_bytes(&bytes, "tiny").unwrap();
        assert_eq!(m.is_batched(), batched);
        let together = m.infer_batch(&refs).unwrap();
        assert_eq!(together.len(), refs.len());
        for (w, (ev, mat)) in refs.iter().zip(&together) {
            let (ev1, mat1) = m.infer(w, &mut Vec::new()).unwrap();
            for (a, b) in ev.iter().chain(mat).zip(ev1.iter().chain(&mat1)) {
                assert!((a - b).abs() < 1e-6, "batched {a} vs alone {b}");
            }
        }
        // The windows differ, and so do their probabilities: the rows are not mixed up.
        assert!(
            (together[0].0[0] - together[4].0[0]).abs() > 1e-4,
            "{together:?}"
        );
    }
    let e = load_err(
        &with_meta(
            tiny_batched(8, 32, Dim::Param("batch"), Dim::Fixed(1), 0.0),
            "",
            None,
        )
        .build(),
    );
    assert!(e.contains("output 'event_logits'"), "{e}");
}

/// Sessions stepped together (`Stabilizer::step_many`, one model run for the windows due at the
/// same frame) give each session what stepping it alone gives, on the shipped model (whose batch
/// axis is dynamic) and the held-out generated sequences; a bad frame fails alone.
#[test]
fn sessions_stepped_together_match_sessions_stepped_alone() {
    let model = shipped();
    assert!(
        model.is_batched(),
        "the shipped model's batch axis is dynamic"
    );
    let names = fixture_names();
    let recordings: Vec<(String, Recording)> =
        names.iter().map(|n| (n.clone(), fixture(n).0)).collect();
    let open = |name: &str| {
        let style = if name.ends_with("_raw") {
            "raw"
        } else {
            "pretared"
        };
        Stabilizer::with_detectors(
            session(style),
            vec![Box::new(LstmDetector::new(model.clone()))],
        )
        .unwrap()
    };
    let mut alone: Vec<Stabilizer> = recordings.iter().map(|(n, _)| open(n)).collect();
    let mut together: Vec<Stabilizer> = recordings.iter().map(|(n, _)| open(n)).collect();
    let frames: Vec<Vec<graspd_core::tactile::Frame>> =
        recordings.iter().map(|(_, r)| r.frames()).collect();
    let steps = frames.iter().map(Vec::len).min().unwrap();
    let (mut compared, mut flipped) = (0usize, 0usize);
    for t in 0..steps {
        let want: Vec<_> = alone
            .iter_mut()
            .zip(&frames)
            .map(|(s, f)| s.step(&f[t]).unwrap())
            .collect();
        let mut bad = frames[0][t].clone();
        bad.fingers.clear();
        let mut work: Vec<(&mut Stabilizer, &graspd_core::tactile::Frame)> = together
            .iter_mut()
            .zip(&frames)
            .map(|(s, f)| (s, &f[t]))
            .collect();
        let mut extra = open(&names[0]);
        if t == 5 {
            work.push((&mut extra, &bad));
        }
        let got = Stabilizer::step_many(&mut work);
        if t == 5 {
            let e = got.last().unwrap().as_ref().unwrap_err();
            assert!(e.field.starts_with("frame.fingers"), "{e}");
            assert_eq!(extra.frames(), 0, "a rejected frame changes nothing");
        }
        for (w, g) in want.iter().zip(&got) {
            let (w, g) = (&w.fingers[0], &g.as_ref().unwrap().fingers[0]);
            compared += 1;
            flipped += (w.event != g.event) as usize;
            for (a, b) in w.event_probabilities.iter().zip(&g.event_probabilities) {
                assert!((a - b).abs() < 1e-4, "frame {t}: alone {a} vs together {b}");
            }
            assert_eq!(w.force, g.force);
        }
    }
    assert!(compared > 1000, "{compared} frames compared");
    // Only a probability tie within 1e-5 could flip an event.
    assert_eq!(flipped, 0);
}
