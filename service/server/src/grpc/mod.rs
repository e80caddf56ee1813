//! The gRPC transport: one file per service, one conversion module, thin over the facade.

pub mod grasp_planner;
pub mod status;
pub mod tactile_stabilizer;

use crate::ops::edge::{EdgeHooks, EdgeLayer};
use crate::ops::{Ops, ReadyState, Transport};
use crate::runner::PlanRunner;
use crate::tls::Listening;
use graspd_proto::v1::grasp_planner_server::GraspPlannerServer;
use graspd_proto::v1::tactile_stabilizer_server::TactileStabilizerServer;
use std::borrow::Cow;
use std::future::Future;
use tonic::transport::Server;
use tonic::transport::server::TcpIncoming;
use tonic_health::ServingStatus;

/// The methods served, as the metrics label them; any other path is labelled `other`.
pub const METHODS: &[&str] = &[
    "/graspd.v1.GraspPlanner/PlanGrasp",
    "/graspd.v1.GraspPlanner/ListHands",
    "/graspd.v1.GraspPlanner/GetHand",
    "/graspd.v1.GraspPlanner/GetHandSynergies",
    "/graspd.v1.GraspPlanner/RegisterHand",
    "/graspd.v1.GraspPlanner/PlanReach",
    "/graspd.v1.TactileStabilizer/Stabilize",
    "/graspd.v1.TactileStabilizer/Calibrate",
    "/graspd.v1.TactileStabilizer/ListCalibrations",
    "/graspd.v1.TactileStabilizer/GetCalibration",
    "/graspd.v1.TactileStabilizer/DeleteCalibration",
    "/grpc.health.v1.Health/Check",
    "/grpc.health.v1.Health/Watch",
    "/grpc.health.v1.Health/List",
    "/grpc.reflection.v1.ServerReflection/ServerReflectionInfo",
];

/// The health service stays open to probes when tokens are configured.
const OPEN_PREFIX: &str = "/grpc.health.v1.Health/";

fn route(parts: &tonic::codegen::http::request::Parts) -> Cow<'static, str> {
    let path = parts.uri.path();
    Cow::Borrowed(
        METHODS
            .iter()
            .find(|m| **m == path)
            .copied()
            .unwrap_or("other"),
    )
}

/// How the gRPC transport plugs into the edge layer.
pub const EDGE_HOOKS: EdgeHooks = EdgeHooks {
    transport: Transport::Grpc,
    route,
    open: |path| path.starts_with(OPEN_PREFIX),
    timeout: status::timeout_of,
    refusal: status::refusal,
    code: |parts| status::code_of(&parts.headers),
    trailer_code: status::code_of,
    abandoned_code: "CANCELLED",
};

async fn mirror_readiness(reporter: &tonic_health::server::HealthReporter, state: ReadyState) {
    let status = match state {
        ReadyState::Ready => ServingStatus::Serving,
        ReadyState::Starting | ReadyState::Draining => ServingStatus::NotServing,
    };
    for name in ["", "graspd.v1.GraspPlanner", "graspd.v1.TactileStabilizer"] {
        reporter.set_service_status(name, status).await;
    }
}

/// Serves GraspPlanner, TactileStabilizer, health and reflection on `listener` (over TLS with
/// `tls`) until `shutdown` completes, then drains in-flight calls. The health service follows the readiness: SERVING
/// while ready, NOT_SERVING while draining.
pub async fn serve(
    listening: Listening,
    runner: PlanRunner,
    ops: Ops,
    shutdown: impl Future<Output = ()> + Send,
) -> Result<(), tonic::transport::Error> {
    let limit = runner.service().limits().max_message_bytes;
    let planner = GraspPlannerServer::new(grasp_planner::GraspPlannerService::new(runner.clone()))
        .max_decoding_message_size(limit);
    let tactile = TactileStabilizerServer::new(tactile_stabilizer::TactileStabilizerService::new(
        runner.clone(),
    ))
    .max_decoding_message_size(limit);
    let (health_reporter, health) = tonic_health::server::health_reporter();
    let mut readiness = ops.readiness.subscribe();
    let state = *readiness.borrow_and_update();
    mirror_readiness(&health_reporter, state).await;
    tokio::spawn(async move {
        while readiness.changed().await.is_ok() {
            let state = *readiness.borrow_and_update();
            mirror_readiness(&health_reporter, state).await;
        }
    });
    let reflection = tonic_reflection::server::Builder::configure()
        .register_encoded_file_descriptor_set(graspd_proto::FILE_DESCRIPTOR_SET)
        .build_v1()
        .expect("the embedded descriptor set is valid");
    let router = Server::builder()
        .layer(EdgeLayer::new(EDGE_HOOKS, &ops))
        .layer(tower::util::MapResponseLayer::new(move |r| {
            status::rewrite_too_large(r, limit)
        }))
        .add_service(health)
        .add_service(reflection)
        .add_service(planner)
        .add_service(tactile);
    // No Nagle: a small answer must not wait for the peer's delayed ACK (40 ms per call on
    // loopback without this; REST's axum sets it by default; the TLS listener sets it too).
    match listening {
        Listening::Plain(listener) => {
            router
                .serve_with_incoming_shutdown(
                    TcpIncoming::from(listener).with_nodelay(Some(true)),
                    shutdown,
                )
                .await
        }
        Listening::Tls(listener) => {
            router
                .serve_with_incoming_shutdown(listener.into_stream(), shutdown)
                .await
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use prost::Message;

    #[test]
    fn the_method_labels_cover_the_graspd_services() {
        let set = prost_types::FileDescriptorSet::decode(graspd_proto::FILE_DESCRIPTOR_SET)
            .expect("the embedded descriptor set decodes");
        let mut n = 0;
        for file in &set.file {
            for service in &file.service {
                for method in &service.method {
                    let path = format!("/{}.{}/{}", file.package(), service.name(), method.name());
                    assert!(
                        METHODS.contains(&path.as_str()),
                        "{path} has no metrics label"
                    );
                    n += 1;
                }
            }
        }
        assert!(n >= 5);
    }

    #[test]
    fn grpc_timeouts() {
        use std::time::Duration;
        let h = |v: &str| {
            let mut m = tonic::codegen::http::HeaderMap::new();
            m.insert("grpc-timeout", v.parse().unwrap());
            status::timeout_of(&m).unwrap()
        };
        assert_eq!(h("100m"), Some(Duration::from_millis(99)));
        assert_eq!(h("2S"), Some(Duration::from_millis(1999)));
        assert_eq!(h("1000u"), Some(Duration::ZERO));
        assert_eq!(h("123456789m"), None);
        assert_eq!(h("5x"), None);
        assert_eq!(h("m"), None);
    }
}
