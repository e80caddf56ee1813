//! Grasp-type detection (method.md §4, dissertation ch. 4.2.2): a fully convolutional network
//! gives six pixel-wise probability maps, one per grasp type (Eq 4.1–4.2); the object's type
//! probabilities are the maps' means over its region (Eq 4.3); the attention point is the
//! strongest mean-shift mode of the chosen type's map inside the region (its 3-D point is found
//! on the target's points by [`super::information`]).
//!
//! The network runs in ONNX Runtime through `ort`, loaded at run time
//! ([`crate::onnx_runtime::init_onnx_runtime`]: `ORT_DYLIB_PATH` or an explicit path;
//! `scripts/fetch-onnxruntime.sh` fetches the library).
//!
//! # Model contract (docs/model-contract.md)
//!
//! - **Input**: exactly one, float32, shape `[1, C, H, W]` (the batch may be dynamic) with
//!   C = 3 (R, G, B) or C = 4 (R, G, B, depth). H and W are fixed in the model or dynamic
//!   (`-1`): a fixed size makes graspd resize the frame (bilinear) to H × W, a dynamic one
//!   feeds the frame at its own size.
//! - **Normalisation**: colour channels are `(x / 255 − mean) / std` with the ImageNet mean
//!   (0.485, 0.456, 0.406) and std (0.229, 0.224, 0.225) unless the model's metadata
//!   (`custom_metadata_map`) has `graspd.mean` / `graspd.std`, each three comma-separated
//!   numbers. Depth is in metres, 0 where the sensor gave no reading, never normalised.
//! - **Output**: exactly one, float32, `[1, 6, H', W']` of *logits* in [`GraspType::ALL`] order.
//!   graspd applies the sigmoid itself (Eq 4.1–4.2: six independent binary problems, a pixel may
//!   afford several types, so no softmax across types). H', W' may be smaller than the input
//!   (strided networks); map pixels are spread evenly over the frame.
//!
//! Load-time checks ([`GraspTypeModel::load`]) name what was found against what the contract
//! needs, so that a wrongly exported model fails at start, not at the first request.

use super::rgbd::DecodedFrame;
use crate::grasp_type::GraspType;
use crate::onnx_runtime::{RuntimeError, fmt_dims, runtime_env, tensor_info};
use ort::session::Session;
use ort::value::{TensorElementType, TensorRef};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};
use thiserror::Error;

/// Number of grasp types, i.e. output channels of the model.
pub const NUM_TYPES: usize = GraspType::ALL.len();

/// ImageNet channel means (R, G, B), the default colour normalisation.
pub const IMAGENET_MEAN: [f32; 3] = [0.485, 0.456, 0.406];
/// ImageNet channel standard deviations (R, G, B).
pub const IMAGENET_STD: [f32; 3] = [0.229, 0.224, 0.225];

/// Metadata keys that override the colour normalisation.
pub const META_MEAN: &str = "graspd.mean";
pub const META_STD: &str = "graspd.std";

/// Errors of the grasp-type model (and of the runtime under it).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum ModelError {
    /// ONNX Runtime itself is missing or failed to load.
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
    #[error("cannot load the grasp-type model {}: {reason}", path.display())]
    Load { path: PathBuf, reason: String },
    #[error(
        "the grasp-type model {} does not follow the model contract (docs/model-contract.md): \
         {reason}",
        path.display()
    )]
    Contract { path: PathBuf, reason: String },
    #[error("grasp-type inference failed: {0}")]
    Inference(String),
}

/// The six sigmoid probability maps of one frame (Eq 4.1–4.2).
#[derive(Debug, Clone, PartialEq)]
pub struct TypeMaps {
    /// Size of the maps (the model's output; may be smaller than the frame).
    pub width: usize,
    pub height: usize,
    /// Six planes in [`GraspType::ALL`] order (type-major), each row-major `width × height`.
    pub probs: Vec<f32>,
}

impl TypeMaps {
    /// The map of type `s`, row-major.
    pub fn plane(&self, s: GraspType) -> &[f32] {
        let n = self.width * self.height;
        &self.probs[s.index() * n..(s.index() + 1) * n]
    }

    /// P(s) at map pixel (u_map, v_map).
    pub fn prob(&self, s: GraspType, u_map: usize, v_map: usize) -> f32 {
        self.plane(s)[v_map * self.width + u_map]
    }

