//! A hand registration in domain terms, as both transports decode it, with the registration
//! rules they share ([`HandUpload::from_request`], [`check_name`]), and the answer to it; and a
//! hand's posture synergies as served.

use graspd_core::{FieldError, HandDescription};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The document format of a hand model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ModelFormat {
    Mjcf,
    Urdf,
}

impl ModelFormat {
    /// Parses `mjcf` / `urdf` (case-insensitive); `field` names the value in errors.
    pub fn parse(s: &str, field: &str) -> Result<Self, FieldError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "mjcf" | "mujoco" => Ok(ModelFormat::Mjcf),
            "urdf" => Ok(ModelFormat::Urdf),
            "" => Err(FieldError::new(field, "missing: give 'mjcf' or 'urdf'")),
            other => Err(FieldError::new(
                field,
                format!(
                    "unknown format '{}' (give 'mjcf' or 'urdf')",
                    other.escape_debug()
                ),
            )),
        }
    }

    /// From a file name's extension (`.xml` → MJCF, `.urdf` → URDF).
    pub fn from_path(path: &Path) -> Option<Self> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "xml" | "mjcf" => Some(ModelFormat::Mjcf),
            "urdf" => Some(ModelFormat::Urdf),
            _ => None,
        }
    }
}

/// Overrides of the palm/finger/thumb detection, as stored and uploaded.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StoredOverrides {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub palm: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fingertips: Option<Vec<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thumb: Option<String>,
}

impl StoredOverrides {
    /// The overrides a registration asks for, as either transport received them: an empty
    /// name or list means "detect it".
    pub fn requested(palm: Option<String>, fingertips: Vec<String>, thumb: Option<String>) -> Self {
        let name = |s: Option<String>| s.map(|s| s.trim().to_string()).filter(|s| !s.is_empty());
        let fingertips: Vec<String> = fingertips
            .into_iter()
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect();
        Self {
            palm: name(palm),
            fingertips: (!fingertips.is_empty()).then_some(fingertips),
            thumb: name(thumb),
        }
    }
}

/// One uploaded file.
#[derive(Debug, Clone, PartialEq)]
pub struct Asset {
    /// Relative path (as the model refers to it), `/`-separated.
    pub path: String,
    pub data: Vec<u8>,
}

/// A registration request in domain terms.
#[derive(Debug, Clone, PartialEq)]
pub struct HandUpload {
    pub name: String,
    pub format: ModelFormat,
    /// The model document.
    pub text: String,
    pub assets: Vec<Asset>,
    pub overrides: StoredOverrides,
}

impl HandUpload {
    /// The registration rules both transports share, on what they decoded: a parametric
    /// description (`parametric`) is not registered, a model document is required; `model`
    /// gives its format (named, or as `ModelFormat::parse` reads it), text, assets and
    /// overrides. Errors name the field.
    pub fn from_request(
        name: String,
        parametric: bool,
        model: Option<(ModelFormat, String, Vec<Asset>, StoredOverrides)>,
    ) -> Result<Self, FieldError> {
        if parametric {
            return Err(FieldError::new(
                "hand",
                "parametric descriptions are not registered; send them inline as \
                 hand_description with each plan, or register a robot description in model",
            ));
        }
        let (format, text, assets, overrides) = model.ok_or_else(|| {
            FieldError::new("model", "missing: give the hand's MJCF or URDF document")
        })?;
        Ok(Self {
            name,
            format,
            text,
            assets,
            overrides,
        })
    }
}

/// Checks a hand name: 1–64 ASCII letters, digits, `_`, `-`, `.`, not starting with `.`.
pub fn check_name(name: &str, field: &str) -> Result<(), FieldError> {
    if name.is_empty() {
        return Err(FieldError::new(field, "missing: give the hand a name"));
    }
    if name.len() > 64
        || name.starts_with('.')
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
    {
        return Err(FieldError::new(
            field,
            format!(
                "'{}' is not a valid hand name (1-64 of A-Z a-z 0-9 _ - ., not starting with '.')",
                name.escape_debug()
            ),
        ));
    }
    Ok(())
}

/// The answer to a registration.
#[derive(Debug, Clone, PartialEq)]
pub struct RegisteredHand {
    pub description: HandDescription,
    /// Joint names of the model, in the order plans list them.
    pub joints: Vec<String>,
    /// Stored in the hands directory (else in memory only).
    pub persisted: bool,
}

/// A hand's posture synergies (`GET /v1/hands/{name}/synergies`, gRPC `GetHandSynergies`;
/// dissertation §7.3): the posture space fitted to graspd's own plans for the hand.
#[derive(Debug, Clone, PartialEq)]
pub struct HandSynergies {
    pub hand: String,
    pub synergies: graspd_core::hand::PostureSynergies,
    /// Plans made for it (feasible ones gave the postures: `synergies.postures`).
    pub plans: usize,
    /// The planner's seed.
    pub seed: u64,
}
