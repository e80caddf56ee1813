//! The facade's errors; each transport maps them to its status codes.

use graspd_core::{FieldError, PlanError};
use thiserror::Error;

/// Errors of the facade; each transport maps them to its status codes.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ServiceError {
    /// Bad input (gRPC INVALID_ARGUMENT, HTTP 400).
    #[error(transparent)]
    InvalidArgument(FieldError),
    /// A named thing does not exist (NOT_FOUND, 404).
    #[error(transparent)]
    NotFound(FieldError),
    /// Input over a configured limit (RESOURCE_EXHAUSTED, 413).
    #[error(transparent)]
    TooLarge(FieldError),
    /// A configured capacity is used up, retry later (RESOURCE_EXHAUSTED, 503).
    #[error("{0}")]
    Exhausted(String),
    /// The planner's queue is full: the request was shed, retry in a second
    /// (RESOURCE_EXHAUSTED with `retry-after-ms`, 503 with `Retry-After`).
    #[error("{0}")]
    Overloaded(String),
    /// A name is taken (ALREADY_EXISTS, 409).
    #[error(transparent)]
    AlreadyExists(FieldError),
    /// Valid but not implemented yet (UNIMPLEMENTED, 501).
    #[error("{0}")]
    Unimplemented(String),
    /// A bug: the planner failed (INTERNAL, 500).
    #[error("internal error: {0}")]
    Internal(String),
}

impl ServiceError {
    /// The offending field, when the error is about one.
    pub fn field(&self) -> Option<&str> {
        match self {
            ServiceError::InvalidArgument(e)
            | ServiceError::NotFound(e)
            | ServiceError::AlreadyExists(e)
            | ServiceError::TooLarge(e) => Some(&e.field),
            _ => None,
        }
    }
}

impl From<FieldError> for ServiceError {
    fn from(e: FieldError) -> Self {
        ServiceError::InvalidArgument(e)
    }
}

impl From<PlanError> for ServiceError {
    fn from(e: PlanError) -> Self {
        match e {
            PlanError::InvalidInput(f) => ServiceError::InvalidArgument(f),
            PlanError::NotFound(f) => ServiceError::NotFound(f),
            PlanError::Unimplemented(m) => ServiceError::Unimplemented(m),
            PlanError::Model(m) => ServiceError::Internal(m),
        }
    }
}
