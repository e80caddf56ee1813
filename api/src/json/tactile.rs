//! Tactile sessions, frames, `POST /v1/tactile/analyze` and the stabilize stream's messages.

use crate::request::{LawWire, LayoutChoice, TactileFingerRequest, TactileSessionRequest};
use crate::schemas::{DetectorDoc, ElectrodePolarityDoc, FrameResultDoc, LayoutDoc, PidGainsDoc};
use graspd_core::tactile::{
    Baseline, DetectorChoice, ElectrodePolarity, FingerReading, Frame, FrameResult, LayoutSpec,
    ModelFreeThresholds, PidGains, StabilizerConfig, TareConfig,
};
use serde::{Deserialize, Serialize};
use utoipa::{IntoParams, ToSchema};

/// A finger's layout: a built-in name (`"biotac"`, `"biotac_sp"`) or
/// `{"name": .., "electrodes": [[x_mm, y_mm], …]}`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum LayoutJson {
    Name(String),
    Custom(LayoutSpec),
}

/// Taring, as in the proto's TareSettings: default the mean of the first 50 frames, falling
/// electrodes; `pretared: true` for already tared data (electrodes rising unless given).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct TareJson {
    #[serde(default)]
    pub baseline_frames: Option<usize>,
    #[serde(default)]
    pub pretared: bool,
    #[serde(default)]
    #[schema(value_type = Option<ElectrodePolarityDoc>)]
    pub electrode_polarity: Option<ElectrodePolarity>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct TactileFingerJson {
    pub name: String,
    #[schema(value_type = LayoutDoc)]
    pub layout: LayoutJson,
    #[serde(default)]
    pub tare: Option<TareJson>,
    /// The sensor gives only its electrodes: frames may send `"pac": []`, and pdc, tdc and tac
    /// are not read; contact from the electrodes, slip from the contact centroid's motion.
    #[serde(default)]
    pub electrodes_only: bool,
    /// This finger detects with this calibration (POST /v1/tactile/calibrations), whatever
    /// the session's detector: fingers that carry different sensors, or one calibration each.
    #[serde(default)]
    pub calibration: Option<String>,
}

/// `{"model_free": {thresholds…}}`, `{"model": "name"}` or `{"calibration": "name"}`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum DetectorJson {
    ModelFree(ModelFreeThresholds),
    Model(String),
    Calibration(String),
}

/// The session-opening message (the proto's TactileSession in JSON); unset fields take the
/// defaults.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct TactileSessionJson {
    pub fingers: Vec<TactileFingerJson>,
    #[serde(default)]
    pub window_length: Option<usize>,
    #[serde(default)]
    pub stride: Option<usize>,
    #[serde(default)]
    pub f0: Option<f64>,
    #[serde(default)]
    pub delta_material: Option<f64>,
    #[serde(default)]
    pub delta_slip: Option<f64>,
    #[serde(default)]
    pub f_min: Option<f64>,
    #[serde(default)]
    pub f_max: Option<f64>,
    /// Unset gains keep their defaults.
    #[serde(default)]
    #[schema(value_type = Option<PidGainsDoc>)]
    pub pid: Option<PidGains>,
    #[serde(default)]
    pub alpha: Option<f64>,
    #[serde(default)]
    pub calibration_gain: Option<f64>,
    /// Latched slip (a deviation from Eq 6.9, off by default): each slip episode (and each
    /// further 0.1 s a slip lasts) raises f_d by delta_slip until contact is lost.
    #[serde(default)]
    pub latch_slip: Option<bool>,
    /// Slip from the contact centroid's motion (not in the dissertation; unset: off): a finger
    /// in contact whose electrode centroid moves faster than this, mm/s, slips.
    #[serde(default)]
    pub centroid_slip_mm_s: Option<f64>,
    #[serde(default)]
    #[schema(value_type = Option<DetectorDoc>)]
    pub detector: Option<DetectorJson>,
}

/// pac as one number or the driver's samples.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(untagged)]
pub enum PacJson {
    One(f64),
    Samples(Vec<f64>),
}

