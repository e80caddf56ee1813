//! `POST /v1/plan`: a JSON body, or a multipart upload with a `cloud` file part (PCD or PLY), or
//! `color` and `depth` file parts (PNG / JPEG colour, 16-bit PNG depth) of an RGB-D frame, and a
//! `request` part holding the same JSON without the file's data.
//!
//! `?format=png` answers with the overlay image (`image/png`) instead of the JSON plan (RGB-D
//! input only), `?format=glb` with the plan as a binary glTF scene (`model/gltf-binary`,
//! `graspd_core::plan_scene`); `?format=json` is the default.

use super::body::{Body, Part, after_reading_body, read_body};
use super::error::ApiError;
use super::json::{self, ErrorJson, PlanRequestJson, PlanResponseJson};
use crate::facade::{Limits, PlanRequest, PlanSource};
use crate::ops::Transport;
use crate::runner::PlanRunner;
use axum::Json;
use axum::extract::{Query, Request, State};
use axum::http::header::CONTENT_TYPE;
use axum::response::{IntoResponse, Response};
use graspd_core::FieldError;
use graspd_core::cloud::PointCloud;
use graspd_core::cloud::io::read_cloud_file;
use serde::Deserialize;

/// The query of `POST /v1/plan`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanQuery {
    /// `json` (default), `png` (the overlay) or `glb` (the 3D scene).
    #[serde(default)]
    format: Option<String>,
}

#[utoipa::path(
    post,
    path = "/v1/plan",
    tag = "plan",
    summary = "Plan a grasp",
    description = "A JSON body (PlanRequestJson: a cloud or an RGB-D frame, a hand, options, hints), or multipart/form-data with a `cloud` file part (PCD or PLY) or `color` and `depth` file parts (PNG/JPEG colour, 16-bit PNG depth), and a `request` JSON part. See the README's API and Perception sections.",
    params(
        ("format" = Option<String>, Query, description = "`json` (default): the plan as JSON; `png`: the overlay picture (RGB-D input only); `glb`: the plan as a binary glTF scene (the points, support plane, contacts, opposition and, for a hand with kinematics, the hand posed at the pre-grasp, grasp and squeeze)"),
        ("x-request-timeout-ms" = Option<u64>, Header, description = "The caller's time budget, whole milliseconds, at least 1; 504 when it passes"),
    ),
    request_body(content(
        (PlanRequestJson = "application/json"),
        (PlanUpload = "multipart/form-data"),
    )),
    responses(
        (status = 200, description = "The plan (JSON), or with `format=png` the overlay picture, with `format=glb` the 3D scene", content(
            (PlanResponseJson = "application/json"),
            ("image/png"),
            ("model/gltf-binary"),
        )),
        (status = 400, description = "Bad input, naming the field", body = ErrorJson),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
        (status = 404, description = "Unknown hand", body = ErrorJson),
        (status = 413, description = "The body or cloud exceeds the configured limits", body = ErrorJson),
        (status = 415, description = "Neither JSON nor multipart", body = ErrorJson),
        (status = 503, description = "Overloaded or out of plan slots (Retry-After)", body = ErrorJson),
        (status = 504, description = "The x-request-timeout-ms deadline passed", body = ErrorJson),
    )
)]
pub async fn plan(
    State(runner): State<PlanRunner>,
    query: Result<Query<PlanQuery>, axum::extract::rejection::QueryRejection>,
    request: Request,
) -> Result<Response, ApiError> {
    let limits = *runner.service().limits();
    let format = query
        .map_err(|e| ApiError::invalid(FieldError::new("query", e.body_text())))
        .and_then(|q| match q.0.format.as_deref() {
            None | Some("json") => Ok(Format::Json),
            Some("png") => Ok(Format::Png),
            Some("glb") => Ok(Format::Glb),
            Some(other) => Err(ApiError::invalid(FieldError::new(
                "format",
                format!(
                    "unknown format '{}' (json, png or glb)",
                    other.escape_debug()
                ),
            ))),
        });
    let format = match format {
        Ok(f) => f,
        Err(e) => return Err(after_reading_body(request, &limits, e).await),
    };
    let plan_request = match read_body(
        request,
        &limits,
        false,
        "application/json (curl: -H 'content-type: application/json') or multipart/form-data",
    )
    .await?
    {
        Body::Multipart(parts) => from_multipart(parts, &limits)?,
        Body::Json(bytes) | Body::Csv(bytes) => {
            let body: PlanRequestJson = json::parse(&bytes, "body")?;
            json::plan_request_from_json(body, None, Default::default(), &limits)?
        }
    };
    let mut plan_request = plan_request;
    match format {
        Format::Png => {
            if !matches!(plan_request.source, PlanSource::Rgbd(_)) {
                return Err(ApiError::invalid(FieldError::new(
                    "format",
                    "format=png draws on the colour image: it needs rgbd input",
                )));
            }
            plan_request.output.overlay = true;
        }
        Format::Glb => plan_request.output.scene_glb = true,
        Format::Json => {}
    }
    let plan = runner.plan(plan_request, Transport::Rest).await?;
    match format {
        Format::Png => {
            let bytes = plan
                .perception
                .and_then(|p| p.overlay_png)
                .unwrap_or_default();
            Ok(([(CONTENT_TYPE, "image/png")], bytes).into_response())
        }
        Format::Glb => Ok((
            [(CONTENT_TYPE, "model/gltf-binary")],
            plan.scene_glb.unwrap_or_default(),
        )
            .into_response()),
        Format::Json => Ok(Json(PlanResponseJson::from(&plan)).into_response()),
    }
}

