//! The graspd.v1 API as the server and its clients share it (issue 17): the generated proto
//! (`graspd-proto`, re-exported as [`proto`]) and [`convert`], the conversions between its
//! messages and `graspd-core`'s domain types that do not depend on the server. The server
//! (`graspd::grpc::convert`), `graspctl` and `graspd-sim` use these instead of their own.

pub use graspd_proto as proto;

pub mod convert;
