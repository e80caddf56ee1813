//! `/v1/tactile/calibrations`: fit a detector on labelled recordings (issue 16), list, get and
//! delete calibrations. A session names one as `"detector": {"calibration": "NAME"}`.

use super::body::{Body, read_body};
use super::error::ApiError;
use super::json::{self, CalibrateJson, CalibrationJson, CalibrationsJson, ErrorJson};
use crate::facade::ServiceError;
use crate::ops::Transport;
use crate::runner::PlanRunner;
use axum::Json;
use axum::extract::{Path, Request, State};
use axum::http::StatusCode;

#[utoipa::path(
    post,
    path = "/v1/tactile/calibrations",
    tag = "tactile",
    summary = "Fit a calibration on labelled tactile recordings",
    description = "A JSON body (CalibrateJson): the name, the recordings as `_bio.csv` texts with their material (paper, foam, plastic or metal, optionally `/kind`) and optionally the arm's `_cw.csv` and `_cv.csv` texts (frame events), the window and the taring. Fitted in the server (a linear discriminant on the detector's hand features) and stored under its name; 201 with its description.",
    request_body(content((CalibrateJson = "application/json"))),
    responses(
        (status = 201, description = "Fitted and stored", body = CalibrationJson),
        (status = 400, description = "Bad input, naming the field (unknown material, one class only, mismatched electrode counts, non-finite values, a bad CSV)", body = ErrorJson),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
        (status = 409, description = "A calibration of that name exists (set replace)", body = ErrorJson),
        (status = 413, description = "The body exceeds max_message_bytes", body = ErrorJson),
        (status = 415, description = "Not JSON", body = ErrorJson),
    )
)]
pub async fn calibrate(
    State(runner): State<PlanRunner>,
    request: Request,
) -> Result<(StatusCode, Json<CalibrationJson>), ApiError> {
    let limits = *runner.service().limits();
    let body = match read_body(request, &limits, false, "application/json (CalibrateJson)").await? {
        Body::Json(bytes) => json::parse::<CalibrateJson>(&bytes, "body")?,
        _ => {
            return Err(ApiError::new(
                StatusCode::UNSUPPORTED_MEDIA_TYPE,
                "unsupported_media_type",
                "a calibration is an application/json body (CalibrateJson)",
            ));
        }
    };
    let info = runner
        .run_blocking("calibration", Transport::Rest, move |s| {
            s.calibrate(body.into())
        })
        .await?;
    tracing::info!(calibration = %info.calibration.name, persisted = info.persisted, "calibration fitted");
    Ok((StatusCode::CREATED, Json((&info).into())))
}

#[utoipa::path(
    get,
    path = "/v1/tactile/calibrations",
    tag = "tactile",
    summary = "The calibrations",
    responses(
        (status = 200, description = "Every calibration", body = CalibrationsJson),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
    )
)]
pub async fn list(State(runner): State<PlanRunner>) -> Json<CalibrationsJson> {
    Json(CalibrationsJson {
        calibrations: runner
            .service()
            .list_calibrations()
            .iter()
            .map(Into::into)
            .collect(),
    })
}

#[utoipa::path(
    get,
    path = "/v1/tactile/calibrations/{name}",
    tag = "tactile",
    summary = "One calibration",
    params(("name" = String, Path, description = "The calibration's name")),
    responses(
        (status = 200, description = "The calibration", body = CalibrationJson),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
        (status = 404, description = "No calibration of that name", body = ErrorJson),
    )
)]
pub async fn get(
    State(runner): State<PlanRunner>,
    Path(name): Path<String>,
) -> Result<Json<CalibrationJson>, ApiError> {
    Ok(Json((&runner.service().get_calibration(&name)?).into()))
}

#[utoipa::path(
    delete,
    path = "/v1/tactile/calibrations/{name}",
    tag = "tactile",
    summary = "Delete a calibration (sessions using it keep it)",
    params(("name" = String, Path, description = "The calibration's name")),
    responses(
        (status = 204, description = "Deleted"),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
        (status = 404, description = "No calibration of that name", body = ErrorJson),
    )
)]
pub async fn delete(
    State(runner): State<PlanRunner>,
    Path(name): Path<String>,
) -> Result<StatusCode, ApiError> {
    let service = runner.service().clone();
    tokio::task::spawn_blocking(move || service.delete_calibration(&name))
        .await
        .unwrap_or_else(|e| Err(ServiceError::Internal(format!("delete task failed: {e}"))))?;
    Ok(StatusCode::NO_CONTENT)
}
