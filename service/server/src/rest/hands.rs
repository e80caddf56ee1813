//! `/v1/hands`: the hand catalog, and registering hands from their robot descriptions.

use super::body::{Body, Part, read_body};
use super::error::ApiError;
use super::json::{
    self, ErrorJson, HandJson, HandSynergiesJson, HandsJson, RegisterHandJson, RegisteredHandJson,
};
use crate::hand_store::{Asset, HandUpload, ModelFormat, StoredOverrides};
use crate::ops::Transport;
use crate::runner::PlanRunner;
use axum::Json;
use axum::extract::{Path, Request, State};
use axum::http::StatusCode;
use graspd_core::FieldError;

#[utoipa::path(
    get,
    path = "/v1/hands",
    tag = "hands",
    summary = "The hand catalog",
    responses(
        (status = 200, description = "Every hand", body = HandsJson),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
    )
)]
pub async fn list(State(runner): State<PlanRunner>) -> Json<HandsJson> {
    Json(HandsJson {
        hands: runner.service().list_hands(),
    })
}

#[utoipa::path(
    get,
    path = "/v1/hands/{name}",
    tag = "hands",
    summary = "One hand and the grasp types it realises",
    params(("name" = String, Path, description = "The hand's name")),
    responses(
        (status = 200, description = "The hand", body = HandJson),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
        (status = 404, description = "No hand of that name", body = ErrorJson),
    )
)]
pub async fn get(
    State(runner): State<PlanRunner>,
    Path(name): Path<String>,
) -> Result<Json<HandJson>, ApiError> {
    let hand = runner.service().get_hand(&name, "name")?;
    Ok(Json(hand.into()))
}

#[utoipa::path(
    get,
    path = "/v1/hands/{name}/synergies",
    tag = "hands",
    summary = "A hand's posture synergies (dissertation §7.3)",
    description = "The principal components of the hand's grasp postures (Eq 7.3) and each grasp type's centre among them, fitted on the first request to graspd's own plans for the hand over generated objects (0.2–3 s on one core for the shared hands) and kept until the hand is replaced. Only for hands with kinematics (imported or registered from MJCF or URDF).",
    params(("name" = String, Path, description = "The hand's name")),
    responses(
        (status = 200, description = "The posture space", body = HandSynergiesJson),
        (status = 400, description = "The hand has no kinematics, or too few of its plans were feasible", body = ErrorJson),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
        (status = 404, description = "No hand of that name", body = ErrorJson),
    )
)]
pub async fn synergies(
    State(runner): State<PlanRunner>,
    Path(name): Path<String>,
) -> Result<Json<HandSynergiesJson>, ApiError> {
    let synergies = runner
        .run_blocking("posture synergies", Transport::Rest, move |s| {
            s.hand_synergies(&name)
        })
        .await?;
    Ok(Json(synergies.as_ref().into()))
}

/// `POST /v1/hands`: registers a hand from its MJCF or URDF document and files, as JSON
/// (`RegisterHandJson`, assets in base64) or as multipart/form-data: a file part `model` (the
/// document; its file name's extension gives the format unless a `format` part does), one file
/// part `asset` per mesh or included file whose file name is its relative path
/// (`curl -F "asset=@meshes/palm.stl;filename=meshes/palm.stl"`), a text part `name`, and
/// optional text parts `format`, `palm`, `thumb`, `fingertips` (comma-separated) and `replace`
/// (`true`). Answers 201 with the derived description.
#[utoipa::path(
    post,
    path = "/v1/hands",
    tag = "hands",
    summary = "Register a hand from its MJCF or URDF document",
    description = "JSON (RegisterHandJson, files in base64) or multipart/form-data (a `model` file part, one `asset` file part per mesh or included file named by its relative path, text parts `name`, `format`, `palm`, `thumb`, `fingertips`, `replace`). See the README's \"Hands from MJCF/URDF\" section.",
    params(("x-request-timeout-ms" = Option<u64>, Header, description = "The caller's time budget, whole milliseconds, at least 1; 504 when it passes")),
    request_body(content(
        (RegisterHandJson = "application/json"),
        (HandUploadForm = "multipart/form-data"),
    )),
    responses(
        (status = 201, description = "Registered: the derived description", body = RegisteredHandJson),
        (status = 400, description = "Bad input, naming the field", body = ErrorJson),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
        (status = 409, description = "A hand of that name exists (send replace)", body = ErrorJson),
        (status = 413, description = "The body exceeds max_message_bytes", body = ErrorJson),
        (status = 415, description = "Neither JSON nor multipart", body = ErrorJson),
        (status = 504, description = "The x-request-timeout-ms deadline passed", body = ErrorJson),
    )
)]
pub async fn register(
    State(runner): State<PlanRunner>,
    request: Request,
) -> Result<(StatusCode, Json<RegisteredHandJson>), ApiError> {
    let limits = *runner.service().limits();
    let (upload, replace) = match read_body(
        request,
        &limits,
        false,
        "application/json or multipart/form-data",
    )
    .await?
    {
        Body::Multipart(parts) => from_multipart(parts)?,
        Body::Json(bytes) | Body::Csv(bytes) => {
            let body: RegisterHandJson = json::parse(&bytes, "body")?;
            json::register_request_from_json(body)?
        }
    };
    let registered = runner
        .run_blocking("hand import", Transport::Rest, move |s| {
            s.register_hand(upload, replace)
        })
        .await?;
    tracing::info!(hand = %registered.description.name, persisted = registered.persisted, "hand registered");
    Ok((StatusCode::CREATED, Json(registered.into())))
}

