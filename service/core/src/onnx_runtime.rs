//! The process-wide ONNX Runtime that graspd's networks run in (the grasp-type network,
//! `perception::grasp_type`; the tactile detector, `tactile::lstm_detector`): `ort`
//! loads the library at run time, from an explicit path or `$ORT_DYLIB_PATH`, once per
//! process; the session building both models share; and the helpers their contract checks use.

use ort::environment::Environment;
use ort::session::Session;
use ort::value::{TensorElementType, ValueType};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};
use thiserror::Error;

/// The environment variable naming the ONNX Runtime library when no path is given.
pub const ORT_DYLIB_ENV: &str = "ORT_DYLIB_PATH";

/// Why ONNX Runtime is not there.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum RuntimeError {
    #[error(
        "no ONNX Runtime library: pass its path or set {ORT_DYLIB_ENV} \
         (scripts/fetch-onnxruntime.sh fetches libonnxruntime.so.1.31.1)"
    )]
    NoRuntime,
    #[error("cannot load the ONNX Runtime library {}: {reason}", path.display())]
    Load { path: PathBuf, reason: String },
}

/// The process-wide ONNX Runtime: ort loads one library and allows one environment per process.
struct Runtime {
    path: PathBuf,
    env: Environment,
}

static RUNTIME: Mutex<Option<Runtime>> = Mutex::new(None);

/// Loads ONNX Runtime from `dylib`, else from `$ORT_DYLIB_PATH`, once per process.
///
/// Later calls succeed without loading anything (a process holds a single runtime; a different
/// path is logged and ignored), but a given path that does not exist is always an error naming
/// it. Errors name the library's path, or say that none was given.
pub fn init_onnx_runtime(dylib: Option<&Path>) -> Result<(), RuntimeError> {
    runtime_env(dylib).map(|_| ())
}

/// Why a model's session was not built: the runtime is missing, or ort refused the model (its
/// message; each model wraps it in its own error, naming its file).
#[derive(Debug)]
pub(crate) enum SessionError {
    Runtime(RuntimeError),
    Load(String),
}

/// A session over a model held in memory, with `intra_threads` threads inside a run.
pub(crate) fn session_from_memory(
    bytes: &[u8],
    intra_threads: usize,
) -> Result<Session, SessionError> {
    let env = runtime_env(None).map_err(SessionError::Runtime)?;
    let mut builder = Session::builder(&env)
        .map_err(|e| SessionError::Load(e.to_string()))?
        .with_intra_threads(intra_threads)
        .map_err(|e| SessionError::Load(e.to_string()))?;
    builder
        .commit_from_memory(bytes)
        .map_err(|e| SessionError::Load(e.to_string()))
}

pub(crate) fn runtime_env(dylib: Option<&Path>) -> Result<Environment, RuntimeError> {
    let missing = |p: &Path| RuntimeError::Load {
        path: p.to_path_buf(),
        reason: "no such file (scripts/fetch-onnxruntime.sh fetches it)".into(),
    };
    if let Some(p) = dylib
        && !p.is_file()
    {
        return Err(missing(p));
    }
    let mut rt = RUNTIME.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some(rt) = rt.as_ref() {
        if let Some(p) = dylib
            && std::path::absolute(p).ok().as_ref() != Some(&rt.path)
        {
            tracing::warn!(
                requested = %p.display(),
                loaded = %rt.path.display(),
                "ONNX Runtime is already loaded; a process can hold only one"
            );
        }
        return Ok(rt.env.clone());
    }
    let requested = match dylib {
        Some(p) => Some(p.to_path_buf()),
        None => std::env::var_os(ORT_DYLIB_ENV)
            .filter(|s| !s.is_empty())
            .map(PathBuf::from),
    };
    if let Some(p) = &requested
        && !p.is_file()
    {
        return Err(missing(p));
    }
    let path = requested.ok_or(RuntimeError::NoRuntime)?;
    // Absolute, so that ort does not look for a relative path next to the executable first.
    let path = std::path::absolute(&path).unwrap_or(path);
    let fail = |reason: String| RuntimeError::Load {
        path: path.clone(),
        reason,
    };
    let env = ort::init_from(&path)
        .map_err(|e| fail(e.to_string()))?
        .with_name("graspd")
        .with_telemetry(false)
        .build()
        .map_err(|e| fail(e.to_string()))?;
    *rt = Some(Runtime {
        path,
        env: env.clone(),
    });
    Ok(env)
}

/// Formats a shape, dynamic dimensions by their symbol or `?`.
pub(crate) fn fmt_dims(dims: &[i64], symbols: &[String]) -> String {
    let parts: Vec<String> = dims
        .iter()
        .enumerate()
        .map(|(i, &d)| match symbols.get(i).filter(|s| !s.is_empty()) {
            Some(sym) if d < 0 => sym.clone(),
            _ if d < 0 => "?".into(),
            _ => d.to_string(),
        })
        .collect();
    format!("[{}]", parts.join(", "))
}

/// A tensor's element type, shape and dimension symbols; None for a non-tensor.
pub(crate) fn tensor_info(t: &ValueType) -> Option<(TensorElementType, &[i64], &[String])> {
    match t {
        ValueType::Tensor {
            ty,
            shape,
            dimension_symbols,
        } => Some((*ty, &shape[..], &dimension_symbols[..])),
        _ => None,
    }
}

/// Checks that `session` has exactly the float32 inputs `expect` (name, dims after the batch),
/// naming what it found against what the contract needs.
pub(crate) fn check_float_inputs(
    session: &ort::session::Session,
    expect: &[(&str, &[i64])],
) -> Result<(), String> {
    let wanted = || {
        expect
            .iter()
            .map(|(n, d)| {
                let dims: Vec<String> = d.iter().map(|x| x.to_string()).collect();
                format!("{n} [N, {}]", dims.join(", "))
            })
            .collect::<Vec<_>>()
            .join(" and ")
    };
    if session.inputs().len() != expect.len() {
        return Err(format!(
            "the model has {} inputs; the contract needs {}: {}, float32",
            session.inputs().len(),
            expect.len(),
            wanted()
        ));
    }
    for (name, dims) in expect {
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
    Ok(())
}

/// The softmax of one row of logits.
pub(crate) fn softmax(logits: &[f32]) -> Vec<f64> {
    let m = logits.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
    let e: Vec<f64> = logits.iter().map(|&x| (x as f64 - m).exp()).collect();
    let sum: f64 = e.iter().sum();
    e.into_iter().map(|x| x / sum).collect()
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

    #[test]
    fn an_unloadable_library_is_named() {
        let path = std::env::temp_dir().join(format!("graspd-not-ort-{}.so", std::process::id()));
        std::fs::write(&path, b"not a shared library").unwrap();
        if RUNTIME
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .is_some()
        {
            return;
        }
        let e = init_onnx_runtime(Some(&path)).unwrap_err().to_string();
        std::fs::remove_file(&path).ok();
        assert!(
            e.contains("cannot load the ONNX Runtime library") && e.contains("graspd-not-ort-"),
            "{e}"
        );
    }
}
