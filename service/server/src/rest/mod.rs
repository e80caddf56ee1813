//! The REST transport (axum): routes and typed errors, thin over the facade; the bodies and
//! their conversions are `graspd-api`'s ([`json`], [`schemas`]).

pub mod body;
pub mod calibrations;
pub mod console;
mod drain;
pub mod error;
pub mod hands;
pub mod openapi;
pub mod plan;
pub mod reach;
pub mod stabilize;
pub mod tactile;

pub use graspd_api::{json, schemas};

use crate::ops::edge::{EdgeHooks, EdgeLayer};
use crate::ops::{Ops, Transport, metrics};
use crate::runner::PlanRunner;
use crate::tls::Listening;
use axum::extract::{DefaultBodyLimit, FromRef, MatchedPath, State};
use axum::http::header::CONTENT_TYPE;
use axum::http::{HeaderMap, Method, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use error::ApiError;
use serde_json::{Value, json};
use std::borrow::Cow;
use std::future::Future;
use std::time::Duration;

/// The optional request header giving the caller's time budget, milliseconds.
pub const REQUEST_TIMEOUT_HEADER: &str = "x-request-timeout-ms";

/// The REST routes' state: the runner (most handlers) and the operations.
#[derive(Debug, Clone)]
pub struct AppState {
    pub runner: PlanRunner,
    pub ops: Ops,
}

impl FromRef<AppState> for PlanRunner {
    fn from_ref(state: &AppState) -> Self {
        state.runner.clone()
    }
}

/// All routes, with the configured body limit, behind the edge layer.
pub fn router(runner: PlanRunner, ops: Ops) -> Router {
    let limit = runner.service().limits().max_message_bytes;
    let edge = EdgeLayer::new(EDGE_HOOKS, &ops);
    Router::new()
        .route("/v1/plan", post(plan::plan))
        .route("/v1/reach", post(reach::reach))
        .route("/v1/hands", get(hands::list).post(hands::register))
        .route("/v1/hands/{name}", get(hands::get))
        .route("/v1/hands/{name}/synergies", get(hands::synergies))
        .route("/v1/stabilize", get(stabilize::stabilize))
        .route("/v1/tactile/analyze", post(tactile::analyze))
        .route(
            "/v1/tactile/calibrations",
            get(calibrations::list).post(calibrations::calibrate),
        )
        .route(
            "/v1/tactile/calibrations/{name}",
            get(calibrations::get).delete(calibrations::delete),
        )
        .route("/healthz", get(health))
        .route("/readyz", get(ready))
        .route("/metrics", get(metrics_text))
        .route("/openapi.json", get(openapi::openapi_json))
        .route("/", get(console::index))
        .route("/console/{*path}", get(console::file))
        .fallback(not_found)
        .layer(DefaultBodyLimit::max(limit))
        .layer(edge)
        .layer(drain::DrainLayer::new(limit))
        .with_state(AppState { runner, ops })
}

/// Serves the routes on `listener` until `shutdown` completes, then drains open requests.
/// With `tls`, serves HTTPS (handshakes in [`TlsListener`]); WebSocket upgrades work the same.
pub async fn serve(
    listening: Listening,
    runner: PlanRunner,
    ops: Ops,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let app = router(runner, ops);
    match listening {
        Listening::Plain(listener) => {
            axum::serve(listener, app)
                .with_graceful_shutdown(shutdown)
                .await
        }
        Listening::Tls(listener) => {
            axum::serve(listener, app)
                .with_graceful_shutdown(shutdown)
                .await
        }
    }
}

/// Paths answered without a token: the probes, the metrics, the OpenAPI document and the web
/// console (its page and files hold no data; its API calls carry the token).
fn open(path: &str) -> bool {
    matches!(
        path,
        "/healthz" | "/readyz" | "/metrics" | "/openapi.json" | "/"
    ) || path.starts_with("/console/")
}

/// `METHOD /route/{template}`; `unmatched` for the fallback.
fn route(parts: &axum::http::request::Parts) -> Cow<'static, str> {
    let Some(path) = parts.extensions.get::<MatchedPath>() else {
        return Cow::Borrowed("unmatched");
    };
    let method = match parts.method {
        Method::GET => "GET",
        Method::POST => "POST",
        Method::PUT => "PUT",
        Method::DELETE => "DELETE",
        Method::PATCH => "PATCH",
        Method::HEAD => "HEAD",
        Method::OPTIONS => "OPTIONS",
        _ => "OTHER",
    };
    Cow::Owned(format!("{method} {}", path.as_str()))
}

