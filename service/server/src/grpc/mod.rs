//! The gRPC transport: one file per service, one conversion module, thin over the facade.

pub mod convert;
pub mod grasp_planner;
pub mod status;
pub mod tactile_stabilizer;

use crate::runner::PlanRunner;
use graspd_proto::v1::grasp_planner_server::GraspPlannerServer;
use graspd_proto::v1::tactile_stabilizer_server::TactileStabilizerServer;
use std::future::Future;
use tokio::net::TcpListener;
use tokio_stream::wrappers::TcpListenerStream;
use tonic::transport::Server;

/// Serves GraspPlanner, TactileStabilizer, health and reflection on `listener` until `shutdown`
/// completes, then drains in-flight calls.
pub async fn serve(
    listener: TcpListener,
    runner: PlanRunner,
    shutdown: impl Future<Output = ()> + Send,
) -> Result<(), tonic::transport::Error> {
    let limit = runner.service().limits().max_message_bytes;
    let planner = GraspPlannerServer::new(grasp_planner::GraspPlannerService::new(runner.clone()))
        .max_decoding_message_size(limit);
    let tactile = TactileStabilizerServer::new(tactile_stabilizer::TactileStabilizerService::new(
        runner.service().clone(),
    ))
    .max_decoding_message_size(limit);
    let (health_reporter, health) = tonic_health::server::health_reporter();
    health_reporter
        .set_serving::<GraspPlannerServer<grasp_planner::GraspPlannerService>>()
        .await;
    let reflection = tonic_reflection::server::Builder::configure()
        .register_encoded_file_descriptor_set(graspd_proto::FILE_DESCRIPTOR_SET)
        .build_v1()
        .expect("the embedded descriptor set is valid");
    Server::builder()
        .layer(tower::util::MapResponseLayer::new(move |r| {
            status::rewrite_too_large(r, limit)
        }))
        .add_service(health)
        .add_service(reflection)
        .add_service(planner)
        .add_service(tactile)
        .serve_with_incoming_shutdown(TcpListenerStream::new(listener), shutdown)
        .await
}