fn no_pac() -> PacJson {
    PacJson::Samples(Vec::new())
}

#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct FingerReadingJson {
    pub pdc: f64,
    /// Absent or `[]` only for an electrodes-only finger.
    #[serde(default = "no_pac")]
    pub pac: PacJson,
    pub tdc: f64,
    pub tac: f64,
    pub electrodes: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct TactileFrameJson {
    pub timestamp: f64,
    pub fingers: Vec<FingerReadingJson>,
}

/// `POST /v1/tactile/analyze` with a JSON body.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct AnalyzeRequestJson {
    pub session: TactileSessionJson,
    pub frames: Vec<TactileFrameJson>,
}

/// `POST /v1/tactile/analyze` with a CSV body: the session of one finger as query parameters.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, IntoParams)]
#[serde(deny_unknown_fields)]
#[into_params(parameter_in = Query)]
pub struct AnalyzeCsvQuery {
    /// Finger name [finger].
    #[serde(default)]
    pub finger: Option<String>,
    /// Built-in layout [biotac].
    #[serde(default)]
    pub layout: Option<String>,
    #[serde(default)]
    pub pretared: bool,
    #[serde(default)]
    pub baseline_frames: Option<usize>,
    #[serde(default)]
    #[param(value_type = Option<ElectrodePolarityDoc>)]
    pub electrode_polarity: Option<ElectrodePolarity>,
    #[serde(default)]
    pub window_length: Option<usize>,
    #[serde(default)]
    pub stride: Option<usize>,
    #[serde(default)]
    pub f0: Option<f64>,
    #[serde(default)]
    pub delta_material: Option<f64>,
    #[serde(default)]
    pub delta_slip: Option<f64>,
    #[serde(default)]
    pub f_min: Option<f64>,
    #[serde(default)]
    pub f_max: Option<f64>,
    #[serde(default)]
    pub kp: Option<f64>,
    #[serde(default)]
    pub ki: Option<f64>,
    #[serde(default)]
    pub kd: Option<f64>,
    #[serde(default)]
    pub alpha: Option<f64>,
    #[serde(default)]
    pub calibration_gain: Option<f64>,
    /// A calibration (POST /v1/tactile/calibrations) as the detector.
    #[serde(default)]
    pub calibration: Option<String>,
    /// Latched slip (see TactileSessionJson).
    #[serde(default)]
    pub latch_slip: Option<bool>,
    /// Slip from the contact centroid's motion, mm/s (see TactileSessionJson).
    #[serde(default)]
    pub centroid_slip_mm_s: Option<f64>,
    /// The finger's sensor gives only its electrodes (see TactileFingerJson).
    #[serde(default)]
    pub electrodes_only: bool,
}

impl AnalyzeCsvQuery {
    pub fn session(self) -> TactileSessionJson {
        let pid = (self.kp.is_some() || self.ki.is_some() || self.kd.is_some()).then(|| {
            let d = PidGains::default();
            PidGains {
                kp: self.kp.unwrap_or(d.kp),
                ki: self.ki.unwrap_or(d.ki),
                kd: self.kd.unwrap_or(d.kd),
                ..d
            }
        });
        TactileSessionJson {
            fingers: vec![TactileFingerJson {
                name: self.finger.unwrap_or_else(|| "finger".into()),
                layout: LayoutJson::Name(self.layout.unwrap_or_else(|| "biotac".into())),
                tare: Some(TareJson {
                    baseline_frames: self.baseline_frames,
                    pretared: self.pretared,
                    electrode_polarity: self.electrode_polarity,
                }),
                electrodes_only: self.electrodes_only,
                calibration: None,
            }],
            window_length: self.window_length,
            stride: self.stride,
            f0: self.f0,
            delta_material: self.delta_material,
            delta_slip: self.delta_slip,
            f_min: self.f_min,
            f_max: self.f_max,
            pid,
            alpha: self.alpha,
            calibration_gain: self.calibration_gain,
            latch_slip: self.latch_slip,
            centroid_slip_mm_s: self.centroid_slip_mm_s,
            detector: self.calibration.map(DetectorJson::Calibration),
        }
    }
}

