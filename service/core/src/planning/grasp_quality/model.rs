//! The grasp-quality network loaded and checked against its contract (docs/model-contract.md,
//! "The grasp-quality network"): two inputs, `crop` `[N, 2, 32, 32]` and `configuration`
//! `[N, 1]` float32 ([`super::crop::grasp_view`]), one output, `[N, 2]` logits (P, Q);
//! graspd applies the softmax, P(y = 1) = e^Q / (e^P + e^Q) (Eq 3.1).

use super::crop::{CHANNELS, CROP, GraspView};
use crate::onnx_runtime::{check_float_inputs, fmt_dims, softmax, tensor_info};
use crate::perception::grasp_type::{ModelError, checked_session, read_model_file};
use ort::session::Session;
use ort::value::{TensorElementType, TensorRef};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

/// The loaded network. Runs are serialised by a mutex, as for graspd's other networks.
#[derive(Debug)]
pub struct GraspQualityModel {
    path: PathBuf,
    session: Mutex<Session>,
}

impl GraspQualityModel {
    /// Loads the ONNX model at `path` and checks it against the contract.
    pub fn load(path: &Path, intra_threads: usize) -> Result<Self, ModelError> {
        let bytes = read_model_file(path)?;
        Self::from_bytes(&bytes, &path.display().to_string(), intra_threads)
    }

    /// Loads a model held in memory (the copy of models/grasp_quality/grasp_quality.onnx built
    /// into graspd); `name` stands for its path in messages.
    pub fn from_bytes(bytes: &[u8], name: &str, intra_threads: usize) -> Result<Self, ModelError> {
        let (path, session, ()) = checked_session(bytes, name, intra_threads, check_contract)?;
        Ok(Self {
            path,
            session: Mutex::new(session),
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// P(y = 1 | I, g) of Eq 3.1 for each grasp's view, one run for all of them.
    pub fn quality(&self, views: &[GraspView]) -> Result<Vec<f64>, ModelError> {
        if views.is_empty() {
            return Ok(Vec::new());
        }
        let n = views.len();
        let crops: Vec<f32> = views.iter().flat_map(|v| v.crop.iter().copied()).collect();
        let confs: Vec<f32> = views.iter().flat_map(|v| v.configuration).collect();
        let fail = |e: ort::Error| ModelError::Inference(e.to_string());
        let shape_err = |e: ndarray::ShapeError| ModelError::Inference(e.to_string());
        let crop = ndarray::ArrayView4::from_shape((n, CHANNELS, CROP, CROP), &crops)
            .map_err(shape_err)?;
        let conf = ndarray::ArrayView2::from_shape((n, 1), &confs).map_err(shape_err)?;
        let crop = TensorRef::from_array_view(crop).map_err(fail)?;
        let conf = TensorRef::from_array_view(conf).map_err(fail)?;
        let mut session = self.session.lock().unwrap_or_else(PoisonError::into_inner);
        let outputs = session
            .run(ort::inputs!["crop" => crop, "configuration" => conf])
            .map_err(fail)?;
        let (shape, logits) = outputs[0].try_extract_tensor::<f32>().map_err(fail)?;
        if shape.len() != 2 || shape[0] != n as i64 || shape[1] != 2 {
            return Err(ModelError::Inference(format!(
                "the output has shape {}; the grasp-quality contract needs [{n}, 2]",
                fmt_dims(shape, &[])
            )));
        }
        Ok(logits.chunks_exact(2).map(|l| softmax(l)[1]).collect())
    }
}

/// Checks the inputs and the output.
fn check_contract(session: &Session) -> Result<(), String> {
    check_float_inputs(
        session,
        &[
            ("crop", &[CHANNELS as i64, CROP as i64, CROP as i64]),
            ("configuration", &[1]),
        ],
    )?;
    if session.outputs().len() != 1 {
        return Err(format!(
            "the model has {} outputs; the contract needs one, [N, 2] float32 logits (P, Q)",
            session.outputs().len()
        ));
    }
    let (ty, d, syms) = tensor_info(session.outputs()[0].dtype())
        .ok_or_else(|| "the output is not a tensor".to_string())?;
    if ty != TensorElementType::Float32 || d.len() != 2 || (d[1] >= 0 && d[1] != 2) {
        return Err(format!(
            "output is {ty} {}; the contract needs float32 [N, 2] (the logits P and Q of Eq 3.1)",
            fmt_dims(d, syms)
        ));
    }
    Ok(())
}
