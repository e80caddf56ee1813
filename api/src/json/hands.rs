//! `GET /v1/hands`, `GET /v1/hands/{name}` and `POST /v1/hands` (registration).

use crate::request::RegisteredHand;
use crate::request::{Asset, HandUpload, ModelFormat, StoredOverrides};
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