fn from_multipart(parts: Vec<Part>) -> Result<(HandUpload, bool), ApiError> {
    let mut name: Option<String> = None;
    let mut format: Option<String> = None;
    let mut model: Option<(Option<String>, String)> = None;
    let mut assets = Vec::new();
    let (mut palm, mut thumb, mut fingertips) = (None, None, Vec::new());
    let mut replace = false;
    let text = |field: &str, bytes: &[u8]| -> Result<String, ApiError> {
        String::from_utf8(bytes.to_vec())
            .map_err(|_| ApiError::invalid(FieldError::new(field, "must be UTF-8 text")))
    };
    for part in parts {
        let bytes = &part.bytes;
        let file_name = part.file_name.clone();
        match part.name.as_str() {
            "model" if model.is_none() => model = Some((file_name, text("model.text", bytes)?)),
            "asset" => {
                let i = assets.len();
                let path = file_name.filter(|f| !f.is_empty()).ok_or_else(|| {
                    ApiError::invalid(FieldError::new(
                        format!("model.assets[{i}].path"),
                        "an asset part needs a file name: its path relative to the model",
                    ))
                })?;
                assets.push(Asset {
                    path,
                    data: bytes.to_vec(),
                });
            }
            "name" if name.is_none() => name = Some(text("name", bytes)?.trim().to_string()),
            "format" if format.is_none() => format = Some(text("model.format", bytes)?),
            "palm" => palm = Some(text("model.palm", bytes)?),
            "thumb" => thumb = Some(text("model.thumb", bytes)?),
            "fingertips" => {
                fingertips = text("model.fingertips", bytes)?
                    .split(',')
                    .map(str::to_string)
                    .collect()
            }
            "replace" => {
                replace = match text("replace", bytes)?.trim() {
                    "true" | "1" => true,
                    "false" | "0" | "" => false,
                    other => {
                        return Err(ApiError::invalid(FieldError::new(
                            "replace",
                            format!("'{}' is not true or false", other.escape_debug()),
                        )));
                    }
                }
            }
            "model" | "name" | "format" => return Err(part.twice()),
            _ => {
                return Err(
                    part.unknown("model, asset, name, format, palm, thumb, fingertips, replace")
                );
            }
        }
    }
    // The form's own rule: without a 'format' part the model file's name gives it.
    let model = match model {
        Some((model_file, model_text)) => {
            let format = match format {
                Some(f) => ModelFormat::parse(&f, "model.format")?,
                None => model_file
                    .as_deref()
                    .and_then(|f| ModelFormat::from_path(std::path::Path::new(f)))
                    .ok_or_else(|| {
                        ApiError::invalid(FieldError::new(
                            "model.format",
                            "give a 'format' part (mjcf or urdf) or a model file named *.xml or *.urdf",
                        ))
                    })?,
            };
            let overrides = StoredOverrides::requested(palm, fingertips, thumb);
            Some((format, model_text, assets, overrides))
        }
        None => None,
    };
    let upload = HandUpload::from_request(name.unwrap_or_default(), false, model)?;
    Ok((upload, replace))
}

/// `POST /v1/hands` as multipart/form-data.
#[derive(utoipa::ToSchema)]
#[allow(dead_code)]
pub struct HandUploadForm {
    /// The MJCF or URDF document; its file name's extension (.xml, .urdf) gives the format
    /// unless a `format` part does.
    #[schema(value_type = String, format = Binary)]
    model: Vec<u8>,
    /// One part per mesh or included file; its file name is its path relative to the model.
    #[schema(value_type = Option<Vec<String>>, format = Binary)]
    asset: Option<Vec<Vec<u8>>>,
    name: Option<String>,
    /// mjcf or urdf.
    format: Option<String>,
    palm: Option<String>,
    thumb: Option<String>,
    /// Comma-separated body names.
    fingertips: Option<String>,
    /// true to replace a registered hand of the same name.
    replace: Option<bool>,
}
