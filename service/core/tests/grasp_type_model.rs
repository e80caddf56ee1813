//! The grasp-type model path (method.md §4, dissertation ch. 4.2.2) on ONNX models built here
//! with known weights (tests/common/onnx_builder.rs, no Python): the model contract checks at
//! load, the sigmoid maps (Eq 4.1–4.2) against hand-computed logits, P(s|O) over a ROI
//! (Eq 4.3), the choice of s* among realisable types, the mean-shift attention pixel and its
//! back-projection, and maps smaller than the frame.
//!
//! Needs the ONNX Runtime library: `$ORT_DYLIB_PATH`, else
//! `<repo>/.tools/onnxruntime/libonnxruntime.so.1.31.1` (scripts/fetch-onnxruntime.sh).

#[path = "common/onnx_builder.rs"]
mod onnx_builder;

use graspd_core::GraspType;
use graspd_core::onnx_runtime::init_onnx_runtime;
use graspd_core::perception::grasp_type::{IMAGENET_MEAN, IMAGENET_STD};
use graspd_core::perception::{
    CameraIntrinsics, DecodedFrame, GraspTypeModel, ModelError, TypeMaps, attention_pixel,
    choose_type, type_probabilities,
};
use onnx_builder::{DOUBLE, Dim, FLOAT, ModelBuilder, conv1x1_model};
use std::path::{Path, PathBuf};

const ORT_LIB: &str = ".tools/onnxruntime/libonnxruntime.so.1.31.1";

fn ort_library() -> PathBuf {
    if let Some(p) = std::env::var_os("ORT_DYLIB_PATH").filter(|p| !p.is_empty()) {
        return p.into();
    }
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(ORT_LIB);
    assert!(
        p.is_file(),
        "the ONNX Runtime library is missing: run scripts/fetch-onnxruntime.sh (it writes {ORT_LIB}) \
         or set ORT_DYLIB_PATH"
    );
    p
}

fn init() {
    let lib = ort_library();
    init_onnx_runtime(Some(&lib)).unwrap_or_else(|e| panic!("{e}"));
}

/// Writes `bytes` as `<name>.onnx` in the test's scratch directory.
fn write_model(name: &str, bytes: &[u8]) -> PathBuf {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("grasp_type_{name}.onnx"));
    std::fs::write(&path, bytes).unwrap();
    path
}

fn load(name: &str, model: ModelBuilder) -> GraspTypeModel {
    init();
    let path = write_model(name, &model.build());
    GraspTypeModel::load(&path, 1).unwrap_or_else(|e| panic!("{e}"))
}

fn load_err(name: &str, bytes: &[u8]) -> String {
    init();
    let path = write_model(name, bytes);
    match GraspTypeModel::load(&path, 1) {
        Ok(_) => panic!("{name}: the model was accepted"),
        Err(e) => e.to_string(),
    }
}

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// Per-type weights on (R, G, B) in [0, 1] and biases, in GraspType::ALL order: each logit is a
/// known linear function of a pixel's colour.
const COLOR_W: [[f32; 3]; 6] = [
    [0.0, 0.0, 0.0],      // large_wrap: 0 everywhere → 0.5
    [-40.0, -40.0, 40.0], // small_wrap: blue
    [-40.0, 40.0, -40.0], // power: green
    [40.0, -40.0, -40.0], // pinch: red
    [10.0, 0.0, 0.0],     // precision: graded with red
    [0.0, 0.0, 0.0],      // tripod: constant −3
];
const COLOR_B: [f32; 6] = [0.0, -20.0, -20.0, -20.0, -5.0, -3.0];

/// The colour model with identity normalisation (mean 0, std 1: inputs are x/255).
fn color_model(input_hw: Option<(i64, i64)>, stride: usize) -> ModelBuilder {
    let output_hw = input_hw.map(|(h, w)| (h / stride as i64, w / stride as i64));
    conv1x1_model(
        3,
        &COLOR_W.map(|w| w.to_vec()),
        &COLOR_B,
        stride,
        input_hw,
        output_hw,
    )
    .metadata("graspd.mean", "0,0,0")
    .metadata("graspd.std", "1, 1, 1")
}

