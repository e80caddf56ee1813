//! Requests and answers in domain terms, as both transports produce them for the server's
//! facade and the clients build them: what the conversions of [`crate::convert`] decode into
//! and encode from. One file per family: [`plan`], [`hands`] (registration), [`reach`] (PlanReach), [`tactile`]
//! (sessions), [`calibration`].

pub mod calibration;
pub mod hands;
pub mod plan;
pub mod reach;
pub mod tactile;

pub use calibration::*;
pub use hands::*;
pub use plan::*;
pub use reach::*;
pub use tactile::*;
