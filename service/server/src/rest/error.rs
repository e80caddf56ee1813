//! The REST error answer: an HTTP status and `{"error": {"code", "field", "message"}}`.

use super::json::{ErrorDetailJson, ErrorJson};
use crate::facade::ServiceError;
use axum::Json;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use graspd_core::FieldError;

#[derive(Debug, Clone)]
pub struct ApiError {
    pub status: StatusCode,
    pub code: &'static str,
    pub field: Option<String>,
    pub message: String,
}

impl ApiError {
    pub fn new(status: StatusCode, code: &'static str, message: impl Into<String>) -> Self {
        Self {
            status,
            code,
            field: None,
            message: message.into(),
        }
    }

    fn with_field(status: StatusCode, code: &'static str, e: FieldError) -> Self {
        Self {
            status,
            code,
            field: Some(e.field),
            message: e.message,
        }
    }

    pub fn invalid(e: FieldError) -> Self {
        Self::with_field(StatusCode::BAD_REQUEST, "invalid_argument", e)
    }

    pub fn too_large(e: FieldError) -> Self {
        Self::with_field(StatusCode::PAYLOAD_TOO_LARGE, "payload_too_large", e)
    }

    pub fn not_implemented(message: impl Into<String>) -> Self {
        Self::new(StatusCode::NOT_IMPLEMENTED, "unimplemented", message)
    }
}

impl From<ServiceError> for ApiError {
    fn from(e: ServiceError) -> Self {
        match e {
            ServiceError::InvalidArgument(f) => Self::invalid(f),
            ServiceError::NotFound(f) => Self::with_field(StatusCode::NOT_FOUND, "not_found", f),
            ServiceError::AlreadyExists(f) => {
                Self::with_field(StatusCode::CONFLICT, "already_exists", f)
            }
            ServiceError::TooLarge(f) => Self::too_large(f),
            ServiceError::Exhausted(m) => {
                Self::new(StatusCode::SERVICE_UNAVAILABLE, "resource_exhausted", m)
            }
            ServiceError::Unimplemented(m) => Self::not_implemented(m),
            ServiceError::Internal(m) => {
                Self::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", m)
            }
        }
    }
}

impl From<FieldError> for ApiError {
    fn from(e: FieldError) -> Self {
        Self::invalid(e)
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let body = ErrorJson {
            error: ErrorDetailJson {
                code: self.code.into(),
                field: self.field,
                message: self.message,
            },
        };
        (self.status, Json(body)).into_response()
    }
}