fn color_logit(s: usize, rgb: [u8; 3]) -> f64 {
    // The model computes in f32 from x/255 in f32.
    let x = rgb.map(|c| (c as f32 / 255.0) as f64);
    (0..3).map(|k| COLOR_W[s][k] as f64 * x[k]).sum::<f64>() + COLOR_B[s] as f64
}

const RED: [u8; 3] = [255, 0, 0];
const DARK_RED: [u8; 3] = [150, 0, 0];
const GREEN: [u8; 3] = [0, 255, 0];
const GREY: [u8; 3] = [60, 60, 60];
const BLACK: [u8; 3] = [0, 0, 0];

fn frame(
    w: usize,
    h: usize,
    color: impl Fn(usize, usize) -> [u8; 3],
    depth: impl Fn(usize, usize) -> f32,
) -> DecodedFrame {
    let mut rgb = Vec::with_capacity(3 * w * h);
    let mut d = Vec::with_capacity(w * h);
    for v in 0..h {
        for u in 0..w {
            rgb.extend_from_slice(&color(u, v));
            d.push(depth(u, v));
        }
    }
    DecodedFrame {
        width: w,
        height: h,
        rgb,
        valid_depth: d.iter().filter(|z| **z > 0.0).count(),
        depth: d,
        intrinsics: CameraIntrinsics {
            fx: 500.0,
            fy: 400.0,
            cx: w as f64 / 2.0,
            cy: h as f64 / 2.0,
        },
        camera_to_world: None,
    }
}

fn in_box(u: usize, v: usize, b: [usize; 4]) -> bool {
    (b[0]..b[2]).contains(&u) && (b[1]..b[3]).contains(&v)
}

const RED_BOX: [usize; 4] = [8, 8, 24, 24];
const GREEN_BOX: [usize; 4] = [36, 20, 52, 36];

/// 64 × 48: grey, a red square and a green square.
fn squares_frame() -> DecodedFrame {
    frame(
        64,
        48,
        |u, v| {
            if in_box(u, v, RED_BOX) {
                RED
            } else if in_box(u, v, GREEN_BOX) {
                GREEN
            } else {
                GREY
            }
        },
        |_, _| 1.0,
    )
}

fn mask(w: usize, h: usize, f: impl Fn(usize, usize) -> bool) -> Vec<bool> {
    (0..w * h).map(|i| f(i % w, i / w)).collect()
}

/// Eq 4.3 by hand: the mean over the ROI of sigmoid(logit(pixel colour)).
fn expected_means(f: &DecodedFrame, roi: &[bool]) -> [f64; 6] {
    let mut sums = [0.0; 6];
    let mut n = 0.0;
    for (i, _) in roi.iter().enumerate().filter(|(_, r)| **r) {
        let rgb = f.rgb_at(i % f.width, i / f.width);
        for (s, sum) in sums.iter_mut().enumerate() {
            *sum += sigmoid(color_logit(s, rgb));
        }
        n += 1.0;
    }
    sums.map(|s| s / n)
}