/// What `POST /v1/plan` answers with (`?format=`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Json,
    Png,
    Glb,
}

fn from_multipart(parts: Vec<Part>, limits: &Limits) -> Result<PlanRequest, ApiError> {
    let mut cloud: Option<PointCloud> = None;
    let mut request: Option<PlanRequestJson> = None;
    let mut images = json::ImageParts::default();
    for part in parts {
        let bytes = &part.bytes;
        match part.name.as_str() {
            "cloud" if cloud.is_none() => {
                if bytes.len() / 12 > limits.max_points.saturating_mul(64) {
                    return Err(ApiError::too_large(FieldError::new(
                        "cloud.file",
                        "the file is too large for the configured max_points",
                    )));
                }
                cloud = Some(read_cloud_file(bytes)?);
            }
            "request" if request.is_none() => request = Some(json::parse(bytes, "request")?),
            "color" if images.color.is_none() => images.color = Some(bytes.to_vec()),
            "depth" if images.depth.is_none() => images.depth = Some(bytes.to_vec()),
            "cloud" | "request" | "color" | "depth" => return Err(part.twice()),
            _ => {
                return Err(part.unknown(
                    "a file part 'cloud', or 'color' and 'depth', and a JSON part 'request'",
                ));
            }
        }
    }
    if cloud.is_none() && images.color.is_none() && images.depth.is_none() {
        return Err(ApiError::invalid(FieldError::new(
            "cloud",
            "the multipart upload has no file part named 'cloud' (nor 'color' and 'depth')",
        )));
    }
    Ok(json::plan_request_from_json(
        request.unwrap_or_default(),
        cloud,
        images,
        limits,
    )?)
}

/// `POST /v1/plan` as multipart/form-data: a `cloud` file, or `color` and `depth` files, and a
/// `request` part (PlanRequestJson without the file's data).
#[derive(utoipa::ToSchema)]
#[allow(dead_code)]
pub struct PlanUpload {
    /// PCD (ascii/binary) or PLY (ascii/binary little-endian) point cloud.
    #[schema(value_type = Option<String>, format = Binary)]
    cloud: Option<Vec<u8>>,
    /// The colour image (PNG or JPEG) of an RGB-D frame.
    #[schema(value_type = Option<String>, format = Binary)]
    color: Option<Vec<u8>>,
    /// The depth image (16-bit PNG) of an RGB-D frame.
    #[schema(value_type = Option<String>, format = Binary)]
    depth: Option<Vec<u8>>,
    /// The request JSON (PlanRequestJson) without the file's data; RGB-D needs at least
    /// `rgbd.intrinsics`.
    request: Option<PlanRequestJson>,
}
