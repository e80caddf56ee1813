//! The `graspd.v1.GraspPlanner` service: decode, call the facade, encode.

use super::status::to_status;
use crate::ops::Transport;
use crate::runner::PlanRunner;
use graspd_api::convert;
use graspd_proto::v1 as pb;
use graspd_proto::v1::grasp_planner_server::GraspPlanner;
use tonic::{Request, Response, Status};

pub struct GraspPlannerService {
    runner: PlanRunner,
}

impl GraspPlannerService {
    pub fn new(runner: PlanRunner) -> Self {
        Self { runner }
    }
}

#[tonic::async_trait]
impl GraspPlanner for GraspPlannerService {
    async fn plan_grasp(
        &self,
        request: Request<pb::PlanGraspRequest>,
    ) -> Result<Response<pb::PlanGraspResponse>, Status> {
        let limits = *self.runner.service().limits();
        let request =
            convert::plan_request_from_proto(request.into_inner(), &limits).map_err(to_status)?;
        let plan = self
            .runner
            .plan(request, Transport::Grpc)
            .await
            .map_err(to_status)?;
        Ok(Response::new(convert::plan_to_proto(&plan)))
    }

    async fn list_hands(
        &self,
        _request: Request<pb::ListHandsRequest>,
    ) -> Result<Response<pb::ListHandsResponse>, Status> {
        let hands = self.runner.service().list_hands();
        Ok(Response::new(pb::ListHandsResponse {
            hands: hands.iter().map(convert::hand_to_proto).collect(),
        }))
    }

    async fn get_hand(
        &self,
        request: Request<pb::GetHandRequest>,
    ) -> Result<Response<pb::GetHandResponse>, Status> {
        let name = request.into_inner().name;
        let hand = self
            .runner
            .service()
            .get_hand(&name, "name")
            .map_err(to_status)?;
        Ok(Response::new(pb::GetHandResponse {
            realisable_types: hand
                .realisable_types()
                .into_iter()
                .map(|t| convert::grasp_type_to_proto(t) as i32)
                .collect(),
            hand: Some(convert::hand_to_proto(&hand)),
        }))
    }

    async fn get_hand_synergies(
        &self,
        request: Request<pb::GetHandSynergiesRequest>,
    ) -> Result<Response<pb::HandSynergies>, Status> {
        let name = request.into_inner().name;
        let synergies = self
            .runner
            .run_blocking("posture synergies", Transport::Grpc, move |s| {
                s.hand_synergies(&name)
            })
            .await
            .map_err(to_status)?;
        Ok(Response::new(convert::synergies_to_proto(&synergies)))
    }

    async fn register_hand(
        &self,
        request: Request<pb::RegisterHandRequest>,
    ) -> Result<Response<pb::RegisterHandResponse>, Status> {
        let (upload, replace) = convert::register_request_from_proto(request.into_inner())
            .map_err(|e| to_status(e.into()))?;
        let registered = self
            .runner
            .run_blocking("hand import", Transport::Grpc, move |s| {
                s.register_hand(upload, replace)
            })
            .await
            .map_err(to_status)?;
        tracing::info!(hand = %registered.description.name, persisted = registered.persisted, "hand registered");
        Ok(Response::new(convert::registered_to_proto(&registered)))
    }

    async fn plan_reach(
        &self,
        request: Request<pb::PlanReachRequest>,
    ) -> Result<Response<pb::PlanReachResponse>, Status> {
        let request = convert::reach_request_from_proto(request.into_inner())
            .map_err(|e| to_status(e.into()))?;
        let (trajectory, ms) = self
            .runner
            .run_blocking("reach", Transport::Grpc, move |s| s.plan_reach(request))
            .await
            .map_err(to_status)?;
        Ok(Response::new(convert::trajectory_to_proto(&trajectory, ms)))
    }
}
