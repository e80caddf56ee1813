//! The recogniser network loaded and checked against its contract (docs/model-contract.md,
//! "The recogniser"): two inputs, `crop` `[N, 5, 64, 64]` and `size` `[N, 3]` float32
//! ([`super::crop`]), one output, `[N, K]` logits over the classes that the metadata
//! `graspd.classes` names (comma-separated, one of them `unknown`); graspd applies the softmax.

use super::crop::{CROP_CHANNELS, CROP_SIDE, ObjectCrop, SIZE_FEATURES};
use crate::onnx_runtime::{SessionError, fmt_dims, session_from_memory, tensor_info};
use crate::perception::grasp_type::{ModelError, read_model_file};
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
        let path = PathBuf::from(name);
        let session = session_from_memory(bytes, intra_threads).map_err(|e| match e {
            SessionError::Runtime(e) => ModelError::Runtime(e),
            SessionError::Load(reason) => ModelError::Load {
                path: path.clone(),
                reason,
            },
        })?;
        let classes = check_contract(&session).map_err(|reason| ModelError::Contract {
            path: path.clone(),
            reason,
        })?;
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

fn softmax(logits: &[f32]) -> Vec<f64> {
    let m = logits.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
    let e: Vec<f64> = logits.iter().map(|&x| (x as f64 - m).exp()).collect();
    let sum: f64 = e.iter().sum();
    e.into_iter().map(|x| x / sum).collect()
}

/// Checks the inputs, the output and the metadata; returns the classes.
fn check_contract(session: &Session) -> Result<Vec<String>, String> {
    let expect = [
        (
            "crop",
            vec![CROP_CHANNELS as i64, CROP_SIDE as i64, CROP_SIDE as i64],
        ),
        ("size", vec![SIZE_FEATURES as i64]),
    ];
    if session.inputs().len() != 2 {
        return Err(format!(
            "the model has {} inputs; the contract needs two: crop [N, {CROP_CHANNELS}, \
             {CROP_SIDE}, {CROP_SIDE}] and size [N, {SIZE_FEATURES}], float32",
            session.inputs().len()
        ));
    }
    for (name, dims) in &expect {
        let input = session
            .inputs()
            .iter()
            .find(|i| i.name() == *name)
            .ok_or_else(|| format!("the model has no input named '{name}'"))?;
        let (ty, d, syms) =
            tensor_info(input.dtype()).ok_or_else(|| format!("input '{name}' is not a tensor"))?;
        if ty != TensorElementType::Float32 || d.len() != dims.len() + 1 || d[1..] != dims[..] {
            return Err(format!(
                "input '{name}' is {ty} {}; the contract needs float32 [N, {}]",
                fmt_dims(d, syms),
                dims.iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn softmax_sums_to_one_and_keeps_the_order() {
        let p = softmax(&[1.0, 3.0, 2.0]);
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        // e^0 / (e^-2 + e^0 + e^-1)
        let z = (-2.0f64).exp() + 1.0 + (-1.0f64).exp();
        assert!((p[1] - 1.0 / z).abs() < 1e-12);
        assert!(p[1] > p[2] && p[2] > p[0]);
    }
}
