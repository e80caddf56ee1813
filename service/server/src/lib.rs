//! graspd: the grasp-planning service. One facade ([`facade::GraspService`]) over the domain
//! crate `graspd-core`, served by two thin transports: gRPC ([`grpc`], tonic) and REST
//! ([`rest`], axum).

pub mod calibration_store;
pub mod config;
pub mod facade;
pub mod grpc;
pub mod hand_store;
pub mod ops;
pub mod probe;
pub mod rest;
pub mod runner;
pub mod server;
pub mod telemetry;
pub mod tls;

pub use facade::{
    GraspService, HandChoice, ImageHints, Limits, OutputOptions, PlanRequest, PlanSource,
    ServiceError,
};