#[test]
fn maps_are_the_sigmoid_of_the_known_logits() {
    let model = load("color", color_model(None, 1));
    assert_eq!(model.channels(), 3);
    assert!(!model.uses_depth());
    assert_eq!(model.input_size(), (None, None));
    assert_eq!(model.normalisation(), ([0.0; 3], [1.0; 3]));
    let f = squares_frame();
    let maps = model.infer(&f).unwrap();
    assert_eq!((maps.width, maps.height), (64, 48));
    assert_eq!(maps.probs.len(), 6 * 64 * 48);
    for v in 0..48 {
        for u in 0..64 {
            for s in GraspType::ALL {
                let want = sigmoid(color_logit(s.index(), f.rgb_at(u, v)));
                let got = maps.prob(s, u, v) as f64;
                assert!(
                    (got - want).abs() < 1e-5,
                    "{s} at ({u}, {v}): {got} vs {want}"
                );
            }
        }
    }
    // Multi-label (Eq 4.1–4.2): on red both pinch and precision are near 1, no softmax.
    assert!(maps.prob(GraspType::Pinch, 10, 10) > 0.99);
    assert!(maps.prob(GraspType::Precision, 10, 10) > 0.99);
    assert!(maps.prob(GraspType::Power, 40, 25) > 0.99);
    // A frame whose buffers do not match its size is refused, not a panic.
    let mut broken = f.clone();
    broken.rgb.pop();
    let e = model.infer(&broken).unwrap_err();
    assert!(matches!(e, ModelError::Inference(_)), "{e:?}");
    assert_eq!((maps.width, maps.height), (64, 48));
    assert_eq!(maps.plane(GraspType::Power).len(), 64 * 48);
}

#[test]
fn default_normalisation_is_imagenet_and_metadata_overrides_it() {
    // Output s = normalised input channel s mod 3, so the logits are the normalised values.
    let identity: Vec<Vec<f32>> = (0..6)
        .map(|s| (0..3).map(|k| if k == s % 3 { 1.0 } else { 0.0 }).collect())
        .collect();
    let pixel = [200u8, 100, 30];
    let f = frame(4, 3, |_, _| pixel, |_, _| 1.0);
    let check = |model: &GraspTypeModel, mean: [f32; 3], std: [f32; 3]| {
        assert_eq!(model.normalisation(), (mean, std));
        let maps = model.infer(&f).unwrap();
        for s in GraspType::ALL {
            let k = s.index() % 3;
            let x = (pixel[k] as f64 / 255.0 - mean[k] as f64) / std[k] as f64;
            let got = maps.prob(s, 1, 1) as f64;
            assert!(
                (got - sigmoid(x)).abs() < 1e-5,
                "{s}: {got} vs {}",
                sigmoid(x)
            );
        }
    };
    let plain = load(
        "imagenet",
        conv1x1_model(3, &identity, &[0.0; 6], 1, None, None),
    );
    check(&plain, IMAGENET_MEAN, IMAGENET_STD);
    let custom = load(
        "custom_norm",
        conv1x1_model(3, &identity, &[0.0; 6], 1, None, None)
            .metadata("graspd.mean", "0.5, 0.25,0.125")
            .metadata("graspd.std", "0.5,0.5,2"),
    );
    check(&custom, [0.5, 0.25, 0.125], [0.5, 0.5, 2.0]);

    let bad = conv1x1_model(3, &identity, &[0.0; 6], 1, None, None)
        .metadata("graspd.std", "1,0,1")
        .build();
    let e = load_err("bad_std", &bad);
    assert!(e.contains("graspd.std") && e.contains("\"1,0,1\""), "{e}");
    let bad = conv1x1_model(3, &identity, &[0.0; 6], 1, None, None)
        .metadata("graspd.mean", "0.5,0.5")
        .build();
    let e = load_err("bad_mean", &bad);
    assert!(e.contains("graspd.mean") && e.contains("three"), "{e}");
}

