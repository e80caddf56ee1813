//! The one place that converts between the REST JSON and domain types. The JSON mirrors the proto
//! in snake_case; where the domain's own serde form is the documented one (hand descriptions,
//! planner options, grasp-type and hand-part names, the numeric report structs) it is used as
//! is, and the DTOs here cover what differs: clouds (arrays or base64), positions as
//! `{x, y, z}` (accepted as `[x, y, z]` too), poses and the response layout.
//!
//! One file per message family: [`values`], [`plan`], [`reach`], [`perception`], [`ros`], [`tactile`],
//! [`calibration`], [`hands`];
//! here the parser that names fields by their paths, and the error body.

mod calibration;
mod hands;
mod perception;
mod plan;
mod reach;
mod ros;
mod tactile;
mod values;

pub use calibration::*;
pub use hands::*;
pub use perception::*;
pub use plan::*;
pub use reach::*;
pub use ros::*;
pub use tactile::*;
pub use values::*;

use graspd_core::FieldError;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// Parses JSON; errors name the field by its path (`hints.grasp_type`, `options.foo`), or
/// `root` (e.g. `body`) when the JSON itself is malformed.
/// The JSON must be an object (serde would also read a struct from an array).
pub fn parse<T: DeserializeOwned>(bytes: &[u8], root: &str) -> Result<T, FieldError> {
    match bytes.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => {}
        Some(_) => return Err(FieldError::new(root, "must be a JSON object")),
        None => return Err(FieldError::new(root, "is empty; expected a JSON object")),
    }
    let de = &mut serde_json::Deserializer::from_slice(bytes);
    let value = serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let top = path == "." || path == "?" || path.is_empty();
        // Truncated JSON is the body's fault, not the field's where it stopped.
        let syntax = e.inner().classify() == serde_json::error::Category::Eof;
        let message = e.inner().to_string();
        let mut field = if top || syntax {
            root.to_string()
        } else {
            path
        };
        // serde reports an unknown field at its parent; name the field itself.
        if let Some(rest) = message.strip_prefix("unknown field `")
            && let Some(name) = rest.split('`').next()
            && !field.ends_with(name)
        {
            field = if top {
                name.to_string()
            } else {
                format!("{field}.{name}")
            };
        }
        FieldError::new(field, message)
    })?;
    Ok(value)
}

/// The error body of every non-2xx answer.
#[derive(Debug, Clone, Serialize, Deserialize, ToSchema)]
pub struct ErrorJson {
    pub error: ErrorDetailJson,
}

#[derive(Debug, Clone, Serialize, Deserialize, ToSchema)]
pub struct ErrorDetailJson {
    /// invalid_argument, not_found, payload_too_large, resource_exhausted, unimplemented,
    /// unsupported_media_type, websocket_required, internal.
    pub code: String,
    pub field: Option<String>,
    pub message: String,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::limits::Limits;
    use crate::request::PlanSource;
    use base64::Engine;
    use nalgebra::Point3;

    fn limits() -> Limits {
        Limits::default()
    }

    #[test]
    fn unknown_fields_are_named_with_their_path() {
        let e =
            parse::<PlanRequestJson>(br#"{"hand_name":"shadow","bogus":1}"#, "body").unwrap_err();
        assert_eq!(e.field, "bogus");
        let e = parse::<PlanRequestJson>(br#"{"options":{"epsilonn":1}}"#, "body").unwrap_err();
        assert_eq!(e.field, "options.epsilonn");
        let e =
            parse::<PlanRequestJson>(br#"{"hints":{"grasp_type":"grab"}}"#, "body").unwrap_err();
        assert_eq!(e.field, "hints.grasp_type");
        let e = parse::<PlanRequestJson>(br#"{"cloud":{"points":[[1,2]]}}"#, "body").unwrap_err();
        assert!(e.field.starts_with("cloud.points"), "{}", e.field);
        let e = parse::<PlanRequestJson>(b"{not json", "body").unwrap_err();
        assert_eq!(e.field, "body");
    }

    #[test]
    fn clouds_as_arrays_or_base64() {
        let r: PlanRequestJson = parse(
            br#"{"cloud":{"points":[[0,0,0],[1,2,3]]},"hand_name":"shadow","hints":{"attention_point":{"x":1,"y":2,"z":3},"viewpoint":[0,0,1]}}"#,
            "body",
        )
        .unwrap();
        let req = plan_request_from_json(r, None, Default::default(), &limits()).unwrap();
        let PlanSource::Cloud(c) = &req.source else {
            panic!()
        };
        assert_eq!(c.points[1], Point3::new(1.0, 2.0, 3.0));
        assert_eq!(req.hints.attention_point, Some(Point3::new(1.0, 2.0, 3.0)));

        let packed = graspd_core::cloud::encode_packed_xyz(&[Point3::new(1.0, 2.0, 3.0)]);
        let b64 = base64::engine::general_purpose::STANDARD.encode(&packed[..11]);
        let body = format!(r#"{{"cloud":{{"points":"{b64}"}},"hand_name":"shadow"}}"#);
        let r: PlanRequestJson = parse(body.as_bytes(), "body").unwrap();
        let e = plan_request_from_json(r, None, Default::default(), &limits()).unwrap_err();
        assert_eq!(e.field(), Some("cloud.points"));
        assert!(e.to_string().contains("byte length 11"));
    }
}
