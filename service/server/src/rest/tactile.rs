//! `POST /v1/tactile/analyze`: a whole recorded sequence through a fresh stabilization session,
//! one result per frame (the same results as the `Stabilize` stream for the same frames).
//!
//! The body is one of
//! * `application/json`: `{"session": {…}, "frames": [{"timestamp", "fingers": [{"pdc", "pac",
//!   "tdc", "tac", "electrodes"}]}]}` (the proto's TactileSession and TactileFrame in JSON);
//! * `text/csv`: a `_bio.csv` recording (`timestamp,tdc,tac,pdc,pac1..pac22,ele1..eleN`) of one
//!   finger, with the session in the query string: `finger`, `layout` (built-in, default
//!   `biotac`), `pretared`, `baseline_frames`, `electrode_polarity`, `window_length`, `stride`,
//!   `f0`, `delta_material`, `delta_slip`, `f_min`, `f_max`, `kp`, `ki`, `kd`, `alpha`,
//!   `calibration_gain` — e.g. `curl --data-binary @mat5_1_bio.csv -H 'content-type: text/csv'
//!   'localhost:8080/v1/tactile/analyze?pretared=true'`;
//! * `multipart/form-data`: a file part `bio_csv` (the CSV above) and an optional JSON part
//!   `session` (the full session; default one `biotac` finger with default taring).

use super::body::{Body, Part, read_body};
use super::error::ApiError;
use super::json::{self, AnalyzeCsvQuery, AnalyzeRequestJson, AnalyzeResponseJson, ErrorJson};
use crate::facade::TactileSessionRequest;
use crate::ops::Transport;
use crate::runner::PlanRunner;
use axum::Json;
use axum::extract::{Query, Request, State};
use graspd_core::FieldError;
use graspd_core::tactile::{Frame, Recording};

#[utoipa::path(
    post,
    path = "/v1/tactile/analyze",
    tag = "tactile",
    summary = "Run a whole tactile recording through a fresh stabilization session",
    description = "`application/json` (AnalyzeRequestJson), `text/csv` (a `_bio.csv` recording of one finger, the session in the query parameters) or multipart/form-data (a `bio_csv` file part and an optional `session` JSON part). See the README's Tactile stabilization section.",
    params(AnalyzeCsvQuery, ("x-request-timeout-ms" = Option<u64>, Header, description = "The caller's time budget, whole milliseconds, at least 1; 504 when it passes")),
    request_body(content(
        (AnalyzeRequestJson = "application/json"),
        (String = "text/csv"),
        (AnalyzeUpload = "multipart/form-data"),
    )),
    responses(
        (status = 200, description = "One result per frame", body = AnalyzeResponseJson),
        (status = 400, description = "Bad input, naming the field", body = ErrorJson),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
        (status = 413, description = "The body exceeds max_message_bytes", body = ErrorJson),
        (status = 415, description = "Not JSON, CSV or multipart", body = ErrorJson),
        (status = 503, description = "max_tactile_sessions reached", body = ErrorJson),
        (status = 504, description = "The x-request-timeout-ms deadline passed", body = ErrorJson),
    )
)]
pub async fn analyze(
    State(runner): State<PlanRunner>,
    request: Request,
) -> Result<Json<AnalyzeResponseJson>, ApiError> {
    let limits = *runner.service().limits();
    let uri = request.uri().clone();
    let (session, frames) = match read_body(
        request,
        &limits,
        true,
        "application/json, text/csv (a _bio.csv recording, session in the query) or multipart/form-data (parts bio_csv and session)",
    )
    .await?
    {
        Body::Multipart(parts) => from_multipart(parts)?,
        Body::Csv(bytes) => {
            let query = Query::<AnalyzeCsvQuery>::try_from_uri(&uri)
                .map_err(|e| ApiError::invalid(FieldError::new("query", e.body_text())))?
                .0;
            (
                json::tactile_session_from_json(query.session()),
                frames_from_csv(&bytes, "body")?,
            )
        }
        Body::Json(bytes) => {
            let body: AnalyzeRequestJson = json::parse(&bytes, "body")?;
            (
                json::tactile_session_from_json(body.session),
                body.frames
                    .into_iter()
                    .map(json::tactile_frame_from_json)
                    .collect(),
            )
        }
    };
    let results = runner
        .run_blocking("tactile analysis", Transport::Rest, move |s| {
            s.analyze_tactile(session, &frames)
        })
        .await?;
    Ok(Json(AnalyzeResponseJson {
        frame_count: results.len(),
        frames: results,
    }))
}

fn frames_from_csv(bytes: &[u8], field: &str) -> Result<Vec<Frame>, ApiError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| ApiError::invalid(FieldError::new(field, format!("not UTF-8 text: {e}"))))?;
    let recording = Recording::from_csv(text, None, None)?;
    Ok(recording.frames())
}

fn from_multipart(parts: Vec<Part>) -> Result<(TactileSessionRequest, Vec<Frame>), ApiError> {
    let mut frames = None;
    let mut session = None;
    for part in parts {
        let bytes = &part.bytes;
        match part.name.as_str() {
            "bio_csv" if frames.is_none() => frames = Some(frames_from_csv(bytes, "bio_csv")?),
            "session" if session.is_none() => {
                session = Some(json::parse::<json::TactileSessionJson>(bytes, "session")?)
            }
            "bio_csv" | "session" => return Err(part.twice()),
            _ => {
                return Err(
                    part.unknown("a file part 'bio_csv' and an optional JSON part 'session'")
                );
            }
        }
    }
    let Some(frames) = frames else {
        return Err(ApiError::invalid(FieldError::new(
            "bio_csv",
            "the multipart upload has no file part named 'bio_csv'",
        )));
    };
    let session = session.unwrap_or_else(|| AnalyzeCsvQuery::default().session());
    Ok((json::tactile_session_from_json(session), frames))
}

/// `POST /v1/tactile/analyze` as multipart/form-data.
#[derive(utoipa::ToSchema)]
#[allow(dead_code)]
pub struct AnalyzeUpload {
    /// A `_bio.csv` recording (timestamp,tdc,tac,pdc,pac1..pac22,ele1..eleN) of one finger.
    #[schema(value_type = String, format = Binary)]
    bio_csv: Vec<u8>,
    /// The session JSON; default one biotac finger with default taring.
    session: Option<super::json::TactileSessionJson>,
}