/// `x-request-timeout-ms`: a whole number of milliseconds, at least 1.
fn timeout(headers: &HeaderMap) -> Result<Option<Duration>, String> {
    let Some(value) = headers.get(REQUEST_TIMEOUT_HEADER) else {
        return Ok(None);
    };
    value
        .to_str()
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .filter(|&ms| ms >= 1)
        .map(|ms| Some(Duration::from_millis(ms)))
        .ok_or_else(|| {
            format!("{REQUEST_TIMEOUT_HEADER} must be a whole number of milliseconds, at least 1")
        })
}

/// How the REST transport plugs into the edge layer.
pub const EDGE_HOOKS: EdgeHooks = EdgeHooks {
    transport: Transport::Rest,
    route,
    open,
    timeout,
    refusal: error::refusal,
    code: |parts| Some(error::code_of(parts.status)),
    trailer_code: |_| None,
    abandoned_code: "499",
};

/// Liveness: the process answers.
#[utoipa::path(
    get,
    path = "/healthz",
    tag = "operations",
    summary = "Liveness",
    security(()),
    responses((status = 200, description = "The process answers: {\"status\": \"ok\"}", body = Object))
)]
async fn health() -> Json<Value> {
    Json(json!({"status": "ok"}))
}

/// Readiness: 200 once the hands and models are loaded and both servers listen, 503 while
/// starting or draining.
#[utoipa::path(
    get,
    path = "/readyz",
    tag = "operations",
    summary = "Readiness",
    security(()),
    responses(
        (status = 200, description = "Ready: {\"status\": \"ready\"}", body = Object),
        (status = 503, description = "Starting or draining: {\"status\": \"starting\"|\"draining\"}", body = Object),
    )
)]
async fn ready(State(state): State<AppState>) -> Response {
    readiness(&state.ops)
}

/// The readiness answer of `/readyz` on both the REST and the probe port.
fn readiness(ops: &Ops) -> Response {
    let status = if ops.readiness.is_ready() {
        StatusCode::OK
    } else {
        StatusCode::SERVICE_UNAVAILABLE
    };
    (
        status,
        Json(json!({"status": ops.readiness.state().name()})),
    )
        .into_response()
}

/// The probe port (`--probe-addr`): plain HTTP, `GET /healthz` and `/readyz` only, no token —
/// for probes that cannot speak the other ports' TLS (a kubelet with mutual TLS on).
pub async fn serve_probes(
    listener: tokio::net::TcpListener,
    ops: Ops,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let app = Router::new()
        .route("/healthz", get(health))
        .route(
            "/readyz",
            get(|State(ops): State<Ops>| async move { readiness(&ops) }),
        )
        .with_state(ops);
    axum::serve(listener, app)
        .with_graceful_shutdown(shutdown)
        .await
}

/// The Prometheus exposition (OpenMetrics text).
#[utoipa::path(
    get,
    path = "/metrics",
    tag = "operations",
    summary = "Prometheus metrics",
    security(()),
    responses((status = 200, description = "The OpenMetrics text exposition (prefix graspd_; see the README's API section)", content_type = "application/openmetrics-text", body = String))
)]
async fn metrics_text(State(state): State<AppState>) -> Response {
    let text = state.ops.metrics.render(
        state.runner.service().tactile_sessions_open(),
        state.ops.readiness.is_ready(),
    );
    ([(CONTENT_TYPE, metrics::CONTENT_TYPE)], text).into_response()
}

async fn not_found(method: Method, uri: Uri) -> ApiError {
    ApiError::new(
        axum::http::StatusCode::NOT_FOUND,
        "not_found",
        format!("no route for {method} {}", uri.path()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::facade::{GraspService, Limits};
    use crate::ops::ReadyState;
    use axum::body::Body;
    use axum::http::Request;
    use tower::ServiceExt;

    #[tokio::test]
    async fn readiness_follows_the_flag_and_liveness_does_not() {
        let ops = Ops::default();
        let runner = PlanRunner::new(
            GraspService::builtin(Limits::default()),
            ops.metrics.clone(),
        );
        let app = router(runner, ops.clone());
        let get = |path: &str| {
            app.clone()
                .oneshot(Request::get(path).body(Body::empty()).unwrap())
        };
        for (state, expected) in [
            (ReadyState::Starting, 503),
            (ReadyState::Ready, 200),
            (ReadyState::Draining, 503),
        ] {
            ops.readiness.set(state);
            let response = get("/readyz").await.unwrap();
            assert_eq!(response.status(), expected, "{state:?}");
            assert!(response.headers().contains_key("x-request-id"));
            assert_eq!(get("/healthz").await.unwrap().status(), 200, "{state:?}");
        }
    }
}
