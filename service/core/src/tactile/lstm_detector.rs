//! The learned contact-event and material detector (method.md §5, dissertation ch. 6.3,
//! Eq 6.1–6.4): an LSTM encoder over the window t_seq whose latent code feeds the event
//! classifier (non-contact / contact / slip, Eq 6.3) and the material classifier (paper / foam /
//! plastic / metal, Eq 6.4). It is trained and exported by `models/tactile/train.py` (the
//! encoder–decoder's reconstruction loss, Eq 6.2, only shapes training; the decoder is not
//! exported) and runs here in ONNX Runtime.
//!
//! # Model contract (checked by [`TactileModel::load`], models/tactile/MODEL_CARD.md)
//!
//! - **Input**: exactly one, float32, `[1, l, F]` (batch 1 or dynamic; l fixed or dynamic). With
//!   a dynamic batch axis the windows of several sessions that are due together share one run
//!   ([`TactileModel::infer_batch`]); with batch 1 they run one after another.
//! - **Outputs**: `event_logits` `[1, 3]` (non-contact, contact, slip) and `material_logits`
//!   `[1, 4]` (paper, foam, plastic, metal), float32 logits, the batch axis as the input's;
//!   graspd applies the softmax.
//! - **Metadata** (`custom_metadata_map`), all required:
//!   `graspd.tactile.features` — the F feature names in input order, from `pdc`, `pac` (mean of
//!   the frame's pac samples), `pac_vibration`, `tdc`, `tac` and `e1`…`eN` (tared electrodes, see
//!   [`DetectorSample`]); `graspd.tactile.mean` / `graspd.tactile.std` — F numbers each, the
//!   input is `(x − mean) / std`; `graspd.tactile.window` — l; `graspd.tactile.stride` — k;
//!   `graspd.tactile.padding` — `repeat_oldest` (a window shorter than l, at the start of a
//!   session, is left-padded with its oldest sample); `graspd.tactile.events` =
//!   `non_contact,contact,slip` and `graspd.tactile.materials` = `paper,foam,plastic,metal`
//!   (the output orders).

use super::detector::{
    ContactEvent, Detection, DetectorSample, EventDetector, Material, ModelFreeDetector,
};
use crate::onnx_runtime::{RuntimeError, SessionError, fmt_dims, session_from_memory, tensor_info};
use ort::session::Session;
use ort::value::{TensorElementType, TensorRef};
use std::path::Path;
use std::sync::{Arc, Mutex, PoisonError};
use thiserror::Error;

/// Metadata keys of the contract (module doc).
pub const META_FEATURES: &str = "graspd.tactile.features";
pub const META_MEAN: &str = "graspd.tactile.mean";
pub const META_STD: &str = "graspd.tactile.std";
pub const META_WINDOW: &str = "graspd.tactile.window";
pub const META_STRIDE: &str = "graspd.tactile.stride";
pub const META_PADDING: &str = "graspd.tactile.padding";
pub const META_EVENTS: &str = "graspd.tactile.events";
pub const META_MATERIALS: &str = "graspd.tactile.materials";

const EVENTS: &str = "non_contact,contact,slip";
const MATERIALS: &str = "paper,foam,plastic,metal";
const OUT_EVENT: &str = "event_logits";
const OUT_MATERIAL: &str = "material_logits";

/// Errors of the tactile model.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum TactileModelError {
    /// ONNX Runtime itself is missing or failed to load.
    #[error(transparent)]
    Runtime(RuntimeError),
    #[error("cannot load the tactile model {source_name}: {reason}")]
    Load { source_name: String, reason: String },
    #[error(
        "the tactile model {source_name} does not follow its contract \
         (models/tactile/MODEL_CARD.md): {reason}"
    )]
    Contract { source_name: String, reason: String },
    #[error("tactile inference failed: {0}")]
    Inference(String),
}

/// One input feature, read from a [`DetectorSample`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Feature {
    Pdc,
    Pac,
    PacVibration,
    Tdc,
    Tac,
    /// Electrode index (0-based).
    Electrode(usize),
}

