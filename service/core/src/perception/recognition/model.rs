//! The recogniser network loaded and checked against its contract (docs/model-contract.md,
//! "The recogniser"): two inputs, `crop` `[N, 5, 64, 64]` and `size` `[N, 3]` float32
//! ([`super::crop`]), one output, `[N, K]` logits over the classes that the metadata
//! `graspd.classes` names (comma-separated, one of them `unknown`); graspd applies the softmax.

use super::crop::{CROP_CHANNELS, CROP_SIDE, ObjectCrop, SIZE_FEATURES};
use crate::onnx_runtime::{check_float_inputs, fmt_dims, softmax, tensor_info};
use crate::perception::grasp_type::{ModelError, checked_session, read_model_file};
use ort::session::Session;
use ort::value::{TensorElementType, TensorRef};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

/// The metadata key listing the classes in output order.
pub const META_CLASSES: &str = "graspd.classes";
/// The class of an object that is none of the known ones.
pub const UNKNOWN: &str = "unknown";

/// The loaded recogniser. Runs are serialised by a mutex, as for the grasp-type model.
#[derive(Debug)]
pub struct RecognitionModel {
    path: PathBuf,
    session: Mutex<Session>,
    classes: Vec<String>,
}

impl RecognitionModel {
    /// Loads the ONNX model at `path` and checks it against the contract.
    pub fn load(path: &Path, intra_threads: usize) -> Result<Self, ModelError> {
        let bytes = read_model_file(path)?;
        Self::from_bytes(&bytes, &path.display().to_string(), intra_threads)
    }

    /// Loads a model held in memory (the copy of models/recogniser/recogniser.onnx built into
    /// graspd); `name` stands for its path in messages.
    pub fn from_bytes(bytes: &[u8], name: &str, intra_threads: usize) -> Result<Self, ModelError> {
        let (path, session, classes) = checked_session(bytes, name, intra_threads, check_contract)?;
        Ok(Self {
            path,
            session: Mutex::new(session),
            classes,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The classes, in output order.
    pub fn classes(&self) -> &[String] {
        &self.classes
    }

    /// P(class | object) for each crop (softmax of the logits), one run for all of them.
    pub fn classify(&self, crops: &[ObjectCrop]) -> Result<Vec<Vec<f64>>, ModelError> {
        if crops.is_empty() {
            return Ok(Vec::new());
        }
        let n = crops.len();
        let planes: Vec<f32> = crops
            .iter()
            .flat_map(|c| c.planes.iter().copied())
            .collect();
        let sizes: Vec<f32> = crops.iter().flat_map(|c| c.size).collect();
        let fail = |e: ort::Error| ModelError::Inference(e.to_string());
        let shape_err = |e: ndarray::ShapeError| ModelError::Inference(e.to_string());
        let crop =
            ndarray::ArrayView4::from_shape((n, CROP_CHANNELS, CROP_SIDE, CROP_SIDE), &planes)
                .map_err(shape_err)?;
        let size =
            ndarray::ArrayView2::from_shape((n, SIZE_FEATURES), &sizes).map_err(shape_err)?;
        let crop = TensorRef::from_array_view(crop).map_err(fail)?;
        let size = TensorRef::from_array_view(size).map_err(fail)?;
        let mut session = self.session.lock().unwrap_or_else(PoisonError::into_inner);
        let outputs = session
            .run(ort::inputs!["crop" => crop, "size" => size])
            .map_err(fail)?;
        let (shape, logits) = outputs[0].try_extract_tensor::<f32>().map_err(fail)?;
        let k = self.classes.len();
        if shape.len() != 2 || shape[0] != n as i64 || shape[1] != k as i64 {
            return Err(ModelError::Inference(format!(
                "the output has shape {}; the recogniser contract needs [{n}, {k}]",
                fmt_dims(shape, &[])
            )));
        }
        Ok(logits.chunks_exact(k).map(softmax).collect())
    }
}

/// Checks the inputs, the output and the metadata; returns the classes.
fn check_contract(session: &Session) -> Result<Vec<String>, String> {
    check_float_inputs(
        session,
        &[
            (
                "crop",
                &[CROP_CHANNELS as i64, CROP_SIDE as i64, CROP_SIDE as i64],
            ),
            ("size", &[SIZE_FEATURES as i64]),
        ],
    )?;
    if session.outputs().len() != 1 {
        return Err(format!(
            "the model has {} outputs; the contract needs one, [N, K] float32 logits",
            session.outputs().len()
        ));
    }
    let meta = session
        .metadata()
        .map_err(|e| format!("cannot read the model metadata: {e}"))?;
    let text = meta
        .custom(META_CLASSES)
        .ok_or_else(|| format!("the metadata has no {META_CLASSES} (the class names)"))?;
    let classes: Vec<String> = text.split(',').map(|s| s.trim().to_string()).collect();
    if classes.iter().any(String::is_empty) || !classes.iter().any(|c| c == UNKNOWN) {
        return Err(format!(
            "metadata {META_CLASSES} = {text:?}; it needs non-empty comma-separated names, one \
             of them '{UNKNOWN}'"
        ));
    }
    let output = &session.outputs()[0];
    let (ty, d, syms) =
        tensor_info(output.dtype()).ok_or_else(|| "the output is not a tensor".to_string())?;
    if ty != TensorElementType::Float32
        || d.len() != 2
        || (d[1] >= 0 && d[1] != classes.len() as i64)
    {
        return Err(format!(
            "output is {ty} {}; the contract needs float32 [N, {}] (one logit per class of \
             {META_CLASSES})",
            fmt_dims(d, syms),
            classes.len()
        ));
    }
    Ok(classes)
}
