//! gRPC status codes for facade errors, and the rewrite of tonic's own "message too large"
//! answer into RESOURCE_EXHAUSTED with a message that names the limit.

use crate::facade::ServiceError;
use tonic::codegen::http;
use tonic::{Code, Status};

/// Metadata key carrying the offending field, for clients that want it without parsing.
pub const FIELD_METADATA_KEY: &str = "graspd-field";

pub fn to_status(e: ServiceError) -> Status {
    let code = match &e {
        ServiceError::InvalidArgument(_) => Code::InvalidArgument,
        ServiceError::NotFound(_) => Code::NotFound,
        ServiceError::AlreadyExists(_) => Code::AlreadyExists,
        ServiceError::TooLarge(_) => Code::ResourceExhausted,
        ServiceError::Exhausted(_) => Code::ResourceExhausted,
        ServiceError::Unimplemented(_) => Code::Unimplemented,
        ServiceError::Internal(_) => Code::Internal,
    };
    let mut status = Status::new(code, e.to_string());
    if let Some(field) = e.field()
        && let Ok(v) = field.parse()
    {
        status.metadata_mut().insert(FIELD_METADATA_KEY, v);
    }
    status
}

/// tonic refuses a request larger than `max_decoding_message_size` with OUT_OF_RANGE and a
/// message that names no limit; callers get RESOURCE_EXHAUSTED naming `max_message_bytes`.
pub fn rewrite_too_large<B>(mut response: http::Response<B>, limit: usize) -> http::Response<B> {
    let Some(original) = Status::from_header_map(response.headers()) else {
        return response;
    };
    if original.code() != Code::OutOfRange
        || !original
            .message()
            .contains("decoded message length too large")
    {
        return response;
    }
    let found = original
        .message()
        .split("found ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .unwrap_or("?")
        .to_string();
    let mut status = Status::new(
        Code::ResourceExhausted,
        format!(
            "request: message of {found} bytes exceeds the configured limit of {limit} bytes (max_message_bytes)"
        ),
    );
    if let Ok(v) = "request".parse() {
        status.metadata_mut().insert(FIELD_METADATA_KEY, v);
    }
    let _ = status.add_header(response.headers_mut());
    response.extensions_mut().insert(status);
    response
}
