//! gRPC status codes for facade errors, and the rewrite of tonic's own "message too large"
//! answer into RESOURCE_EXHAUSTED with a message that names the limit.

use crate::facade::ServiceError;
use crate::ops::edge::{AnswerCode, Refusal};
use crate::runner::SHED_RETRY_AFTER;
use std::borrow::Cow;
use std::time::Duration;
use tonic::codegen::http;
use tonic::{Code, Status};

/// Metadata key carrying the offending field, for clients that want it without parsing.
pub const FIELD_METADATA_KEY: &str = "graspd-field";

/// Metadata key of a shed request's retry hint, milliseconds.
pub const RETRY_AFTER_METADATA_KEY: &str = "retry-after-ms";

pub fn to_status(e: ServiceError) -> Status {
    let code = match &e {
        ServiceError::InvalidArgument(_) => Code::InvalidArgument,
        ServiceError::NotFound(_) => Code::NotFound,
        ServiceError::AlreadyExists(_) => Code::AlreadyExists,
        ServiceError::TooLarge(_) => Code::ResourceExhausted,
        ServiceError::Exhausted(_) | ServiceError::Overloaded(_) => Code::ResourceExhausted,
        ServiceError::Unimplemented(_) => Code::Unimplemented,
        ServiceError::Internal(_) => Code::Internal,
    };
    let mut status = Status::new(code, e.to_string());
    if let Some(field) = e.field()
        && let Ok(v) = field.parse()
    {
        status.metadata_mut().insert(FIELD_METADATA_KEY, v);
    }
    if matches!(e, ServiceError::Overloaded(_)) {
        status.metadata_mut().insert(
            RETRY_AFTER_METADATA_KEY,
            SHED_RETRY_AFTER
                .as_millis()
                .to_string()
                .parse()
                .expect("digits"),
        );
    }
    status
}

/// The trailers-only answer to a request the edge layer refuses.
pub fn refusal(refusal: &Refusal) -> http::Response<bytes::Bytes> {
    let status = match refusal {
        Refusal::Unauthenticated => Status::unauthenticated(
            "missing or wrong bearer token: send the metadata `authorization: Bearer <token>`",
        ),
        Refusal::DeadlineExceeded(timeout) => Status::deadline_exceeded(format!(
            "the deadline ({} ms after the request arrived) passed before the answer was ready",
            timeout.as_millis()
        )),
        Refusal::BadTimeout(message) => Status::invalid_argument(message.clone()),
    };
    let mut response = status.into_http::<bytes::Bytes>();
    if *refusal == Refusal::Unauthenticated {
        response.headers_mut().insert(
            http::header::WWW_AUTHENTICATE,
            http::HeaderValue::from_static("Bearer"),
        );
    }
    response
}

/// The gRPC name of a code, as metrics label it (`OK`, `INVALID_ARGUMENT`, …).
pub fn code_name(code: Code) -> &'static str {
    match code {
        Code::Ok => "OK",
        Code::Cancelled => "CANCELLED",
        Code::Unknown => "UNKNOWN",
        Code::InvalidArgument => "INVALID_ARGUMENT",
        Code::DeadlineExceeded => "DEADLINE_EXCEEDED",
        Code::NotFound => "NOT_FOUND",
        Code::AlreadyExists => "ALREADY_EXISTS",
        Code::PermissionDenied => "PERMISSION_DENIED",
        Code::ResourceExhausted => "RESOURCE_EXHAUSTED",
        Code::FailedPrecondition => "FAILED_PRECONDITION",
        Code::Aborted => "ABORTED",
        Code::OutOfRange => "OUT_OF_RANGE",
        Code::Unimplemented => "UNIMPLEMENTED",
        Code::Internal => "INTERNAL",
        Code::Unavailable => "UNAVAILABLE",
        Code::DataLoss => "DATA_LOSS",
        Code::Unauthenticated => "UNAUTHENTICATED",
    }
}

/// The code carried by `grpc-status` in headers (trailers-only answers) or trailers.
pub fn code_of(headers: &http::HeaderMap) -> Option<AnswerCode> {
    let value = headers.get("grpc-status")?;
    let code = Code::from_bytes(value.as_bytes());
    Some((Cow::Borrowed(code_name(code)), code != Code::Ok))
}

/// The caller's budget from `grpc-timeout` (gRPC over HTTP/2: up to 8 digits and a unit, H M S
/// m u n), less a millisecond so that the edge answers DEADLINE_EXCEEDED before tonic's own
/// timer, which would answer CANCELLED, fires. An unreadable value is ignored, as tonic does.
pub fn timeout_of(headers: &http::HeaderMap) -> Result<Option<Duration>, String> {
    let Some(value) = headers.get("grpc-timeout").and_then(|v| v.to_str().ok()) else {
        return Ok(None);
    };
    let Some(unit) = value.chars().last() else {
        return Ok(None);
    };
    let digits = &value[..value.len() - unit.len_utf8()];
    if digits.is_empty() || digits.len() > 8 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return Ok(None);
    }
    let n: u64 = digits.parse().unwrap_or(0);
    let timeout = match unit {
        'H' => Duration::from_secs(n * 3600),
        'M' => Duration::from_secs(n * 60),
        'S' => Duration::from_secs(n),
        'm' => Duration::from_millis(n),
        'u' => Duration::from_micros(n),
        'n' => Duration::from_nanos(n),
        _ => return Ok(None),
    };
    Ok(Some(timeout.saturating_sub(Duration::from_millis(1))))
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