#[test]
fn depth_channel_is_metres_with_zero_where_invalid() {
    // 4 → 6: tripod = 10·depth − 3; the others as in the colour model.
    let weights: Vec<Vec<f32>> = (0..6)
        .map(|s| {
            let mut w = COLOR_W[s].to_vec();
            w.push(if s == GraspType::Tripod.index() {
                10.0
            } else {
                0.0
            });
            w
        })
        .collect();
    let build = |hw| {
        conv1x1_model(4, &weights, &COLOR_B, 1, hw, hw)
            .metadata("graspd.mean", "0,0,0")
            .metadata("graspd.std", "1,1,1")
    };
    let depth = |u: usize, _v: usize| if u < 33 { 0.8 } else { 0.0 };
    let f = frame(64, 48, |_, _| BLACK, depth);
    let model = load("depth", build(None));
    assert!(model.uses_depth());
    let maps = model.infer(&f).unwrap();
    let t = GraspType::Tripod;
    let tripod = |d: f32| sigmoid(10.0 * d as f64 - 3.0);
    assert!((maps.prob(t, 10, 5) as f64 - tripod(0.8)).abs() < 1e-5);
    assert!((maps.prob(t, 50, 5) as f64 - tripod(0.0)).abs() < 1e-5);

    // Resized to 32 × 24: map column 16 averages frame columns 32 (0.8 m) and 33 (no reading);
    // only the valid reading counts, so its depth is 0.8, not 0.4.
    let model = load("depth_fixed", build(Some((24, 32))));
    let maps = model.infer(&f).unwrap();
    assert_eq!((maps.width, maps.height), (32, 24));
    for (u, want) in [(15, 0.8f32), (16, 0.8), (17, 0.0)] {
        let got = maps.prob(t, u, 3) as f64;
        let want = tripod(want);
        assert!((got - want).abs() < 1e-5, "column {u}: {got} vs {want}");
    }
}

#[test]
fn eq_4_3_is_the_mean_of_each_map_over_the_roi() {
    let model = load("color_eq43", color_model(None, 1));
    let f = squares_frame();
    let maps = model.infer(&f).unwrap();
    let (w, h) = (f.width, f.height);

    let red = mask(w, h, |u, v| in_box(u, v, RED_BOX));
    let p = type_probabilities(&maps, &red, w, h);
    let want = expected_means(&f, &red);
    for s in 0..6 {
        assert!(
            (p[s] - want[s]).abs() < 1e-6,
            "type {s}: {} vs {}",
            p[s],
            want[s]
        );
    }
    assert!(p[GraspType::Pinch.index()] > 1.0 - 1e-6);
    assert!(p[GraspType::Power.index()] < 1e-6);
    assert!(p[GraspType::SmallWrap.index()] < 1e-6);
    assert!((p[GraspType::LargeWrap.index()] - 0.5).abs() < 1e-6);

    // Half red, half green: 8 × 16 pixels of each.
    let half = mask(w, h, |u, v| {
        (16..24).contains(&u) && (8..24).contains(&v)
            || (36..44).contains(&u) && (20..36).contains(&v)
    });
    let p = type_probabilities(&maps, &half, w, h);
    let want = expected_means(&f, &half);
    for s in 0..6 {
        assert!(
            (p[s] - want[s]).abs() < 1e-6,
            "type {s}: {} vs {}",
            p[s],
            want[s]
        );
    }
    assert!((p[GraspType::Pinch.index()] - 0.5).abs() < 1e-6);
    assert!((p[GraspType::Power.index()] - 0.5).abs() < 1e-6);

    // An empty ROI has no mean.
    assert_eq!(
        type_probabilities(&maps, &vec![false; w * h], w, h),
        [0.0; 6]
    );
}

#[test]
fn s_star_is_the_most_probable_realisable_type() {
    let model = load("color_choose", color_model(None, 1));
    let f = squares_frame();
    let maps = model.infer(&f).unwrap();
    let red = mask(f.width, f.height, |u, v| in_box(u, v, RED_BOX));
    let p = type_probabilities(&maps, &red, f.width, f.height);
    // pinch ≈ 1 > precision = σ(5) > large_wrap = 0.5 > tripod = σ(−3) > power, small_wrap.
    use GraspType::*;
    assert_eq!(choose_type(&p, &GraspType::ALL), Some(Pinch));
    assert_eq!(
        choose_type(&p, &[LargeWrap, Power, Precision, Tripod]),
        Some(Precision)
    );
    assert_eq!(choose_type(&p, &[Tripod, LargeWrap]), Some(LargeWrap));
    assert_eq!(choose_type(&p, &[Power, SmallWrap, Tripod]), Some(Tripod));
    assert_eq!(choose_type(&p, &[]), None);
    // Ties go to the lower index; NaN never wins.
    assert_eq!(choose_type(&[0.5; 6], &[Tripod, Power, Pinch]), Some(Power));
    let nan = [f64::NAN, 0.1, 0.2, 0.2, 0.0, 0.0];
    assert_eq!(choose_type(&nan, &GraspType::ALL), Some(Power));
    assert_eq!(choose_type(&nan, &[LargeWrap]), Some(LargeWrap));
}