    /// The map pixel covering frame pixel (u, v) of the `frame_w × frame_h` frame the maps were
    /// inferred from (pixels outside it are clamped to the border). Map pixels are spread evenly
    /// over the frame, a map half the frame's size giving one map pixel per 2 × 2 frame pixels,
    /// which is what both resizing and strided convolutions do.
    pub fn map_pixel(&self, u: usize, v: usize, frame_w: usize, frame_h: usize) -> (usize, usize) {
        (
            scale_index(u, frame_w, self.width),
            scale_index(v, frame_h, self.height),
        )
    }

    /// The maps reduced (area average) so that neither side exceeds `max_side` (at least 1),
    /// keeping the aspect ratio; unchanged when they already fit. For responses that return the
    /// maps: area averaging keeps each map's mean, so Eq 4.3 over the smaller maps stays close.
    pub fn downsample(&self, max_side: usize) -> TypeMaps {
        let max_side = max_side.max(1);
        let long = self.width.max(self.height);
        if long <= max_side {
            return self.clone();
        }
        let scale = max_side as f64 / long as f64;
        let nw = ((self.width as f64 * scale).round() as usize).clamp(1, max_side);
        let nh = ((self.height as f64 * scale).round() as usize).clamp(1, max_side);
        let (xw, yw) = (area_weights(self.width, nw), area_weights(self.height, nh));
        let mut probs = Vec::with_capacity(NUM_TYPES * nw * nh);
        let mut rows = vec![0.0f32; nw * self.height];
        for s in GraspType::ALL {
            let src = self.plane(s);
            for (y, row) in rows.chunks_mut(nw).enumerate() {
                let src_row = &src[y * self.width..(y + 1) * self.width];
                for (o, taps) in row.iter_mut().zip(&xw) {
                    *o = taps.iter().map(|&(i, w)| w * src_row[i]).sum();
                }
            }
            for taps in &yw {
                for x in 0..nw {
                    probs.push(taps.iter().map(|&(j, w)| w * rows[j * nw + x]).sum());
                }
            }
        }
        TypeMaps {
            width: nw,
            height: nh,
            probs,
        }
    }
}

/// Index of the destination cell (of `dst` over the same extent) covering source cell `i` of
/// `src`: centre-to-cell, so equal sizes give the identity.
fn scale_index(i: usize, src: usize, dst: usize) -> usize {
    (((i as f64 + 0.5) * dst as f64 / src.max(1) as f64) as usize).min(dst - 1)
}

/// Area-average taps from `src` cells to `dst` (≤ `src`) cells: (source index, weight) each,
/// the weights of one destination cell summing to 1.
fn area_weights(src: usize, dst: usize) -> Vec<Vec<(usize, f32)>> {
    let r = src as f64 / dst as f64;
    (0..dst)
        .map(|o| {
            let (a, b) = (o as f64 * r, (o + 1) as f64 * r);
            (a.floor() as usize..(b.ceil() as usize).min(src))
                .filter_map(|i| {
                    let overlap = b.min(i as f64 + 1.0) - a.max(i as f64);
                    (overlap > 1e-12).then_some((i, (overlap / r) as f32))
                })
                .collect()
        })
        .collect()
}

/// The loaded grasp-type network (method.md §4, ch. 4.2.2), checked against the model contract.
/// Usable from several threads: ort's `Session::run` needs `&mut`, so runs are serialised by a
/// mutex (ONNX Runtime parallelises inside a run with `intra_threads`).
#[derive(Debug)]
pub struct GraspTypeModel {
    path: PathBuf,
    session: Mutex<Session>,
    channels: usize,
    /// Fixed input height and width; `None` where the model takes any size.
    input_h: Option<usize>,
    input_w: Option<usize>,
    mean: [f32; 3],
    std: [f32; 3],
}

