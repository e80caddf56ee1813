//! The graspd.v1 API as the server and its clients share it (issue 17): the generated proto
//! (`graspd-proto`, re-exported as [`proto`]), [`request`], the requests and answers in domain
//! terms that the server's facade takes and gives, [`convert`], the conversions between the
//! proto messages and those and `graspd-core`'s domain types, and [`json`], the REST bodies
//! (DTOs and their conversions, with [`schemas`], the OpenAPI stand-ins for domain types). The
//! server, `graspctl` and `graspd-sim` use these instead of their own.

pub use graspd_proto as proto;

pub mod convert;
pub mod error;
pub mod json;
pub mod limits;
pub mod request;
pub mod schemas;

pub use error::ServiceError;
pub use limits::Limits;
