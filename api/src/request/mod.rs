//! Requests and answers in domain terms, as both transports produce them for the server's
//! facade and the clients build them: what the conversions of [`crate::convert`] decode into
//! and encode from.

pub mod calibration;
pub mod tactile;

pub use calibration::*;
pub use tactile::*;
