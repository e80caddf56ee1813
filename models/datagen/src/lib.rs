//! Generated RGB-D tabletop scenes for training graspd's networks: [`scene`] draws and
//! ray-casts them. For the grasp-type network (models/grasp_type/MODEL_CARD.md), [`labels`] is
//! the label rule set (LABELS.md) and [`sample`] turns scene i of a seed into the network's
//! input exactly as graspd preprocesses a frame; for the recogniser
//! (models/recogniser/MODEL_CARD.md), [`recognition`] segments and crops cluttered scenes as
//! graspd does and labels each segment.

pub mod labels;
pub mod recognition;
pub mod scene;

use graspd_core::perception::{DecodedFrame, bilinear_taps, resized_planes};
pub use graspd_testkit::npy::npy_header;
pub use scene::{Frame, Scene};

/// Source rows (or columns) that a bilinear resize from `src` to `dst` reads, and the one the
/// nearest-pixel label comes from (the taps of graspd's resize, model contract).
pub fn needed(src: usize, dst: usize) -> Vec<bool> {
    let mut need = vec![src == dst; src];
    let r = src as f64 / dst as f64;
    for (o, (i0, i1, _)) in bilinear_taps(src, dst).into_iter().enumerate() {
        need[i0] = true;
        need[i1] = true;
        need[label_source(o, r, src)] = true;
    }
    need
}

/// The source pixel whose label a model pixel takes (its centre's pixel).
pub fn label_source(o: usize, r: f64, src: usize) -> usize {
    (((o as f64 + 0.5) * r) as usize).min(src - 1)
}

/// One scene as the network sees it.
pub struct Sample {
    /// [4, h, w]: R, G, B (0…255) and depth (m), as `resized_planes` makes them.
    pub x: Vec<f32>,
    /// [h, w] label bytes.
    pub y: Vec<u8>,
    /// The full frame, when asked for.
    pub full: Option<Frame>,
    /// The full frame as graspd decodes it (only the pixels the resize reads are rendered
    /// unless `full`).
    pub decoded: DecodedFrame,
}

/// Scene `i` of the data set with `seed` (drawn from seed `seed · 1 000 003 + i`), at model input
/// size `width` × `height`; `full` renders every pixel and keeps the frame.
pub fn sample(
    seed: u64,
    i: usize,
    width: usize,
    height: usize,
    full: bool,
) -> Result<Sample, String> {
    let scene = Scene::random(seed.wrapping_mul(1_000_003).wrapping_add(i as u64))
        .map_err(|e| e.to_string())?;
    let k = scene.camera.intrinsics;
    let (rows, cols) = if full {
        (vec![true; k.height], vec![true; k.width])
    } else {
        (needed(k.height, height), needed(k.width, width))
    };
    let frame = scene.render(&rows, &cols);
    let decoded = frame.decoded(&k);
    let x = resized_planes(&decoded, width, height, true);
    let (rx, ry) = (
        frame.width as f64 / width as f64,
        frame.height as f64 / height as f64,
    );
    let mut y = Vec::with_capacity(width * height);
    for v in 0..height {
        let sv = label_source(v, ry, frame.height);
        for u in 0..width {
            y.push(frame.labels[sv * frame.width + label_source(u, rx, frame.width)]);
        }
    }
    Ok(Sample {
        x,
        y,
        full: full.then_some(frame),
        decoded,
    })
}
