//! Domain errors. Every error that comes from input names the offending field, so that the
//! transports can answer INVALID_ARGUMENT / HTTP 400 with a message a caller can act on.

use thiserror::Error;

/// Bad input: which field, and what is wrong with it.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{field}: {message}")]
pub struct FieldError {
    pub field: String,
    pub message: String,
}

impl FieldError {
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            message: message.into(),
        }
    }
}

/// Errors of the planner.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlanError {
    /// The request is malformed or cannot be served as given.
    #[error(transparent)]
    InvalidInput(#[from] FieldError),
    /// The request names something that is not there (an object not in view).
    #[error(transparent)]
    NotFound(FieldError),
    /// A model graspd runs failed on a valid request (an inference error).
    #[error("{0}")]
    Model(String),
    /// The input is valid but this capability is not implemented yet.
    #[error("{0}")]
    Unimplemented(String),
}