pub(super) fn tare_from_json(t: Option<TareJson>) -> TareConfig {
    let Some(t) = t else {
        return TareConfig::default();
    };
    let d = TareConfig::default();
    TareConfig {
        baseline: if t.pretared {
            Baseline::None
        } else {
            match d.baseline {
                Baseline::FirstFrames(n) => Baseline::FirstFrames(t.baseline_frames.unwrap_or(n)),
                Baseline::None => Baseline::None,
            }
        },
        electrode_polarity: t.electrode_polarity.unwrap_or(if t.pretared {
            ElectrodePolarity::Rising
        } else {
            ElectrodePolarity::Falling
        }),
    }
}

pub fn tactile_session_from_json(s: TactileSessionJson) -> TactileSessionRequest {
    let d = StabilizerConfig::default();
    TactileSessionRequest {
        fingers: s
            .fingers
            .into_iter()
            .map(|f| TactileFingerRequest {
                name: f.name,
                layout: match f.layout {
                    LayoutJson::Name(n) => LayoutChoice::Name(n),
                    LayoutJson::Custom(spec) => LayoutChoice::Custom(spec),
                },
                tare: tare_from_json(f.tare),
                electrodes_only: f.electrodes_only,
                calibration: f.calibration,
            })
            .collect(),
        config: StabilizerConfig {
            fingers: Vec::new(),
            window_length: s.window_length.unwrap_or(d.window_length),
            stride: s.stride.unwrap_or(d.stride),
            law: LawWire {
                f0: s.f0,
                delta_material: s.delta_material,
                delta_slip: s.delta_slip,
                f_min: s.f_min,
                f_max: s.f_max,
                latch_slip: s.latch_slip,
            }
            .law(),
            pid: s.pid.unwrap_or(d.pid),
            alpha: s.alpha.unwrap_or(d.alpha),
            calibration_gain: s.calibration_gain,
            centroid_slip_mm_s: s.centroid_slip_mm_s,
            detector: match s.detector {
                None => d.detector,
                Some(DetectorJson::ModelFree(t)) => DetectorChoice::ModelFree(t),
                Some(DetectorJson::Model(n)) => DetectorChoice::Model(n),
                Some(DetectorJson::Calibration(n)) => DetectorChoice::Calibration(n),
            },
        },
    }
}

pub fn tactile_frame_from_json(f: TactileFrameJson) -> Frame {
    Frame {
        timestamp: f.timestamp,
        fingers: f
            .fingers
            .into_iter()
            .map(|r| FingerReading {
                pdc: r.pdc,
                pac: match r.pac {
                    PacJson::One(v) => vec![v],
                    PacJson::Samples(v) => v,
                },
                tdc: r.tdc,
                tac: r.tac,
                electrodes: r.electrodes,
            })
            .collect(),
    }
}

/// The answer of `POST /v1/tactile/analyze`: one result per frame, in the domain's serde form
/// (the fields of the proto's StabilizationSetpoint / FingerSetpoint; enums as snake_case names,
/// probabilities and locations as arrays, absent values as null).
#[derive(Debug, Clone, Serialize, ToSchema)]
pub struct AnalyzeResponseJson {
    pub frame_count: usize,
    #[schema(value_type = Vec<FrameResultDoc>)]
    pub frames: Vec<FrameResult>,
}

/// One message of the `GET /v1/stabilize` WebSocket (the proto's StabilizeRequest in JSON):
/// `{"session": {…}}` first, then `{"frame": {…}}`.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct StabilizeMessageJson {
    #[serde(default)]
    pub session: Option<TactileSessionJson>,
    #[serde(default)]
    pub frame: Option<TactileFrameJson>,
}

/// The WebSocket's answer to one frame (the proto's StabilizationSetpoint in JSON): the frame's
/// 0-based index and its result, with the fields of an analyze result.
#[derive(Debug, Clone, Serialize)]
pub struct SetpointJson {
    pub frame_index: u64,
    #[serde(flatten)]
    pub result: FrameResult,
}
