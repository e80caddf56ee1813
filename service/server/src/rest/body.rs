//! The body of a POST route that takes JSON, multipart/form-data or (`/v1/tactile/analyze`) CSV:
//! one reader for every route. The content type decides; none means JSON. A body over the size
//! limit is 413, a broken one 400, and an unsupported content type 415 — answered after the
//! body is drained (up to the limit), so that an HTTP/1.1 client still writing it gets the
//! status instead of a broken pipe.

use super::error::{ApiError, body_error};
use crate::facade::Limits;
use axum::body::Bytes;
use axum::extract::{FromRequest, Multipart, Request};
use axum::http::StatusCode;
use axum::http::header::CONTENT_TYPE;
use graspd_core::FieldError;

/// A body as the route's content type gives it.
pub enum Body {
    /// `application/json`, or no content type.
    Json(Bytes),
    /// `text/csv` (only where the route accepts it).
    Csv(Bytes),
    /// `multipart/form-data`: its parts in order.
    Multipart(Vec<Part>),
}

/// One part of a multipart body.
pub struct Part {
    pub name: String,
    pub file_name: Option<String>,
    pub bytes: Bytes,
}

impl Part {
    /// The error for a part that may come once and came again.
    pub fn twice(&self) -> ApiError {
        ApiError::invalid(FieldError::new(
            self.name.clone(),
            format!("the part '{}' is given twice", self.name),
        ))
    }

    /// The error for a part the route does not know; `expected` says which it knows.
    pub fn unknown(&self, expected: &str) -> ApiError {
        ApiError::invalid(FieldError::new(
            "multipart",
            format!(
                "unknown part '{}' (expected {expected})",
                self.name.escape_debug()
            ),
        ))
    }
}

/// Reads `request`'s body. `csv`: whether the route takes `text/csv`; `accepted` completes the
/// 415 message ("send …").
pub async fn read_body(
    request: Request,
    limits: &Limits,
    csv: bool,
    accepted: &str,
) -> Result<Body, ApiError> {
    let content_type = request
        .headers()
        .get(CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_ascii_lowercase();
    let read_err =
        |e: axum::extract::rejection::BytesRejection| body_error(e.status(), e.body_text(), limits);
    if content_type.starts_with("multipart/form-data") {
        let mut multipart = Multipart::from_request(request, &())
            .await
            .map_err(|e| body_error(e.status(), e.body_text(), limits))?;
        let mut parts = Vec::new();
        while let Some(field) = multipart
            .next_field()
            .await
            .map_err(|e| body_error(e.status(), e.body_text(), limits))?
        {
            let name = field.name().unwrap_or("").to_string();
            let file_name = field.file_name().map(str::to_string);
            let bytes = field
                .bytes()
                .await
                .map_err(|e| body_error(e.status(), e.body_text(), limits))?;
            parts.push(Part {
                name,
                file_name,
                bytes,
            });
        }
        Ok(Body::Multipart(parts))
    } else if csv && content_type.starts_with("text/csv") {
        Ok(Body::Csv(
            Bytes::from_request(request, &()).await.map_err(read_err)?,
        ))
    } else if content_type.is_empty() || content_type.starts_with("application/json") {
        Ok(Body::Json(
            Bytes::from_request(request, &()).await.map_err(read_err)?,
        ))
    } else {
        let e = ApiError::new(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "unsupported_media_type",
            format!("content type '{content_type}' is not supported; send {accepted}"),
        );
        Err(after_reading_body(request, limits, e).await)
    }
}

/// `e`, once the body (up to the size limit) has been read: an answer sent while an HTTP/1.1
/// client is still writing a large body closes the connection under it, and the client sees a
/// broken pipe instead of the error.
pub async fn after_reading_body(request: Request, limits: &Limits, e: ApiError) -> ApiError {
    let _ = axum::body::to_bytes(request.into_body(), limits.max_message_bytes).await;
    e
}
