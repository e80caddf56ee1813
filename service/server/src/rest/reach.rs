//! `POST /v1/reach`: a reaching trajectory from the hand's pose to a grasp (the proto's
//! PlanReachRequest in JSON; README, "Reaching"), e.g.
//! `curl -d '{"start": {"position": [0,0,0.4], "orientation": {"x":0,"y":0,"z":0,"w":1}},
//! "goal": {"position": [0.5,0.2,0.1], "orientation": {"x":1,"y":0,"z":0,"w":0}},
//! "approach": [0,0,-1], "support_plane": {"normal": [0,0,1], "offset": 0}}'
//! localhost:8080/v1/reach`.

use super::body::{Body, read_body};
use super::error::ApiError;
use super::json::{self, ErrorJson, ReachRequestJson, ReachResponseJson};
use crate::ops::Transport;
use crate::runner::PlanRunner;
use axum::Json;
use axum::extract::{Request, State};

#[utoipa::path(
    post,
    path = "/v1/reach",
    tag = "plan",
    summary = "Plan a reaching trajectory to a grasp",
    description = "From the hand's `start` pose to the grasp pose `goal`, the last `pregrasp_distance` along `approach`: the impedance model of the dissertation's §3.3 driven by a forcing term learned from demonstrations (built-in: a minimum-jerk reach), corrected by iLQR inside MPC to keep `options.min_clearance` between a sphere of `hand_radius` and each obstacle box, and above the support plane. Samples every `options.time_step` s. See the README's Reaching section.",
    params(("x-request-timeout-ms" = Option<u64>, Header, description = "The caller's time budget, whole milliseconds, at least 1; 504 when it passes")),
    request_body(content((ReachRequestJson = "application/json"))),
    responses(
        (status = 200, description = "The trajectory", body = ReachResponseJson),
        (status = 400, description = "Bad input, or an obstacle no reach gets round, naming the field", body = ErrorJson),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
        (status = 413, description = "The body exceeds max_message_bytes", body = ErrorJson),
        (status = 415, description = "Not JSON", body = ErrorJson),
        (status = 503, description = "Overloaded (Retry-After)", body = ErrorJson),
        (status = 504, description = "The x-request-timeout-ms deadline passed", body = ErrorJson),
    )
)]
pub async fn reach(
    State(runner): State<PlanRunner>,
    request: Request,
) -> Result<Json<ReachResponseJson>, ApiError> {
    let limits = *runner.service().limits();
    let bytes = match read_body(
        request,
        &limits,
        false,
        "application/json (curl: -H 'content-type: application/json')",
    )
    .await?
    {
        Body::Json(bytes) | Body::Csv(bytes) => bytes,
        Body::Multipart(_) => {
            return Err(ApiError::new(
                axum::http::StatusCode::UNSUPPORTED_MEDIA_TYPE,
                "unsupported_media_type",
                "send application/json",
            ));
        }
    };
    let body: ReachRequestJson = json::parse(&bytes, "body")?;
    let request = json::reach_request_from_json(body).map_err(ApiError::invalid)?;
    let (trajectory, ms) = runner
        .run_blocking("reach", Transport::Rest, move |s| s.plan_reach(request))
        .await?;
    Ok(Json(json::trajectory_to_json(&trajectory, ms)))
}