impl Feature {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "pdc" => Self::Pdc,
            "pac" => Self::Pac,
            "pac_vibration" => Self::PacVibration,
            "tdc" => Self::Tdc,
            "tac" => Self::Tac,
            _ => {
                let k: usize = name.strip_prefix('e')?.parse().ok()?;
                Self::Electrode(k.checked_sub(1)?)
            }
        })
    }

    fn value(self, s: &DetectorSample) -> f64 {
        match self {
            Self::Pdc => s.pdc,
            Self::Pac => s.pac,
            Self::PacVibration => s.pac_vibration,
            Self::Tdc => s.tdc,
            Self::Tac => s.tac,
            Self::Electrode(i) => s.electrodes.get(i).copied().unwrap_or(0.0),
        }
    }
}

/// A loaded tactile model, shared by the sessions (runs are serialised: ort's `Session::run`
/// needs `&mut`; one run of the shipped model takes tens of microseconds).
#[derive(Debug)]
pub struct TactileModel {
    source_name: String,
    session: Mutex<Session>,
    features: Vec<Feature>,
    mean: Vec<f32>,
    inv_std: Vec<f32>,
    window: usize,
    stride: usize,
    electrodes: usize,
    /// Whether the batch axis is dynamic (windows of several sessions share a run).
    batched: bool,
}

/// Windows one run of a model with a dynamic batch axis takes at most (a larger batch is run in
/// pieces).
pub const MAX_BATCH: usize = 64;

/// Event and material probabilities of one window (softmax of the model's logits).
pub type ModelOutput = ([f64; 3], [f64; 4]);

impl TactileModel {
    /// Loads the ONNX file at `path` and checks it against the contract (module doc).
    /// Initialises ONNX Runtime from `$ORT_DYLIB_PATH` unless `init_onnx_runtime` ran before.
    pub fn load(path: &Path) -> Result<Self, TactileModelError> {
        let name = path.display().to_string();
        if !path.is_file() {
            return Err(TactileModelError::Load {
                source_name: name,
                reason: "no such file".into(),
            });
        }
        let bytes = std::fs::read(path).map_err(|e| TactileModelError::Load {
            source_name: name.clone(),
            reason: e.to_string(),
        })?;
        Self::from_bytes(&bytes, &name)
    }

    /// Loads a model from memory (e.g. a copy embedded in the binary); `source_name` names it in
    /// errors and logs.
    pub fn from_bytes(bytes: &[u8], source_name: &str) -> Result<Self, TactileModelError> {
        let session = session_from_memory(bytes, 1).map_err(|e| match e {
            SessionError::Runtime(e) => TactileModelError::Runtime(e),
            SessionError::Load(reason) => TactileModelError::Load {
                source_name: source_name.to_string(),
                reason,
            },
        })?;
        let contract = check_contract(&session).map_err(|reason| TactileModelError::Contract {
            source_name: source_name.to_string(),
            reason,
        })?;
        Ok(Self {
            source_name: source_name.to_string(),
            session: Mutex::new(session),
            electrodes: contract
                .features
                .iter()
                .filter_map(|f| match f {
                    Feature::Electrode(i) => Some(i + 1),
                    _ => None,
                })
                .max()
                .unwrap_or(0),
            features: contract.features,
            mean: contract.mean,
            inv_std: contract.std.iter().map(|s| 1.0 / s).collect(),
            window: contract.window,
            stride: contract.stride,
            batched: contract.batched,
        })
    }

    /// Where the model came from (a path, or `embedded:…`).
    pub fn source_name(&self) -> &str {
        &self.source_name
    }

    /// l: the window length the model was trained on.
    pub fn window_length(&self) -> usize {
        self.window
    }

    /// k: every k-th reading enters the window.
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Electrodes the model reads (e1…eN): 19 for the classic BioTac.
    pub fn electrode_count(&self) -> usize {
        self.electrodes
    }

    /// Whether the model's batch axis is dynamic: [`Self::infer_batch`] then runs up to
    /// [`MAX_BATCH`] windows at once.
    pub fn is_batched(&self) -> bool {
        self.batched
    }