fn disc(u: usize, v: usize, c: (f64, f64), r: f64) -> bool {
    (u as f64 - c.0).powi(2) + (v as f64 - c.1).powi(2) <= r * r
}

fn assert_near(got: Option<(f64, f64)>, want: (f64, f64), tol: f64) {
    let (x, y) = got.expect("an attention pixel");
    let d = (x - want.0).hypot(y - want.1);
    assert!(
        d <= tol,
        "attention ({x:.2}, {y:.2}) is {d:.2} px from {want:?}"
    );
}

#[test]
fn attention_is_the_centre_of_the_strongest_blob() {
    let model = load("color_attention", color_model(None, 1));
    let (w, h) = (96, 64);
    let all = vec![true; w * h];

    // One red disc: the pinch map peaks there.
    let c = (30.0, 25.0);
    let f = frame(
        w,
        h,
        |u, v| if disc(u, v, c, 5.0) { RED } else { BLACK },
        |_, _| 1.0,
    );
    let maps = model.infer(&f).unwrap();
    assert_near(
        attention_pixel(&maps, GraspType::Pinch, &all, w, h, 6.0),
        c,
        1.5,
    );
    // Inside a ROI box around it, and with a wide bandwidth.
    let roi = mask(w, h, |u, v| in_box(u, v, [10, 5, 60, 50]));
    assert_near(
        attention_pixel(&maps, GraspType::Pinch, &roi, w, h, 6.0),
        c,
        1.5,
    );
    assert_near(
        attention_pixel(&maps, GraspType::Pinch, &all, w, h, 20.0),
        c,
        1.5,
    );

    // Two blobs: a small strong one (precision σ(5)) and a larger weaker one (σ(0.88)). The
    // larger has more mass, the smaller the higher probability: the smaller wins.
    let strong = (20.0, 20.0);
    let weak = (65.0, 40.0);
    let f = frame(
        w,
        h,
        |u, v| {
            if disc(u, v, strong, 4.0) {
                RED
            } else if disc(u, v, weak, 8.0) {
                DARK_RED
            } else {
                BLACK
            }
        },
        |_, _| 1.0,
    );
    let maps = model.infer(&f).unwrap();
    let s = GraspType::Precision;
    assert_near(attention_pixel(&maps, s, &all, w, h, 6.0), strong, 1.5);
    // Without the strong blob in the ROI, the weak one.
    let right = mask(w, h, |u, _| u >= 40);
    assert_near(attention_pixel(&maps, s, &right, w, h, 6.0), weak, 1.5);
    // Deterministic.
    assert_eq!(
        attention_pixel(&maps, s, &all, w, h, 6.0),
        attention_pixel(&maps, s, &all, w, h, 6.0)
    );
    // No ROI, no attention.
    assert_eq!(
        attention_pixel(&maps, s, &vec![false; w * h], w, h, 6.0),
        None
    );
}

