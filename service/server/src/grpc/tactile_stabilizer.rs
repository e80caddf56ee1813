//! The `graspd.v1.TactileStabilizer` service. Not implemented yet: it answers UNIMPLEMENTED with
//! a message instead of tonic's generic one.

use graspd_proto::v1 as pb;
use graspd_proto::v1::tactile_stabilizer_server::TactileStabilizer;
use std::pin::Pin;
use tokio_stream::Stream;
use tonic::{Request, Response, Status, Streaming};

#[derive(Debug, Default)]
pub struct TactileStabilizerService;

type SetpointStream = Pin<Box<dyn Stream<Item = Result<pb::StabilizationSetpoint, Status>> + Send>>;

#[tonic::async_trait]
impl TactileStabilizer for TactileStabilizerService {
    type StabilizeStream = SetpointStream;

    async fn stabilize(
        &self,
        _request: Request<Streaming<pb::TactileFrame>>,
    ) -> Result<Response<Self::StabilizeStream>, Status> {
        Err(Status::unimplemented(
            "tactile stabilisation is not implemented yet; plan grasps with GraspPlanner.PlanGrasp",
        ))
    }
}