    /// Event and material probabilities (softmax of the logits) for a window (oldest first, 1 to
    /// l samples; shorter windows are left-padded with the oldest sample). `input` is scratch
    /// space reused between calls.
    pub fn infer(
        &self,
        window: &[DetectorSample],
        input: &mut Vec<f32>,
    ) -> Result<ModelOutput, TactileModelError> {
        let mut out = self.run(&[window], input)?;
        Ok(out.remove(0))
    }

    /// [`Self::infer`] for several windows: one run per [`MAX_BATCH`] windows when the batch
    /// axis is dynamic, else one run per window. The outputs are in the windows' order.
    pub fn infer_batch(
        &self,
        windows: &[&[DetectorSample]],
    ) -> Result<Vec<ModelOutput>, TactileModelError> {
        let mut input = Vec::new();
        let per_run = if self.batched { MAX_BATCH } else { 1 };
        let mut out = Vec::with_capacity(windows.len());
        for chunk in windows.chunks(per_run) {
            out.extend(self.run(chunk, &mut input)?);
        }
        Ok(out)
    }

    /// One run over `windows` (as many as the batch axis allows).
    fn run(
        &self,
        windows: &[&[DetectorSample]],
        input: &mut Vec<f32>,
    ) -> Result<Vec<ModelOutput>, TactileModelError> {
        let f = self.features.len();
        let b = windows.len();
        input.clear();
        for window in windows {
            if window.is_empty() || window.len() > self.window {
                return Err(TactileModelError::Inference(format!(
                    "the window has {} samples; the model takes 1 to {}",
                    window.len(),
                    self.window
                )));
            }
            let pad = self.window - window.len();
            for s in std::iter::repeat_n(&window[0], pad).chain(window.iter()) {
                for (k, feat) in self.features.iter().enumerate() {
                    input.push((feat.value(s) as f32 - self.mean[k]) * self.inv_std[k]);
                }
            }
        }
        let fail = |e: ort::Error| TactileModelError::Inference(e.to_string());
        let view = ndarray::ArrayView3::from_shape((b, self.window, f), &input[..])
            .map_err(|e| TactileModelError::Inference(e.to_string()))?;
        let tensor = TensorRef::from_array_view(view).map_err(fail)?;
        let mut session = self.session.lock().unwrap_or_else(PoisonError::into_inner);
        let outputs = session.run(ort::inputs![tensor]).map_err(fail)?;
        let read = |name: &str, n: usize| -> Result<Vec<f32>, TactileModelError> {
            let (shape, v) = outputs[name].try_extract_tensor::<f32>().map_err(fail)?;
            if v.len() != b * n {
                return Err(TactileModelError::Inference(format!(
                    "output '{name}' has shape {}; it needs [{b}, {n}]",
                    fmt_dims(shape, &[])
                )));
            }
            Ok(v.to_vec())
        };
        let e = read(OUT_EVENT, 3)?;
        let m = read(OUT_MATERIAL, 4)?;
        Ok(e.chunks(3)
            .zip(m.chunks(4))
            .map(|(e, m)| {
                let (e, m) = (softmax(e), softmax(m));
                ([e[0], e[1], e[2]], [m[0], m[1], m[2], m[3]])
            })
            .collect())
    }
}

fn softmax(logits: &[f32]) -> Vec<f64> {
    let max = logits.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
    let e: Vec<f64> = logits.iter().map(|&x| (x as f64 - max).exp()).collect();
    let s: f64 = e.iter().sum();
    e.into_iter().map(|x| x / s).collect()
}

struct Contract {
    features: Vec<Feature>,
    mean: Vec<f32>,
    std: Vec<f32>,
    window: usize,
    stride: usize,
    batched: bool,
}

