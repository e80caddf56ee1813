//! `GET /v1/stabilize`: the `Stabilize` stream as a WebSocket with the same messages in JSON.
//!
//! Client → server, one text message each: first `{"session": {…}}` (the analyze endpoint's
//! session JSON), then `{"frame": {"timestamp", "fingers": [{"pdc", "pac", "tdc", "tac",
//! "electrodes"}]}}`. Server → client: exactly one `{"frame_index", "timestamp", "fingers":
//! [{…}]}` per frame (the fields of an analyze result). An error — a bad session or frame, or
//! `max_tactile_sessions` reached — is sent as `{"error": {"code", "field", "message"}}`, then
//! the socket is closed (1008 policy violation; 1013 try again later for the session limit).
//!
//! One message is handled at a time: the next is read only after the answer has been written,
//! so a slow reader stops the reading (TCP flow control then stops the client) and memory stays
//! bounded. When the socket closes or fails, the session and its slot are dropped at once.

use super::error::ApiError;
use super::json::{self, ErrorDetailJson, ErrorJson, SetpointJson, StabilizeMessageJson};
use crate::facade::{GraspService, TactileSession};
use crate::runner::PlanRunner;
use axum::extract::State;
use axum::extract::ws::rejection::WebSocketUpgradeRejection;
use axum::extract::ws::{CloseFrame, Message, WebSocket, WebSocketUpgrade, close_code};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use graspd_core::FieldError;
use tracing::Instrument;

#[utoipa::path(
    get,
    path = "/v1/stabilize",
    tag = "tactile",
    summary = "Tactile stabilization as a WebSocket",
    description = "A WebSocket (`ws://…/v1/stabilize`) carrying the `Stabilize` stream in JSON text messages. Client → server: first `{\"session\": {…}}` (TactileSessionJson, as in /v1/tactile/analyze), then one `{\"frame\": {\"timestamp\", \"fingers\": [{\"pdc\", \"pac\", \"tdc\", \"tac\", \"electrodes\"}]}}` per reading (StabilizeMessageJson). Server → client: exactly one setpoint per frame, `{\"frame_index\", \"timestamp\", \"fingers\": [{…}]}` (the 0-based frame index and the fields of a FrameResult). An error — a bad session or frame, or max_tactile_sessions reached — is sent as the error body (ErrorJson), then the socket closes with 1008 (policy violation) or 1013 (try again later, the session limit). One message is handled at a time.",
    responses(
        (status = 101, description = "Switching protocols: the WebSocket is open"),
        (status = 400, description = "Not a WebSocket upgrade (code websocket_required)", body = ErrorJson),
        (status = 401, description = "Missing or wrong bearer token (only when tokens are configured)", body = ErrorJson),
    )
)]
pub async fn stabilize(
    State(runner): State<PlanRunner>,
    ws: Result<WebSocketUpgrade, WebSocketUpgradeRejection>,
) -> Response {
    let ws = match ws {
        Ok(ws) => ws,
        Err(e) => {
            return ApiError::new(
                e.status(),
                "websocket_required",
                format!(
                    "{}: GET /v1/stabilize is a WebSocket (ws://…/v1/stabilize); for a whole recording use POST /v1/tactile/analyze",
                    e.body_text()
                ),
            )
            .into_response();
        }
    };
    let limit = runner.service().limits().max_message_bytes;
    let service = runner.service().clone();
    // The session outlives this handler on its own task: it keeps the request's span, so its
    // log lines carry the request id like every other request's.
    let span = tracing::Span::current();
    ws.max_message_size(limit)
        .on_upgrade(move |socket| run(socket, service).instrument(span))
}

async fn run(mut socket: WebSocket, service: GraspService) {
    tracing::debug!("tactile WebSocket opened");
    let mut session: Option<TactileSession> = None;
    while let Some(Ok(message)) = socket.recv().await {
        let answer = match &message {
            Message::Text(t) => handle(&service, &mut session, t.as_bytes()),
            Message::Binary(b) => handle(&service, &mut session, b),
            Message::Close(_) => break,
            Message::Ping(_) | Message::Pong(_) => continue,
        };
        match answer {
            Ok(None) => {}
            Ok(Some(text)) => {
                if socket.send(Message::Text(text.into())).await.is_err() {
                    break;
                }
            }
            Err(e) => {
                tracing::info!(
                    code = e.code,
                    field = e.field.as_deref().unwrap_or(""),
                    error = %e.message,
                    "tactile session refused a message"
                );
                let code = if e.status == StatusCode::SERVICE_UNAVAILABLE {
                    close_code::AGAIN
                } else {
                    close_code::POLICY
                };
                let mut reason = match &e.field {
                    Some(f) => format!("{f}: {}", e.message),
                    None => e.message.clone(),
                };
                // A close reason is at most 123 bytes; the full error is in the message before.
                while reason.len() > 120 {
                    reason.pop();
                }
                let body = ErrorJson {
                    error: ErrorDetailJson {
                        code: e.code.into(),
                        field: e.field,
                        message: e.message,
                    },
                };
                let text = serde_json::to_string(&body).unwrap_or_default();
                if socket.send(Message::Text(text.into())).await.is_ok() {
                    let _ = socket
                        .send(Message::Close(Some(CloseFrame {
                            code,
                            reason: reason.into(),
                        })))
                        .await;
                }
                break;
            }
        }
    }
    tracing::debug!(
        frames = session.as_ref().map_or(0, TactileSession::frames),
        "tactile session closed"
    );
    drop(session);
}

/// One client message: opens the session (no answer) or steps it (one answer).
fn handle(
    service: &GraspService,
    session: &mut Option<TactileSession>,
    bytes: &[u8],
) -> Result<Option<String>, ApiError> {
    let m: StabilizeMessageJson = json::parse(bytes, "message")?;
    match (session.as_mut(), m.session, m.frame) {
        (_, Some(_), Some(_)) => {
            Err(FieldError::new("message", "give either session or frame, not both").into())
        }
        (None, Some(s), None) => {
            let opened = service.open_tactile_session(json::tactile_session_from_json(s))?;
            tracing::debug!(
                fingers = opened.config().fingers.len(),
                "tactile session opened"
            );
            *session = Some(opened);
            Ok(None)
        }
        (None, None, _) => Err(FieldError::new(
            "session",
            "the first message must open the session ({\"session\": {…}}); frames follow it",
        )
        .into()),
        (Some(_), Some(_), None) => Err(FieldError::new(
            "session",
            "the session is already open; every later message carries a frame",
        )
        .into()),
        (Some(_), None, None) => Err(FieldError::new("frame", "is required").into()),
        (Some(s), None, Some(f)) => {
            let frame_index = s.frames();
            let result = s.step(&json::tactile_frame_from_json(f))?;
            let text = serde_json::to_string(&SetpointJson {
                frame_index,
                result,
            })
            .map_err(|e| {
                ApiError::new(
                    StatusCode::INTERNAL_SERVER_ERROR,
                    "internal",
                    format!("cannot encode the answer: {e}"),
                )
            })?;
            Ok(Some(text))
        }
    }
}
