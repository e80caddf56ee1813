//! `/v1/hands`: the hand catalog.

use super::error::ApiError;
use super::json::{HandJson, HandsJson};
use crate::runner::PlanRunner;
use axum::Json;
use axum::extract::{Path, State};

pub async fn list(State(runner): State<PlanRunner>) -> Json<HandsJson> {
    Json(HandsJson {
        hands: runner.service().list_hands(),
    })
}

pub async fn get(
    State(runner): State<PlanRunner>,
    Path(name): Path<String>,
) -> Result<Json<HandJson>, ApiError> {
    let hand = runner.service().get_hand(&name, "name")?;
    Ok(Json(hand.into()))
}

/// Registering hands is not implemented yet (the facade says so, for both transports).
pub async fn register(State(runner): State<PlanRunner>) -> ApiError {
    match runner.service().register_hand() {
        Ok(()) => ApiError::not_implemented("registering hands is not implemented yet"),
        Err(e) => e.into(),
    }
}