#[test]
fn contract_violations_are_named_at_load() {
    let conv = |cin: usize, cout: usize, input: [Dim; 4], output: [Dim; 4]| {
        ModelBuilder::new("bad")
            .input("image", FLOAT, &input)
            .conv(
                "image",
                "logits",
                cin,
                cout,
                1,
                1,
                0,
                vec![0.5; cin * cout],
                vec![0.0; cout],
            )
            .output("logits", FLOAT, &output)
            .build()
    };
    use Dim::Fixed as F;

    // Five output channels.
    let e = load_err(
        "five_types",
        &conv(3, 5, [F(1), F(3), F(48), F(64)], [F(1), F(5), F(48), F(64)]),
    );
    assert!(
        e.contains("output 'logits' has shape [1, 5, 48, 64]") && e.contains("[1, 6, H, W]"),
        "{e}"
    );
    // Two input channels.
    let e = load_err(
        "two_channels",
        &conv(2, 6, [F(1), F(2), F(48), F(64)], [F(1), F(6), F(48), F(64)]),
    );
    assert!(
        e.contains("input 'image' has shape [1, 2, 48, 64]") && e.contains("C = 3"),
        "{e}"
    );
    // Rank 3 input.
    let rank3 = ModelBuilder::new("rank3")
        .input("image", FLOAT, &[F(3), F(48), F(64)])
        .node("Relu", &["image"], &["logits"], vec![])
        .output("logits", FLOAT, &[F(3), F(48), F(64)])
        .build();
    let e = load_err("rank3", &rank3);
    assert!(e.contains("input 'image' has shape [3, 48, 64]"), "{e}");
    // Symbolic dimensions are named.
    let e = load_err(
        "symbolic",
        &conv(
            2,
            6,
            [Dim::Param("N"), F(2), Dim::Param("H"), Dim::Param("W")],
            [Dim::Param("N"), F(6), Dim::Param("H"), Dim::Param("W")],
        ),
    );
    assert!(e.contains("[N, 2, H, W]"), "{e}");
    // float64 input.
    let f64_model = ModelBuilder::new("f64")
        .input("image", DOUBLE, &[F(1), F(3), F(8), F(8)])
        .node("Relu", &["image"], &["logits"], vec![])
        .output("logits", DOUBLE, &[F(1), F(3), F(8), F(8)])
        .build();
    let e = load_err("f64", &f64_model);
    assert!(e.contains("element type f64"), "{e}");
    // Two inputs.
    let two = ModelBuilder::new("two")
        .input("a", FLOAT, &[F(1), F(6), F(8), F(8)])
        .input("b", FLOAT, &[F(1), F(6), F(8), F(8)])
        .node("Add", &["a", "b"], &["logits"], vec![])
        .output("logits", FLOAT, &[F(1), F(6), F(8), F(8)])
        .build();
    let e = load_err("two_inputs", &two);
    assert!(
        e.contains("2 inputs ('a', 'b')") && e.contains("model contract"),
        "{e}"
    );

    // Truncated and garbage files.
    let good = color_model(None, 1).build();
    let e = load_err("truncated", &good[..good.len() / 2]);
    assert!(
        e.contains("cannot load the model") && e.contains("grasp_type_truncated.onnx"),
        "{e}"
    );
    let e = load_err("garbage", b"this is not an ONNX model at all \x00\xff\x13");
    assert!(
        e.contains("cannot load the model") && e.contains("grasp_type_garbage.onnx"),
        "{e}"
    );
    init();
    let missing = Path::new(env!("CARGO_TARGET_TMPDIR")).join("no_such_model.onnx");
    let e = GraspTypeModel::load(&missing, 1).unwrap_err();
    assert!(matches!(e, ModelError::Load { .. }), "{e:?}");
    assert!(
        e.to_string().contains("no_such_model.onnx: no such file"),
        "{e}"
    );
}

#[test]
fn a_missing_runtime_library_is_named() {
    let e =
        init_onnx_runtime(Some(Path::new("/nonexistent/libonnxruntime.so.1.31.1"))).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("/nonexistent/libonnxruntime.so.1.31.1")
            && msg.contains("fetch-onnxruntime.sh"),
        "{msg}"
    );
}