impl GraspTypeModel {
    /// Loads the ONNX model at `path` and checks it against the contract (module docs).
    /// `intra_threads`: ONNX Runtime threads per run (0: its default, one per core). Initialises
    /// ONNX Runtime from `$ORT_DYLIB_PATH` if [`crate::onnx_runtime::init_onnx_runtime`] has not been called.
    pub fn load(path: &Path, intra_threads: usize) -> Result<Self, ModelError> {
        let load_err = |reason: String| ModelError::Load {
            path: path.to_path_buf(),
            reason,
        };
        // ONNX Runtime's message for a missing file is an opaque system error.
        if !path.is_file() {
            return Err(load_err("no such file".into()));
        }
        let bytes = std::fs::read(path).map_err(|e| load_err(e.to_string()))?;
        Self::from_bytes(&bytes, &path.display().to_string(), intra_threads)
    }

    /// Loads a model held in memory (the copy of models/grasp_type/grasp_type.onnx built into
    /// graspd); `name` stands for its path in messages.
    pub fn from_bytes(bytes: &[u8], name: &str, intra_threads: usize) -> Result<Self, ModelError> {
        let path = Path::new(name);
        let env = runtime_env(None)?;
        let load_err = |reason: String| ModelError::Load {
            path: path.to_path_buf(),
            reason,
        };
        let mut builder = Session::builder(&env)
            .map_err(|e| load_err(e.to_string()))?
            .with_intra_threads(intra_threads)
            .map_err(|e| load_err(e.to_string()))?;
        let session = builder
            .commit_from_memory(bytes)
            .map_err(|e| load_err(e.to_string()))?;
        let contract_err = |reason: String| ModelError::Contract {
            path: path.to_path_buf(),
            reason,
        };
        let (channels, input_h, input_w) = check_contract(&session).map_err(contract_err)?;
        let (mean, std) = normalisation(&session).map_err(contract_err)?;
        Ok(Self {
            path: path.to_path_buf(),
            session: Mutex::new(session),
            channels,
            input_h,
            input_w,
            mean,
            std,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Input channels: 3 (RGB) or 4 (RGB + depth).
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Whether the model reads the depth channel.
    pub fn uses_depth(&self) -> bool {
        self.channels == 4
    }

    /// Fixed input (height, width); `None` for a dynamic side (the frame's size is used).
    pub fn input_size(&self) -> (Option<usize>, Option<usize>) {
        (self.input_h, self.input_w)
    }

    /// Colour normalisation (mean, std) per R, G, B.
    pub fn normalisation(&self) -> ([f32; 3], [f32; 3]) {
        (self.mean, self.std)
    }

    /// Runs the network on `frame` and returns the six probability maps (sigmoid of the logits,
    /// Eq 4.1–4.2; multi-label, so per type, not a softmax across types).
    pub fn infer(&self, frame: &DecodedFrame) -> Result<TypeMaps, ModelError> {
        let n = frame.width * frame.height;
        if n == 0 || frame.rgb.len() != 3 * n || frame.depth.len() != n {
            return Err(ModelError::Inference(format!(
                "the frame is {}×{} with {} colour bytes and {} depths; it needs a non-empty \
                 image with 3 bytes and 1 depth per pixel",
                frame.width,
                frame.height,
                frame.rgb.len(),
                frame.depth.len()
            )));
        }
        let (w, h) = (
            self.input_w.unwrap_or(frame.width),
            self.input_h.unwrap_or(frame.height),
        );
        let input = self.input_tensor(frame, w, h);
        let fail = |e: ort::Error| ModelError::Inference(e.to_string());
        let view = ndarray::ArrayView4::from_shape((1, self.channels, h, w), &input)
            .map_err(|e| ModelError::Inference(e.to_string()))?;
        let tensor = TensorRef::from_array_view(view).map_err(fail)?;
        let mut session = self.session.lock().unwrap_or_else(PoisonError::into_inner);
        let outputs = session.run(ort::inputs![tensor]).map_err(fail)?;
        let (shape, logits) = outputs[0].try_extract_tensor::<f32>().map_err(fail)?;
        let ok = shape.len() == 4
            && shape[0] == 1
            && shape[1] == NUM_TYPES as i64
            && shape[2] > 0
            && shape[3] > 0;
        if !ok {
            return Err(ModelError::Inference(format!(
                "the output has shape {}; the grasp-type contract needs [1, 6, H, W]",
                fmt_dims(shape, &[])
            )));
        }
        Ok(TypeMaps {
            width: shape[3] as usize,
            height: shape[2] as usize,
            probs: logits.iter().map(|&x| sigmoid(x)).collect(),
        })
    }

    /// The `[1, C, h, w]` input: [`resized_planes`] with the colour normalised.
    fn input_tensor(&self, frame: &DecodedFrame, w: usize, h: usize) -> Vec<f32> {
        let mut data = resized_planes(frame, w, h, self.channels == 4);
        let n = w * h;
        // (x/255 − mean)/std as one multiply-add per value.
        for (k, plane) in data[..3 * n].chunks_exact_mut(n).enumerate() {
            let gain = 1.0 / (255.0 * self.std[k]);
            let bias = -self.mean[k] / self.std[k];
            for x in plane {
                *x = *x * gain + bias;
            }
        }
        data
    }
}

/// The frame as the network sees it before colour normalisation: planes R, G, B (0…255) and,
/// with `depth`, metres (0 where invalid), resized to `w` × `h` by bilinear interpolation
/// where the size differs (model contract). Public so that training data is made by exactly
/// this code (models/grasp_type).
pub fn resized_planes(frame: &DecodedFrame, w: usize, h: usize, depth: bool) -> Vec<f32> {
    let n = w * h;
    let channels = if depth { 4 } else { 3 };
    let mut data = vec![0.0f32; channels * n];
    let (fw, fh) = (frame.width, frame.height);
    if (w, h) == (fw, fh) {
        for (i, px) in frame.rgb.chunks_exact(3).enumerate() {
            for k in 0..3 {
                data[k * n + i] = px[k] as f32;
            }
        }
        if depth {
            data[3 * n..].copy_from_slice(&frame.depth);
        }
        return data;
    }
    let (xt, yt) = (bilinear_taps(fw, w), bilinear_taps(fh, h));
    for (y, &(y0, y1, b)) in yt.iter().enumerate() {
        for (x, &(x0, x1, a)) in xt.iter().enumerate() {
            let i = y * w + x;
            let corners = [
                (y0 * fw + x0, (1.0 - a) * (1.0 - b)),
                (y0 * fw + x1, a * (1.0 - b)),
                (y1 * fw + x0, (1.0 - a) * b),
                (y1 * fw + x1, a * b),
            ];
            for k in 0..3 {
                data[k * n + i] = corners
                    .iter()
                    .map(|&(j, wt)| wt * frame.rgb[3 * j + k] as f32)
                    .sum();
            }
            if depth {
                // Only valid readings are interpolated: mixing in the 0 of a missing one
                // would invent depths between the object and nothing.
                let (mut sum, mut wsum) = (0.0f32, 0.0f32);
                for &(j, wt) in &corners {
                    let d = frame.depth[j];
                    if d > 0.0 && wt > 0.0 {
                        sum += wt * d;
                        wsum += wt;
                    }
                }
                data[3 * n + i] = if wsum > 0.0 { sum / wsum } else { 0.0 };
            }
        }
    }
    data
}

fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + (-x).exp())
}

/// Bilinear taps (i0, i1, fraction of i1) from `src` samples to `dst`, pixel centres aligned
/// (OpenCV's INTER_LINEAR, PyTorch's `align_corners=False`), clamped at the borders: what
/// [`resized_planes`] reads.
pub fn bilinear_taps(src: usize, dst: usize) -> Vec<(usize, usize, f32)> {
    let r = src as f64 / dst as f64;
    (0..dst)
        .map(|o| {
            let s = ((o as f64 + 0.5) * r - 0.5).clamp(0.0, (src - 1) as f64);
            let i0 = s.floor() as usize;
            (i0, (i0 + 1).min(src - 1), (s - i0 as f64) as f32)
        })
        .collect()
}

/// Checks the session's inputs and outputs against the contract; returns (C, H, W), H and W
/// `None` when dynamic.
fn check_contract(session: &Session) -> Result<(usize, Option<usize>, Option<usize>), String> {
    let names = |v: &[ort::value::Outlet]| {
        v.iter()
            .map(|o| format!("'{}'", o.name()))
            .collect::<Vec<_>>()
    };
    if session.inputs().len() != 1 {
        return Err(format!(
            "the model has {} inputs ({}); the contract needs exactly one, [1, C, H, W] float32",
            session.inputs().len(),
            names(session.inputs()).join(", ")
        ));
    }
    if session.outputs().len() != 1 {
        return Err(format!(
            "the model has {} outputs ({}); the contract needs exactly one, [1, 6, H, W] float32 \
             logits",
            session.outputs().len(),
            names(session.outputs()).join(", ")
        ));
    }
    let input = &session.inputs()[0];
    let (ty, dims, syms) = tensor_info(input.dtype()).ok_or_else(|| {
        format!(
            "input '{}' is {}, not a tensor",
            input.name(),
            input.dtype()
        )
    })?;
    let shape = fmt_dims(dims, syms);
    if ty != TensorElementType::Float32 {
        return Err(format!(
            "input '{}' has element type {ty}; the contract needs f32",
            input.name()
        ));
    }
    let channels_ok = dims.len() == 4 && (dims[1] == 3 || dims[1] == 4);
    if !channels_ok || !(dims[0] == 1 || dims[0] < 0) {
        return Err(format!(
            "input '{}' has shape {shape}; the contract needs [1, C, H, W] with C = 3 (RGB) or \
             4 (RGB + depth)",
            input.name()
        ));
    }
    let side = |d: i64| (d > 0).then_some(d as usize);
    let output = &session.outputs()[0];
    let (ty, odims, osyms) = tensor_info(output.dtype()).ok_or_else(|| {
        format!(
            "output '{}' is {}, not a tensor",
            output.name(),
            output.dtype()
        )
    })?;
    let oshape = fmt_dims(odims, osyms);
    if ty != TensorElementType::Float32 {
        return Err(format!(
            "output '{}' has element type {ty}; the contract needs f32 logits",
            output.name()
        ));
    }
    // A dynamic channel dimension is accepted here and checked on every run.
    let out_ok = odims.len() == 4
        && (odims[0] == 1 || odims[0] < 0)
        && (odims[1] == NUM_TYPES as i64 || odims[1] < 0);
    if !out_ok {
        return Err(format!(
            "output '{}' has shape {oshape}; the grasp-type contract needs [1, 6, H, W] \
             (one logit map per grasp type, in the order large_wrap, small_wrap, power, pinch, \
             precision, tripod)",
            output.name()
        ));
    }
    Ok((dims[1] as usize, side(dims[2]), side(dims[3])))
}

/// The colour normalisation: ImageNet's unless the metadata overrides it.
type Normalisation = ([f32; 3], [f32; 3]);

fn normalisation(session: &Session) -> Result<Normalisation, String> {
    let meta = session
        .metadata()
        .map_err(|e| format!("cannot read the model metadata: {e}"))?;
    let read = |key: &str, default: [f32; 3], positive: bool| -> Result<[f32; 3], String> {
        let Some(text) = meta.custom(key) else {
            return Ok(default);
        };
        let values: Vec<f32> = text
            .split(',')
            .map(|s| s.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("metadata {key} = {text:?} is not a comma-separated list"))?;
        let ok = values.len() == 3
            && values
                .iter()
                .all(|v| v.is_finite() && (!positive || *v > 0.0));
        if !ok {
            return Err(format!(
                "metadata {key} = {text:?}; it needs three finite numbers (R, G, B){}",
                if positive { ", each > 0" } else { "" }
            ));
        }
        Ok([values[0], values[1], values[2]])
    };
    Ok((
        read(META_MEAN, IMAGENET_MEAN, false)?,
        read(META_STD, IMAGENET_STD, true)?,
    ))
}

/// Eq 4.3: P(s|O), the mean of map s over the region O, for each type in [`GraspType::ALL`]
/// order. `roi` is a `frame_w × frame_h` row-major mask (the frame the maps come from); each
/// ROI pixel counts with the map pixel covering it ([`TypeMaps::map_pixel`]), so smaller maps
/// weigh their pixels by the ROI's share. All 0 for an empty ROI.
pub fn type_probabilities(
    maps: &TypeMaps,
    roi: &[bool],
    frame_w: usize,
    frame_h: usize,
) -> [f64; 6] {
    assert_eq!(roi.len(), frame_w * frame_h, "ROI mask size");
    let cols: Vec<usize> = (0..frame_w)
        .map(|u| scale_index(u, frame_w, maps.width))
        .collect();
    let n = maps.width * maps.height;
    let mut sums = [0.0f64; 6];
    let mut count = 0usize;
    for v in 0..frame_h {
        let row = scale_index(v, frame_h, maps.height) * maps.width;
        for (u, _) in roi[v * frame_w..(v + 1) * frame_w]
            .iter()
            .enumerate()
            .filter(|(_, in_roi)| **in_roi)
        {
            let j = row + cols[u];
            for (s, sum) in sums.iter_mut().enumerate() {
                *sum += maps.probs[s * n + j] as f64;
            }
            count += 1;
        }
    }
    if count > 0 {
        sums.iter_mut().for_each(|s| *s /= count as f64);
    }
    sums
}

/// s* = argmax of P(s|O) over the types the hand can realise (method.md §4); ties go to the
/// lower index, NaN never wins. `None` when `realisable` is empty.
pub fn choose_type(p: &[f64; 6], realisable: &[GraspType]) -> Option<GraspType> {
    let mut best: Option<(GraspType, f64)> = None;
    for s in GraspType::ALL
        .into_iter()
        .filter(|s| realisable.contains(s))
    {
        let q = p[s.index()];
        match best {
            Some((_, b)) if !(q > b || (b.is_nan() && !q.is_nan())) => {}
            _ => best = Some((s, q)),
        }
    }
    best.map(|(s, _)| s)
}

/// Seeds per side of the grid over the ROI (at most 8 × 8 = 64 mean-shift runs).
const SEED_GRID: usize = 8;
/// Mean-shift stops when a step is shorter than this (pixels) or after `MAX_ITERATIONS`.
const CONVERGED_PX: f64 = 0.01;
const MAX_ITERATIONS: usize = 100;

/// The attention point p_att (method.md §4): mean-shift over the ROI pixels weighted by map
/// `s_star`, in FRAME pixel coordinates.
///
/// - Kernel: Gaussian with σ = `bandwidth_px`, truncated at 3σ. Gaussian rather than flat so
///   that a seed on a plateau of saturated probabilities still moves towards the plateau's
///   centre instead of stopping wherever its window is full. The bandwidth should be about the
///   size of the graspable part: a plateau much wider than 3σ has many modes.
/// - Seeds: the ROI's bounding box is cut into at most 8 × 8 cells; each seeds at its most
///   probable ROI pixel (first in scan order on ties), so a small strong blob is never missed.
/// - Speed: pixel weights are binned into cells of max(1, ⌊σ/4⌋) pixels that keep their exact
///   weighted centroids; the kernel is evaluated at cell centres.
/// - Modes closer than σ/2 are merged (their mean is the cluster centre); the centre with the
///   highest P(s*) (map pixel under it) wins, ties to the cluster with more seeds, then the
///   first found. Deterministic.
///
/// `None` when the ROI is empty or has no positive weight.
pub fn attention_pixel(
    maps: &TypeMaps,
    s_star: GraspType,
    roi: &[bool],
    frame_w: usize,
    frame_h: usize,
    bandwidth_px: f64,
) -> Option<(f64, f64)> {
    assert_eq!(roi.len(), frame_w * frame_h, "ROI mask size");
    let sigma = if bandwidth_px.is_finite() && bandwidth_px > 0.0 {
        bandwidth_px
    } else {
        1.0
    };
    let plane = maps.plane(s_star);
    let cols: Vec<usize> = (0..frame_w)
        .map(|u| scale_index(u, frame_w, maps.width))
        .collect();
    let weight = |u: usize, v: usize| -> f64 {
        let w = plane[scale_index(v, frame_h, maps.height) * maps.width + cols[u]] as f64;
        if w.is_finite() { w.max(0.0) } else { 0.0 }
    };

    // ROI bounding box.
    let (mut u_lo, mut u_hi, mut v_lo, mut v_hi) = (usize::MAX, 0, usize::MAX, 0);
    for (i, _) in roi.iter().enumerate().filter(|(_, r)| **r) {
        let (u, v) = (i % frame_w, i / frame_w);
        (u_lo, u_hi, v_lo, v_hi) = (u_lo.min(u), u_hi.max(u), v_lo.min(v), v_hi.max(v));
    }
    if u_lo > u_hi {
        return None;
    }
    let (bw, bh) = (u_hi - u_lo + 1, v_hi - v_lo + 1);

    // Binned moments (Σw, Σw·u, Σw·v) and the seed grid's argmax pixels in one pass.
    let f = ((sigma / 4.0).floor() as usize).max(1);
    let (cw, ch) = (bw.div_ceil(f), bh.div_ceil(f));
    let mut m0 = vec![0.0f64; cw * ch];
    let mut mu = vec![0.0f64; cw * ch];
    let mut mv = vec![0.0f64; cw * ch];
    let (gx, gy) = (SEED_GRID.min(bw), SEED_GRID.min(bh));
    let mut seeds: Vec<Option<(f64, usize, usize)>> = vec![None; gx * gy];
    for v in v_lo..=v_hi {
        for u in u_lo..=u_hi {
            if !roi[v * frame_w + u] {
                continue;
            }
            let w = weight(u, v);
            if w <= 0.0 {
                continue;
            }
            let c = ((v - v_lo) / f) * cw + (u - u_lo) / f;
            m0[c] += w;
            mu[c] += w * u as f64;
            mv[c] += w * v as f64;
            let g = ((v - v_lo) * gy / bh) * gx + (u - u_lo) * gx / bw;
            if seeds[g].is_none_or(|(best, _, _)| w > best) {
                seeds[g] = Some((w, u, v));
            }
        }
    }

    let reach = 3.0 * sigma;
    let inv_2s2 = 1.0 / (2.0 * sigma * sigma);
    // Cell centre in frame pixels (cell i spans pixels lo + i·f … lo + i·f + f − 1).
    let centre = |lo: usize, i: usize| lo as f64 + (i * f) as f64 + (f as f64 - 1.0) / 2.0;
    let cell_range = |c: f64, lo: usize, n: usize| -> (usize, usize) {
        let a = ((c - reach - lo as f64) / f as f64).floor().max(0.0) as usize;
        let b = (((c + reach - lo as f64) / f as f64).ceil().max(0.0) as usize).min(n - 1);
        (a.min(n - 1), b)
    };
    let mut kx = Vec::new();
    let mut ky = Vec::new();
    let mut shift = |mut x: f64, mut y: f64| -> Option<(f64, f64)> {
        for _ in 0..MAX_ITERATIONS {
            let (i0, i1) = cell_range(x, u_lo, cw);
            let (j0, j1) = cell_range(y, v_lo, ch);
            kx.clear();
            kx.extend((i0..=i1).map(|i| (-(centre(u_lo, i) - x).powi(2) * inv_2s2).exp()));
            ky.clear();
            ky.extend((j0..=j1).map(|j| (-(centre(v_lo, j) - y).powi(2) * inv_2s2).exp()));
            let (mut s0, mut su, mut sv) = (0.0, 0.0, 0.0);
            for (j, kyj) in (j0..=j1).zip(&ky) {
                for (i, kxi) in (i0..=i1).zip(&kx) {
                    let c = j * cw + i;
                    let k = kxi * kyj;
                    s0 += k * m0[c];
                    su += k * mu[c];
                    sv += k * mv[c];
                }
            }
            if s0 <= 1e-300 {
                return None;
            }
            let (nx, ny) = (su / s0, sv / s0);
            let step = (nx - x).hypot(ny - y);
            (x, y) = (nx, ny);
            if step < CONVERGED_PX {
                break;
            }
        }
        Some((x, y))
    };

    // Clusters: (sum of modes u, sum of modes v, members).
    let mut clusters: Vec<(f64, f64, usize)> = Vec::new();
    for (_, u, v) in seeds.into_iter().flatten() {
        let Some((x, y)) = shift(u as f64, v as f64) else {
            continue;
        };
        let near = clusters.iter_mut().find(|(sx, sy, n)| {
            let k = *n as f64;
            (sx / k - x).hypot(sy / k - y) < sigma / 2.0
        });
        match near {
            Some((sx, sy, n)) => {
                *sx += x;
                *sy += y;
                *n += 1;
            }
            None => clusters.push((x, y, 1)),
        }
    }
    let mut best: Option<(f32, usize, f64, f64)> = None;
    for (sx, sy, n) in clusters {
        let (x, y) = (sx / n as f64, sy / n as f64);
        let u = (x.round().max(0.0) as usize).min(frame_w - 1);
        let v = (y.round().max(0.0) as usize).min(frame_h - 1);
        let (um, vm) = maps.map_pixel(u, v, frame_w, frame_h);
        let p = maps.prob(s_star, um, vm);
        let better = match best {
            None => true,
            Some((bp, bn, _, _)) => p > bp || (p == bp && n > bn),
        };
        if better {
            best = Some((p, n, x, y));
        }
    }
    best.map(|(_, _, x, y)| (x, y))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn maps_with(width: usize, height: usize, f: impl Fn(usize, usize, usize) -> f32) -> TypeMaps {
        let mut probs = Vec::with_capacity(NUM_TYPES * width * height);
        for s in 0..NUM_TYPES {
            for v in 0..height {
                for u in 0..width {
                    probs.push(f(s, u, v));
                }
            }
        }
        TypeMaps {
            width,
            height,
            probs,
        }
    }

    #[test]
    fn resampling_taps() {
        // Same size: the identity.
        for (o, &(i0, _, a)) in bilinear_taps(5, 5).iter().enumerate() {
            assert_eq!((i0, a), (o, 0.0));
        }
        // Half size: the mean of each pair.
        assert_eq!(bilinear_taps(4, 2), vec![(0, 1, 0.5), (2, 3, 0.5)]);
        // Up-sampling clamps at the borders.
        assert_eq!(bilinear_taps(2, 4)[0], (0, 1, 0.0));
        assert_eq!(bilinear_taps(2, 4)[3], (1, 1, 0.0));
        for (src, dst) in [(10, 3), (7, 7), (640, 81)] {
            for taps in area_weights(src, dst) {
                let sum: f32 = taps.iter().map(|t| t.1).sum();
                assert!((sum - 1.0).abs() < 1e-5);
            }
        }
        assert_eq!(scale_index(5, 64, 32), 2);
        assert_eq!(scale_index(63, 64, 32), 31);
        assert_eq!(scale_index(7, 10, 10), 7);
    }

    #[test]
    fn shapes_are_formatted_with_their_symbols() {
        assert_eq!(fmt_dims(&[1, 5, 60, 80], &[]), "[1, 5, 60, 80]");
        let syms = ["N".to_string(), String::new(), "H".into(), String::new()];
        assert_eq!(fmt_dims(&[-1, 3, -1, -1], &syms), "[N, 3, H, ?]");
        assert_eq!(sigmoid(0.0), 0.5);
        assert_eq!(sigmoid(-200.0), 0.0);
        assert_eq!(sigmoid(200.0), 1.0);
    }

    #[test]
    fn eq_4_3_weighs_small_maps_by_roi_share() {
        // 2 × 1 maps over a 4 × 2 frame: the left map pixel covers frame columns 0–1.
        let maps = maps_with(2, 1, |s, u, _| if u == 0 { s as f32 / 10.0 } else { 1.0 });
        // Three ROI pixels on the left, one on the right.
        let roi = [true, true, false, false, true, false, true, false];
        let p = type_probabilities(&maps, &roi, 4, 2);
        for (s, p) in p.iter().enumerate() {
            let want = (3.0 * (s as f32 / 10.0) as f64 + 1.0) / 4.0;
            assert!((p - want).abs() < 1e-12, "{s}: {p} vs {want}");
        }
    }

    #[test]
    fn attention_finds_the_peak_of_a_gaussian_bump() {
        let (w, h) = (120, 90);
        let bump = |u: usize, v: usize, c: (f64, f64), a: f64, r: f64| {
            a * (-((u as f64 - c.0).powi(2) + (v as f64 - c.1).powi(2)) / (2.0 * r * r)).exp()
        };
        let maps = maps_with(w, h, |s, u, v| {
            if s == GraspType::Tripod.index() {
                (bump(u, v, (33.3, 60.7), 0.9, 6.0) + bump(u, v, (90.0, 20.0), 0.6, 10.0)) as f32
            } else {
                0.0
            }
        });
        let roi = vec![true; w * h];
        for bw in [3.0, 8.0, 15.0] {
            let (x, y) = attention_pixel(&maps, GraspType::Tripod, &roi, w, h, bw).unwrap();
            assert!(
                (x - 33.3).hypot(y - 60.7) < 1.0,
                "bandwidth {bw}: ({x}, {y})"
            );
        }
        // All-zero map in the ROI: no attention.
        assert_eq!(
            attention_pixel(&maps, GraspType::Pinch, &roi, w, h, 8.0),
            None
        );
    }
}
