//! The grasp-type network loaded and checked against the model contract (module docs of
//! [`super`]), and the frame as it sees it (resize, normalisation).

use super::maps::{NUM_TYPES, TypeMaps};
use crate::onnx_runtime::{RuntimeError, SessionError, fmt_dims, session_from_memory, tensor_info};
use crate::perception::rgbd::DecodedFrame;
use ort::session::Session;
use ort::value::{TensorElementType, TensorRef};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};
use thiserror::Error;

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
    #[error("cannot load the model {}: {reason}", path.display())]
    Load { path: PathBuf, reason: String },
    #[error(
        "the model {} does not follow the model contract (docs/model-contract.md): \
         {reason}",
        path.display()
    )]
    Contract { path: PathBuf, reason: String },
    #[error("model inference failed: {0}")]
    Inference(String),
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
        let bytes = read_model_file(path)?;
        Self::from_bytes(&bytes, &path.display().to_string(), intra_threads)
    }

    /// Loads a model held in memory (the copy of models/grasp_type/grasp_type.onnx built into
    /// graspd); `name` stands for its path in messages.
    pub fn from_bytes(bytes: &[u8], name: &str, intra_threads: usize) -> Result<Self, ModelError> {
        let path = Path::new(name);
        let session = session_from_memory(bytes, intra_threads).map_err(|e| match e {
            SessionError::Runtime(e) => ModelError::Runtime(e),
            SessionError::Load(reason) => ModelError::Load {
                path: path.to_path_buf(),
                reason,
            },
        })?;
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

/// The bytes of a model file; a missing file is named as such (ONNX Runtime's message for it is
/// an opaque system error).
pub(crate) fn read_model_file(path: &Path) -> Result<Vec<u8>, ModelError> {
    let load_err = |reason: String| ModelError::Load {
        path: path.to_path_buf(),
        reason,
    };
    if !path.is_file() {
        return Err(load_err("no such file".into()));
    }
    std::fs::read(path).map_err(|e| load_err(e.to_string()))
}

/// A session of the model held in `bytes` (`name` stands for its path in messages) that
/// `check` finds under its contract, with what `check` returns.
pub(crate) fn checked_session<T>(
    bytes: &[u8],
    name: &str,
    intra_threads: usize,
    check: impl FnOnce(&Session) -> Result<T, String>,
) -> Result<(PathBuf, Session, T), ModelError> {
    let path = PathBuf::from(name);
    let session = session_from_memory(bytes, intra_threads).map_err(|e| match e {
        SessionError::Runtime(e) => ModelError::Runtime(e),
        SessionError::Load(reason) => ModelError::Load {
            path: path.clone(),
            reason,
        },
    })?;
    let checked = check(&session).map_err(|reason| ModelError::Contract {
        path: path.clone(),
        reason,
    })?;
    Ok((path, session, checked))
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

pub(super) fn sigmoid(x: f32) -> f32 {
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