#[test]
fn maps_smaller_than_the_frame_map_coordinates() {
    // A square on even coordinates: each 2 × 2 block is uniform, so resizing to half size and a
    // stride-2 convolution both see pure colours.
    let sq = [16, 8, 32, 24];
    let f = frame(
        64,
        48,
        |u, v| if in_box(u, v, sq) { RED } else { GREY },
        |_, _| 1.0,
    );
    let roi = mask(64, 48, |u, v| in_box(u, v, sq));
    let fixed = load("color_fixed", color_model(Some((24, 32)), 1));
    assert_eq!(fixed.input_size(), (Some(24), Some(32)));
    let strided = load("color_stride2", color_model(None, 2));
    for model in [&fixed, &strided] {
        let maps = model.infer(&f).unwrap();
        assert_eq!((maps.width, maps.height), (32, 24));
        assert_eq!(maps.map_pixel(17, 9, 64, 48), (8, 4));
        assert_eq!(maps.map_pixel(16, 8, 64, 48), (8, 4));
        assert_eq!(maps.map_pixel(15, 7, 64, 48), (7, 3));
        assert_eq!(maps.map_pixel(63, 47, 64, 48), (31, 23));
        assert_eq!(maps.map_pixel(0, 100, 64, 48), (0, 23));
        let red = sigmoid(color_logit(3, RED));
        let grey = sigmoid(color_logit(3, GREY));
        let pinch = |u: usize, v: usize| {
            let (um, vm) = maps.map_pixel(u, v, 64, 48);
            maps.prob(GraspType::Pinch, um, vm) as f64
        };
        assert!((pinch(16, 8) - red).abs() < 1e-5);
        assert!((pinch(31, 23) - red).abs() < 1e-5);
        assert!((pinch(15, 8) - grey).abs() < 1e-5);
        assert!((pinch(32, 8) - grey).abs() < 1e-5);
        let p = type_probabilities(&maps, &roi, 64, 48);
        let want = expected_means(&f, &roi);
        for s in 0..6 {
            assert!(
                (p[s] - want[s]).abs() < 1e-5,
                "type {s}: {} vs {}",
                p[s],
                want[s]
            );
        }
        // The attention pixel is in frame coordinates: the square's centre (23.5, 15.5).
        let all = vec![true; 64 * 48];
        assert_near(
            attention_pixel(&maps, GraspType::Pinch, &all, 64, 48, 8.0),
            (23.5, 15.5),
            1.5,
        );
    }
}

#[test]
fn downsampled_maps_keep_area_means() {
    let maps = TypeMaps {
        width: 6,
        height: 4,
        probs: (0..6 * 24).map(|i| (i % 24) as f32 / 24.0).collect(),
    };
    assert_eq!(maps.downsample(6), maps);
    let d = maps.downsample(3);
    assert_eq!((d.width, d.height), (3, 2));
    // Each output pixel is the mean of a 2 × 2 block.
    let p = maps.plane(GraspType::Power);
    for v in 0..2 {
        for u in 0..3 {
            let want = (p[2 * v * 6 + 2 * u]
                + p[2 * v * 6 + 2 * u + 1]
                + p[(2 * v + 1) * 6 + 2 * u]
                + p[(2 * v + 1) * 6 + 2 * u + 1])
                / 4.0;
            assert!((d.prob(GraspType::Power, u, v) - want).abs() < 1e-6);
        }
    }
    // A non-integer ratio keeps the plane mean.
    let d = maps.downsample(4);
    assert_eq!((d.width, d.height), (4, 3));
    let mean = |x: &[f32]| x.iter().sum::<f32>() / x.len() as f32;
    assert!((mean(d.plane(GraspType::Tripod)) - mean(p)).abs() < 1e-5);
}

#[test]
fn the_model_serves_several_threads() {
    let model = load("color_threads", color_model(None, 1));
    let f = squares_frame();
    let reference = model.infer(&f).unwrap();
    std::thread::scope(|scope| {
        for _ in 0..3 {
            scope.spawn(|| {
                for _ in 0..3 {
                    assert_eq!(model.infer(&f).unwrap(), reference);
                }
            });
        }
    });
}
