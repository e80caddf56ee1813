//! `POST /v1/plan`: a JSON body, or a multipart upload with a `cloud` file part (PCD or PLY) and
//! an optional `request` part holding the same JSON without `cloud`.

use super::error::ApiError;
use super::json::{self, PlanRequestJson, PlanResponseJson};
use crate::facade::{Limits, PlanRequest};
use crate::runner::PlanRunner;
use axum::Json;
use axum::body::Bytes;
use axum::extract::{FromRequest, Multipart, Request, State};
use axum::http::StatusCode;
use axum::http::header::CONTENT_TYPE;
use graspd_core::FieldError;
use graspd_core::cloud::PointCloud;
use graspd_core::cloud::io::read_cloud_file;

pub async fn plan(
    State(runner): State<PlanRunner>,
    request: Request,
) -> Result<Json<PlanResponseJson>, ApiError> {
    let limits = *runner.service().limits();
    let content_type = request
        .headers()
        .get(CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_ascii_lowercase();
    let plan_request = if content_type.starts_with("multipart/form-data") {
        let multipart = Multipart::from_request(request, &())
            .await
            .map_err(|e| body_error(e.status(), e.body_text(), &limits))?;
        from_multipart(multipart, &limits).await?
    } else if content_type.is_empty() || content_type.starts_with("application/json") {
        let bytes = Bytes::from_request(request, &())
            .await
            .map_err(|e| body_error(e.status(), e.body_text(), &limits))?;
        let body: PlanRequestJson = json::parse(&bytes, "body")?;
        json::plan_request_from_json(body, None, &limits)?
    } else {
        return Err(ApiError::new(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "unsupported_media_type",
            format!(
                "content type '{content_type}' is not supported; send application/json (curl: -H 'content-type: application/json') or multipart/form-data"
            ),
        ));
    };
    let plan = runner.plan(plan_request, "rest").await?;
    Ok(Json(PlanResponseJson::from(&plan)))
}

/// A body that could not be read: over the limit (413) or broken (400).
pub(crate) fn body_error(status: StatusCode, text: String, limits: &Limits) -> ApiError {
    if status == StatusCode::PAYLOAD_TOO_LARGE {
        ApiError::too_large(FieldError::new(
            "body",
            format!(
                "the request body exceeds the configured limit of {} bytes (max_message_bytes)",
                limits.max_message_bytes
            ),
        ))
    } else {
        ApiError::invalid(FieldError::new("body", text))
    }
}

async fn from_multipart(
    mut multipart: Multipart,
    limits: &Limits,
) -> Result<PlanRequest, ApiError> {
    let mut cloud: Option<PointCloud> = None;
    let mut request: Option<PlanRequestJson> = None;
    while let Some(field) = multipart
        .next_field()
        .await
        .map_err(|e| body_error(e.status(), e.body_text(), limits))?
    {
        let name = field.name().unwrap_or("").to_string();
        let bytes = field
            .bytes()
            .await
            .map_err(|e| body_error(e.status(), e.body_text(), limits))?;
        match name.as_str() {
            "cloud" if cloud.is_none() => {
                if bytes.len() / 12 > limits.max_points.saturating_mul(64) {
                    return Err(ApiError::too_large(FieldError::new(
                        "cloud.file",
                        "the file is too large for the configured max_points",
                    )));
                }
                cloud = Some(read_cloud_file(&bytes)?);
            }
            "request" if request.is_none() => request = Some(json::parse(&bytes, "request")?),
            "cloud" | "request" => {
                return Err(ApiError::invalid(FieldError::new(
                    name.clone(),
                    format!("the part '{name}' is given twice"),
                )));
            }
            other => {
                return Err(ApiError::invalid(FieldError::new(
                    "multipart",
                    format!(
                        "unknown part '{}' (expected a file part 'cloud' and an optional JSON part 'request')",
                        other.escape_debug()
                    ),
                )));
            }
        }
    }
    let Some(cloud) = cloud else {
        return Err(ApiError::invalid(FieldError::new(
            "cloud",
            "the multipart upload has no file part named 'cloud'",
        )));
    };
    Ok(json::plan_request_from_json(
        request.unwrap_or_default(),
        Some(cloud),
        limits,
    )?)
}
