//! `/v1/hands`: the hand catalog, and registering hands from their robot descriptions.

use super::error::ApiError;
use super::error::body_error;
use super::json::{self, ErrorJson, HandJson, HandsJson, RegisterHandJson, RegisteredHandJson};
use crate::facade::Limits;
use crate::hand_store::{Asset, HandUpload, ModelFormat, StoredOverrides};
use crate::runner::PlanRunner;
use axum::Json;
use axum::body::Bytes;
use axum::extract::{FromRequest, Multipart, Path, Request, State};
use axum::http::StatusCode;
use axum::http::header::CONTENT_TYPE;
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
    let content_type = request
        .headers()
        .get(CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_ascii_lowercase();
    let (upload, replace) = if content_type.starts_with("multipart/form-data") {
        let multipart = Multipart::from_request(request, &())
            .await
            .map_err(|e| body_error(e.status(), e.body_text(), &limits))?;
        from_multipart(multipart, &limits).await?
    } else if content_type.is_empty() || content_type.starts_with("application/json") {
        let bytes = Bytes::from_request(request, &())
            .await
            .map_err(|e| body_error(e.status(), e.body_text(), &limits))?;
        let body: RegisterHandJson = json::parse(&bytes, "body")?;
        json::register_request_from_json(body)?
    } else {
        return Err(ApiError::new(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "unsupported_media_type",
            format!(
                "content type '{content_type}' is not supported; send application/json or multipart/form-data"
            ),
        ));
    };
    let service = runner.service().clone();
    let registered = tokio::task::spawn_blocking(move || service.register_hand(upload, replace))
        .await
        .map_err(|e| {
            ApiError::new(
                StatusCode::INTERNAL_SERVER_ERROR,
                "internal",
                format!("registration task failed: {e}"),
            )
        })??;
    tracing::info!(hand = %registered.description.name, persisted = registered.persisted, "hand registered");
    Ok((StatusCode::CREATED, Json(registered.into())))
}

async fn from_multipart(
    mut multipart: Multipart,
    limits: &Limits,
) -> Result<(HandUpload, bool), ApiError> {
    let mut name: Option<String> = None;
    let mut format: Option<String> = None;
    let mut model: Option<(Option<String>, String)> = None;
    let mut assets = Vec::new();
    let mut overrides = StoredOverrides::default();
    let mut replace = false;
    let text = |field: &str, bytes: &[u8]| -> Result<String, ApiError> {
        String::from_utf8(bytes.to_vec())
            .map_err(|_| ApiError::invalid(FieldError::new(field, "must be UTF-8 text")))
    };
    while let Some(part) = multipart
        .next_field()
        .await
        .map_err(|e| body_error(e.status(), e.body_text(), limits))?
    {
        let part_name = part.name().unwrap_or("").to_string();
        let file_name = part.file_name().map(str::to_string);
        let bytes = part
            .bytes()
            .await
            .map_err(|e| body_error(e.status(), e.body_text(), limits))?;
        match part_name.as_str() {
            "model" if model.is_none() => model = Some((file_name, text("model.text", &bytes)?)),
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
            "name" if name.is_none() => name = Some(text("name", &bytes)?.trim().to_string()),
            "format" if format.is_none() => format = Some(text("model.format", &bytes)?),
            "palm" => overrides.palm = Some(text("model.palm", &bytes)?.trim().to_string()),
            "thumb" => overrides.thumb = Some(text("model.thumb", &bytes)?.trim().to_string()),
            "fingertips" => {
                overrides.fingertips = Some(
                    text("model.fingertips", &bytes)?
                        .split(',')
                        .map(|s| s.trim().to_string())
                        .filter(|s| !s.is_empty())
                        .collect(),
                )
            }
            "replace" => {
                replace = match text("replace", &bytes)?.trim() {
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
            "model" | "name" | "format" => {
                return Err(ApiError::invalid(FieldError::new(
                    part_name.clone(),
                    format!("the part '{part_name}' is given twice"),
                )));
            }
            other => {
                return Err(ApiError::invalid(FieldError::new(
                    "multipart",
                    format!(
                        "unknown part '{}' (expected model, asset, name, format, palm, thumb, fingertips, replace)",
                        other.escape_debug()
                    ),
                )));
            }
        }
    }
    let Some((model_file, model_text)) = model else {
        return Err(ApiError::invalid(FieldError::new(
            "model",
            "the multipart upload has no file part named 'model'",
        )));
    };
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
    overrides.palm = overrides.palm.filter(|s| !s.is_empty());
    overrides.thumb = overrides.thumb.filter(|s| !s.is_empty());
    overrides.fingertips = overrides.fingertips.filter(|v| !v.is_empty());
    Ok((
        HandUpload {
            name: name.unwrap_or_default(),
            format,
            text: model_text,
            assets,
            overrides,
        },
        replace,
    ))
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
