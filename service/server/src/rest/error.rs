//! The REST error answer: an HTTP status and `{"error": {"code", "field", "message"}}`.

use super::json::{ErrorDetailJson, ErrorJson};
use crate::facade::{Limits, ServiceError};
use crate::ops::edge::{AnswerCode, Refusal};
use crate::runner::SHED_RETRY_AFTER;
use axum::Json;
use axum::http::header::{CONTENT_TYPE, RETRY_AFTER, WWW_AUTHENTICATE};
use axum::http::{HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use bytes::Bytes;
use graspd_core::FieldError;
use std::borrow::Cow;
use std::time::Duration;

#[derive(Debug, Clone)]
pub struct ApiError {
    pub status: StatusCode,
    pub code: &'static str,
    pub field: Option<String>,
    pub message: String,
    /// Sent as `Retry-After` (whole seconds, at least 1).
    pub retry_after: Option<Duration>,
}

impl ApiError {
    pub fn new(status: StatusCode, code: &'static str, message: impl Into<String>) -> Self {
        Self {
            status,
            code,
            field: None,
            message: message.into(),
            retry_after: None,
        }
    }

    fn with_field(status: StatusCode, code: &'static str, e: FieldError) -> Self {
        Self {
            status,
            code,
            field: Some(e.field),
            message: e.message,
            retry_after: None,
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
            ServiceError::Overloaded(m) => Self {
                retry_after: Some(SHED_RETRY_AFTER),
                ..Self::new(StatusCode::SERVICE_UNAVAILABLE, "resource_exhausted", m)
            },
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

impl ApiError {
    fn retry_after_header(&self) -> Option<HeaderValue> {
        self.retry_after
            .map(|d| HeaderValue::from(d.as_secs_f64().ceil().max(1.0) as u64))
    }

    fn body(self) -> ErrorJson {
        ErrorJson {
            error: ErrorDetailJson {
                code: self.code.into(),
                field: self.field,
                message: self.message,
            },
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let status = self.status;
        let retry_after = self.retry_after_header();
        let mut response = (status, Json(self.body())).into_response();
        if let Some(v) = retry_after {
            response.headers_mut().insert(RETRY_AFTER, v);
        }
        response
    }
}

/// The answer to a request the edge layer refuses: the same JSON error as the handlers'.
pub fn refusal(refusal: &Refusal) -> axum::http::Response<Bytes> {
    let error = match refusal {
        Refusal::Unauthenticated => ApiError::new(
            StatusCode::UNAUTHORIZED,
            "unauthenticated",
            "missing or wrong bearer token: send the header `authorization: Bearer <token>`",
        ),
        Refusal::DeadlineExceeded(timeout) => ApiError::new(
            StatusCode::GATEWAY_TIMEOUT,
            "deadline_exceeded",
            format!(
                "the deadline (x-request-timeout-ms: {}) passed before the answer was ready",
                timeout.as_millis()
            ),
        ),
        Refusal::BadTimeout(message) => ApiError {
            field: Some(super::REQUEST_TIMEOUT_HEADER.into()),
            ..ApiError::new(StatusCode::BAD_REQUEST, "invalid_argument", message.clone())
        },
    };
    let status = error.status;
    let body = serde_json::to_vec(&error.body()).unwrap_or_default();
    let mut response = axum::http::Response::new(Bytes::from(body));
    *response.status_mut() = status;
    response
        .headers_mut()
        .insert(CONTENT_TYPE, HeaderValue::from_static("application/json"));
    if *refusal == Refusal::Unauthenticated {
        response
            .headers_mut()
            .insert(WWW_AUTHENTICATE, HeaderValue::from_static("Bearer"));
    }
    response
}

/// The metrics code of a REST answer: its status.
pub fn code_of(status: StatusCode) -> AnswerCode {
    let code = match status.as_u16() {
        200 => Cow::Borrowed("200"),
        101 => Cow::Borrowed("101"),
        n => Cow::Owned(n.to_string()),
    };
    (code, status.is_client_error() || status.is_server_error())
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
