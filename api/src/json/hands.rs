//! `GET /v1/hands`, `GET /v1/hands/{name}`, `GET /v1/hands/{name}/synergies` and
//! `POST /v1/hands` (registration).

use crate::request::{Asset, HandUpload, ModelFormat, StoredOverrides};
use crate::request::{HandSynergies, RegisteredHand};
use crate::schemas::{GraspTypeDoc, HandDescriptionDoc};
use base64::Engine;
use graspd_core::{FieldError, GraspType, HandDescription};
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// `GET /v1/hands`.
#[derive(Debug, Clone, Serialize, Deserialize, ToSchema)]
pub struct HandsJson {
    #[schema(value_type = Vec<HandDescriptionDoc>)]
    pub hands: Vec<HandDescription>,
}

/// `GET /v1/hands/{name}`.
#[derive(Debug, Clone, Serialize, Deserialize, ToSchema)]
pub struct HandJson {
    #[schema(value_type = HandDescriptionDoc)]
    pub hand: HandDescription,
    #[schema(value_type = Vec<GraspTypeDoc>)]
    pub realisable_types: Vec<GraspType>,
}

impl From<HandDescription> for HandJson {
    fn from(hand: HandDescription) -> Self {
        Self {
            realisable_types: hand.realisable_types(),
            hand,
        }
    }
}

/// One principal component eᵢ of a hand's postures (Eq 7.3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SynergyComponentJson {
    /// Unit vector over `joints` (its largest entry positive).
    pub direction: Vec<f64>,
    /// Variance of the postures along it, rad².
    pub variance: f64,
    /// Its share of the total variance.
    pub explained: f64,
}

/// One grasp type's cluster centre in the posture space (the dissertation's Fig 7.3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SynergyCentreJson {
    #[schema(value_type = GraspTypeDoc)]
    pub grasp_type: GraspType,
    /// Postures of this type.
    pub postures: usize,
    /// Mean amplitude on each component; the first two are A_center of Eq 7.5.
    pub amplitudes: Vec<f64>,
}

/// `GET /v1/hands/{name}/synergies`: a hand's posture synergies (dissertation §7.3). A
/// posture c (joint angles in `joints`' order, rad) is c = mean + Σ aᵢ componentsᵢ.direction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct HandSynergiesJson {
    pub hand: String,
    /// The model's joints, the order of every vector here.
    pub joints: Vec<String>,
    /// The nominal posture c_m (the postures' mean), rad.
    pub mean: Vec<f64>,
    /// In order of falling variance; components without variance are left out.
    pub components: Vec<SynergyComponentJson>,
    /// Per grasp type present, in the dissertation's order.
    pub centres: Vec<SynergyCentreJson>,
    /// Postures fitted: the feasible plans among `plans`.
    pub postures: usize,
    /// Plans made: each generated object once per type the hand realises.
    pub plans: usize,
    /// The planner's seed.
    pub seed: u64,
}

impl From<&HandSynergies> for HandSynergiesJson {
    fn from(h: &HandSynergies) -> Self {
        let s = &h.synergies;
        Self {
            hand: h.hand.clone(),
            joints: s.joints.clone(),
            mean: s.mean.clone(),
            components: s
                .components
                .iter()
                .map(|c| SynergyComponentJson {
                    direction: c.direction.clone(),
                    variance: c.variance,
                    explained: c.explained,
                })
                .collect(),
            centres: s
                .centres
                .iter()
                .map(|c| SynergyCentreJson {
                    grasp_type: c.grasp_type,
                    postures: c.postures,
                    amplitudes: c.amplitudes.clone(),
                })
                .collect(),
            postures: s.postures,
            plans: h.plans,
            seed: h.seed,
        }
    }
}

/// One uploaded file of `POST /v1/hands` in JSON: its relative path and its bytes in base64.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct HandAssetJson {
    pub path: String,
    /// Standard base64 (proto3 JSON's encoding of bytes).
    pub data: String,
}

/// The robot description of `POST /v1/hands` (proto `HandModel`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct HandModelJson {
    /// "mjcf" or "urdf".
    #[serde(default)]
    pub format: String,
    /// The XML document.
    #[serde(default)]
    pub text: String,
    #[serde(default)]
    pub assets: Vec<HandAssetJson>,
    #[serde(default)]
    pub palm: Option<String>,
    #[serde(default)]
    pub fingertips: Vec<String>,
    #[serde(default)]
    pub thumb: Option<String>,
}

/// `POST /v1/hands` as JSON (proto `RegisterHandRequest`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct RegisterHandJson {
    #[serde(default)]
    pub name: String,
    #[serde(default)]
    pub replace: bool,
    pub model: Option<HandModelJson>,
    /// Parametric descriptions are not registered (answered 400, naming `hand`).
    #[serde(default)]
    #[schema(value_type = Option<Object>)]
    pub hand: Option<serde_json::Value>,
}

/// The answer of `POST /v1/hands` (201).
#[derive(Debug, Clone, Serialize, Deserialize, ToSchema)]
pub struct RegisteredHandJson {
    #[schema(value_type = HandDescriptionDoc)]
    pub hand: HandDescription,
    #[schema(value_type = Vec<GraspTypeDoc>)]
    pub realisable_types: Vec<GraspType>,
    pub joints: Vec<String>,
    pub persisted: bool,
}

impl From<RegisteredHand> for RegisteredHandJson {
    fn from(r: RegisteredHand) -> Self {
        Self {
            realisable_types: r.description.realisable_types(),
            hand: r.description,
            joints: r.joints,
            persisted: r.persisted,
        }
    }
}

/// Decodes the JSON registration; errors name the field.
pub fn register_request_from_json(r: RegisterHandJson) -> Result<(HandUpload, bool), FieldError> {
    let model = match r.model {
        Some(m) => {
            let format = ModelFormat::parse(&m.format, "model.format")?;
            let mut assets = Vec::with_capacity(m.assets.len());
            for (i, a) in m.assets.into_iter().enumerate() {
                let data = base64::engine::general_purpose::STANDARD
                    .decode(a.data.as_bytes())
                    .map_err(|e| {
                        FieldError::new(
                            format!("model.assets[{i}].data"),
                            format!("not base64: {e}"),
                        )
                    })?;
                assets.push(Asset { path: a.path, data });
            }
            let overrides = StoredOverrides::requested(m.palm, m.fingertips, m.thumb);
            Some((format, m.text, assets, overrides))
        }
        None => None,
    };
    let upload = HandUpload::from_request(r.name, r.hand.is_some(), model)?;
    Ok((upload, r.replace))
}
