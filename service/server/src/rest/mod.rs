//! The REST transport (axum): routes, one JSON conversion module, typed errors. Thin over the
//! facade.

pub mod error;
pub mod hands;
pub mod json;
pub mod plan;
pub mod stabilize;
pub mod tactile;

use crate::runner::PlanRunner;
use axum::extract::DefaultBodyLimit;
use axum::http::{Method, Uri};
use axum::routing::{get, post};
use axum::{Json, Router};
use error::ApiError;
use serde_json::{Value, json};
use std::future::Future;
use tokio::net::TcpListener;

/// All routes, with the configured body limit.
pub fn router(runner: PlanRunner) -> Router {
    let limit = runner.service().limits().max_message_bytes;
    Router::new()
        .route("/v1/plan", post(plan::plan))
        .route("/v1/hands", get(hands::list).post(hands::register))
        .route("/v1/hands/{name}", get(hands::get))
        .route("/v1/stabilize", get(stabilize::stabilize))
        .route("/v1/tactile/analyze", post(tactile::analyze))
        .route("/healthz", get(health))
        .route("/readyz", get(health))
        .fallback(not_found)
        .layer(DefaultBodyLimit::max(limit))
        .with_state(runner)
}

/// Serves the routes on `listener` until `shutdown` completes, then drains open requests.
pub async fn serve(
    listener: TcpListener,
    runner: PlanRunner,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    axum::serve(listener, router(runner))
        .with_graceful_shutdown(shutdown)
        .await
}

async fn health() -> Json<Value> {
    Json(json!({"status": "ok"}))
}

async fn not_found(method: Method, uri: Uri) -> ApiError {
    ApiError::new(
        axum::http::StatusCode::NOT_FOUND,
        "not_found",
        format!("no route for {method} {}", uri.path()),
    )
}