/// Checks inputs, outputs and metadata against the contract (module doc).
fn check_contract(session: &Session) -> Result<Contract, String> {
    let meta = session
        .metadata()
        .map_err(|e| format!("cannot read the model metadata: {e}"))?;
    let get = |key: &str| {
        meta.custom(key)
            .ok_or_else(|| format!("metadata {key} is missing"))
    };
    let names = get(META_FEATURES)?;
    let features = names
        .split(',')
        .map(|n| {
            Feature::parse(n.trim()).ok_or_else(|| {
                format!(
                    "metadata {META_FEATURES} names an unknown feature '{}'; known: pdc, pac, \
                     pac_vibration, tdc, tac, e1…eN",
                    n.trim()
                )
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let f = features.len();
    let numbers = |key: &str, positive: bool| -> Result<Vec<f32>, String> {
        let text = get(key)?;
        let v: Vec<f32> = text
            .split(',')
            .map(|s| s.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("metadata {key} is not a comma-separated list of numbers"))?;
        if v.len() != f || !v.iter().all(|x| x.is_finite() && (!positive || *x > 0.0)) {
            return Err(format!(
                "metadata {key} has {} values; it needs {f} finite numbers{} (one per feature)",
                v.len(),
                if positive { " > 0" } else { "" }
            ));
        }
        Ok(v)
    };
    let mean = numbers(META_MEAN, false)?;
    let std = numbers(META_STD, true)?;
    let count = |key: &str| -> Result<usize, String> {
        get(key)?
            .trim()
            .parse::<usize>()
            .ok()
            .filter(|&n| (1..=1024).contains(&n))
            .ok_or_else(|| format!("metadata {key} must be a whole number 1 to 1024"))
    };
    let window = count(META_WINDOW)?;
    let stride = count(META_STRIDE)?;
    let padding = get(META_PADDING)?;
    if padding != "repeat_oldest" {
        return Err(format!(
            "metadata {META_PADDING} = {padding:?}; graspd pads short windows with \
             'repeat_oldest' only"
        ));
    }
    for (key, want) in [(META_EVENTS, EVENTS), (META_MATERIALS, MATERIALS)] {
        let got = get(key)?;
        if got.replace(' ', "") != want {
            return Err(format!(
                "metadata {key} = {got:?}; graspd reads the outputs in the order {want:?}"
            ));
        }
    }
    if session.inputs().len() != 1 {
        return Err(format!(
            "the model has {} inputs; the contract needs exactly one, [1, {window}, {f}] float32",
            session.inputs().len()
        ));
    }
    let input = &session.inputs()[0];
    let (ty, dims, syms) = tensor_info(input.dtype())
        .ok_or_else(|| format!("input '{}' is not a tensor", input.name()))?;
    let dim_ok = |d: i64, want: usize| d < 0 || d == want as i64;
    if ty != TensorElementType::Float32
        || dims.len() != 3
        || !dim_ok(dims[0], 1)
        || !dim_ok(dims[1], window)
        || dims[2] != f as i64
    {
        return Err(format!(
            "input '{}' is {ty} {}; the contract needs f32 [1, {window}, {f}] (batch 1, the \
             window of {META_WINDOW}, one channel per feature of {META_FEATURES})",
            input.name(),
            fmt_dims(dims, syms)
        ));
    }
    let batched = dims[0] < 0;
    for (name, n) in [(OUT_EVENT, 3usize), (OUT_MATERIAL, 4)] {
        let Some(o) = session.outputs().iter().find(|o| o.name() == name) else {
            let have: Vec<String> = session
                .outputs()
                .iter()
                .map(|o| format!("'{}'", o.name()))
                .collect();
            return Err(format!(
                "no output '{name}' (the model has {}); the contract needs '{OUT_EVENT}' [1, 3] \
                 and '{OUT_MATERIAL}' [1, 4]",
                have.join(", ")
            ));
        };
        let (ty, dims, syms) =
            tensor_info(o.dtype()).ok_or_else(|| format!("output '{name}' is not a tensor"))?;
        // A dynamic batch axis in the input needs one in the outputs.
        if ty != TensorElementType::Float32
            || dims.len() != 2
            || !dim_ok(dims[0], 1)
            || (batched && dims[0] >= 0)
            || !dim_ok(dims[1], n)
        {
            return Err(format!(
                "output '{name}' is {ty} {}; the contract needs f32 [1, {n}] logits",
                fmt_dims(dims, syms)
            ));
        }
    }
    Ok(Contract {
        features,
        mean,
        std,
        window,
        stride,
        batched,
    })
}

/// [`EventDetector`] running a [`TactileModel`]; one per finger and session.
pub struct LstmDetector {
    model: Arc<TactileModel>,
    input: Vec<f32>,
    /// Answers if a run fails (it should not: the contract was checked at load), so that a
    /// session keeps its contact/slip safety behaviour.
    fallback: ModelFreeDetector,
}

impl LstmDetector {
    pub fn new(model: Arc<TactileModel>) -> Self {
        Self {
            model,
            input: Vec::new(),
            fallback: ModelFreeDetector::default(),
        }
    }
}

impl LstmDetector {
    /// Eq 6.3 (event) and Eq 6.4 (material) from the model's probabilities; material is
    /// `Unknown` unless the event is contact or slip. A failed run answers with the model-free
    /// detector, so that a session keeps its contact/slip safety behaviour.
    fn detection(
        &self,
        output: Result<ModelOutput, &TactileModelError>,
        window: &[DetectorSample],
    ) -> Detection {
        match output {
            Ok((ev, mat)) => {
                let best = (0..3).max_by(|&a, &b| ev[a].total_cmp(&ev[b])).unwrap_or(0);
                let event = ContactEvent::ALL[best];
                let (material, material_probabilities) = if event == ContactEvent::NonContact {
                    (Material::Unknown, None)
                } else {
                    let m = (0..4)
                        .max_by(|&a, &b| mat[a].total_cmp(&mat[b]))
                        .unwrap_or(0);
                    (Material::CLASSES[m], Some(mat))
                };
                Detection {
                    event,
                    event_probabilities: ev,
                    material,
                    material_probabilities,
                    slip_direction: None,
                }
            }
            Err(e) => {
                tracing::warn!(model = %self.model.source_name, error = %e, "tactile model run failed; model-free detection for this window");
                self.fallback.clone().detect(window)
            }
        }
    }

    /// The newest l samples of a window (a longer one is cut to the model's l).
    fn newest<'w>(&self, window: &'w [DetectorSample]) -> &'w [DetectorSample] {
        &window[window.len().saturating_sub(self.model.window)..]
    }
}

impl EventDetector for LstmDetector {
    fn detect(&mut self, window: &[DetectorSample]) -> Detection {
        let output = self.model.infer(self.newest(window), &mut self.input);
        self.detection(output.as_ref().map(|o| *o), window)
    }

    /// The model's address: detectors of one loaded model share its runs.
    fn batch_key(&self) -> Option<usize> {
        self.model
            .is_batched()
            .then_some(Arc::as_ptr(&self.model) as usize)
    }

    fn detect_many(&self, windows: &[&[DetectorSample]]) -> Option<Vec<Detection>> {
        let newest: Vec<&[DetectorSample]> = windows.iter().map(|w| self.newest(w)).collect();
        Some(match self.model.infer_batch(&newest) {
            Ok(out) => out
                .into_iter()
                .zip(windows)
                .map(|(o, w)| self.detection(Ok(o), w))
                .collect(),
            Err(e) => windows.iter().map(|w| self.detection(Err(&e), w)).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feature_names_parse() {
        assert_eq!(Feature::parse("pdc"), Some(Feature::Pdc));
        assert_eq!(Feature::parse("e1"), Some(Feature::Electrode(0)));
        assert_eq!(Feature::parse("e19"), Some(Feature::Electrode(18)));
        assert_eq!(Feature::parse("e0"), None);
        assert_eq!(Feature::parse("temperature"), None);
        let s = DetectorSample {
            pdc: 1.0,
            pac: 2.0,
            pac_vibration: 3.0,
            pac_samples: vec![2.0],
            tdc: 4.0,
            tac: 5.0,
            electrodes: vec![6.0, 7.0],
        };
        assert_eq!(Feature::Electrode(1).value(&s), 7.0);
        assert_eq!(Feature::PacVibration.value(&s), 3.0);
    }

    #[test]
    fn softmax_sums_to_one() {
        let p = softmax(&[1.0, 2.0, 3.0]);
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(p[2] > p[1] && p[1] > p[0]);
    }
}
