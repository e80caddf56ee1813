//! The `graspd.v1` gRPC API generated from `proto/graspd/v1/*.proto`. Conversions to the domain
//! types live in `graspd-api` (`graspd_api::convert`), not here, so this crate stays a pure
//! wire-format crate that any client can use.

/// Package `graspd.v1`.
pub mod v1 {
    #![allow(clippy::all, missing_docs)]
    tonic::include_proto!("graspd.v1");
}

/// The encoded `FileDescriptorSet` of the API, for gRPC server reflection.
pub const FILE_DESCRIPTOR_SET: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/graspd_descriptor.bin"));
