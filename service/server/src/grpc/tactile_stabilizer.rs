//! The `graspd.v1.TactileStabilizer` service: one bidirectional stream per session.
//!
//! The first message opens the session through the facade (a slot of `max_tactile_sessions`);
//! each later frame gets exactly one setpoint. A task per stream reads a frame, steps the session
//! and waits until the answer fits into a bounded channel ([`SESSION_QUEUE`]) before it reads the
//! next frame: a slow reader stops the reading (HTTP/2 flow control then stops the client), so
//! server memory does not grow. A bad frame ends the stream with INVALID_ARGUMENT naming the
//! field. When the client goes away the response stream is dropped, the task notices at once
//! (even while it waits for a frame) and the session, with its slot, is dropped.

use super::status::to_status;
use crate::facade::{GraspService, ServiceError};
use crate::ops::Transport;
use crate::runner::PlanRunner;
use graspd_api::convert;
use graspd_core::FieldError;
use graspd_proto::v1 as pb;
use graspd_proto::v1::tactile_stabilizer_server::TactileStabilizer;
use std::pin::Pin;
use tokio::sync::mpsc;
use tokio_stream::Stream;
use tokio_stream::wrappers::ReceiverStream;
use tonic::{Request, Response, Status, Streaming};
use tracing::Instrument;

/// Answers buffered per session before the server stops reading frames.
pub const SESSION_QUEUE: usize = 16;

#[derive(Debug, Clone)]
pub struct TactileStabilizerService {
    service: GraspService,
    /// The CPU-bound pool, for calibrations (shed like plans).
    runner: PlanRunner,
}

impl TactileStabilizerService {
    pub fn new(runner: PlanRunner) -> Self {
        Self {
            service: runner.service().clone(),
            runner,
        }
    }
}

type SetpointStream = Pin<Box<dyn Stream<Item = Result<pb::StabilizationSetpoint, Status>> + Send>>;

fn invalid(e: FieldError) -> Status {
    to_status(ServiceError::InvalidArgument(e))
}

#[tonic::async_trait]
impl TactileStabilizer for TactileStabilizerService {
    type StabilizeStream = SetpointStream;

    async fn stabilize(
        &self,
        request: Request<Streaming<pb::StabilizeRequest>>,
    ) -> Result<Response<Self::StabilizeStream>, Status> {
        let mut inbound = request.into_inner();
        let first = inbound.message().await?.ok_or_else(|| {
            invalid(FieldError::new(
                "session",
                "the stream ended before the session was opened",
            ))
        })?;
        let session_request = convert::stabilize_session_from_proto(first).map_err(invalid)?;
        let mut session = self
            .service
            .open_tactile_session(session_request)
            .map_err(to_status)?;
        tracing::debug!(
            fingers = session.config().fingers.len(),
            "tactile session opened"
        );
        let (tx, rx) = mpsc::channel(SESSION_QUEUE);
        tokio::spawn(
            async move {
                loop {
                    let message = tokio::select! {
                        () = tx.closed() => break,
                        m = inbound.message() => m,
                    };
                    let message = match message {
                        Ok(Some(m)) => m,
                        // The client finished sending, or the connection failed.
                        Ok(None) | Err(_) => break,
                    };
                    let index = session.frames();
                    let answer = convert::stabilize_frame_from_proto(message)
                        .map_err(ServiceError::from)
                        .and_then(|frame| session.step(&frame))
                        .map(|r| convert::setpoint_to_proto(&r, index))
                        .map_err(to_status);
                    let failed = answer.is_err();
                    if tx.send(answer).await.is_err() || failed {
                        break;
                    }
                }
                tracing::debug!(frames = session.frames(), "tactile session closed");
                drop(session);
            }
            .in_current_span(),
        );
        Ok(Response::new(Box::pin(ReceiverStream::new(rx))))
    }

    async fn calibrate(
        &self,
        request: Request<pb::CalibrateRequest>,
    ) -> Result<Response<pb::CalibrationInfo>, Status> {
        let upload =
            convert::calibrate_request_from_proto(request.into_inner()).map_err(invalid)?;
        let info = self
            .runner
            .run_blocking("calibration", Transport::Grpc, move |s| s.calibrate(upload))
            .await
            .map_err(to_status)?;
        tracing::info!(calibration = %info.calibration.name, persisted = info.persisted, "calibration fitted");
        Ok(Response::new(convert::calibration_info_to_proto(&info)))
    }

    async fn list_calibrations(
        &self,
        _request: Request<pb::ListCalibrationsRequest>,
    ) -> Result<Response<pb::ListCalibrationsResponse>, Status> {
        Ok(Response::new(pb::ListCalibrationsResponse {
            calibrations: self
                .service
                .list_calibrations()
                .iter()
                .map(convert::calibration_info_to_proto)
                .collect(),
        }))
    }

    async fn get_calibration(
        &self,
        request: Request<pb::GetCalibrationRequest>,
    ) -> Result<Response<pb::CalibrationInfo>, Status> {
        let info = self
            .service
            .get_calibration(&request.into_inner().name)
            .map_err(to_status)?;
        Ok(Response::new(convert::calibration_info_to_proto(&info)))
    }

    async fn delete_calibration(
        &self,
        request: Request<pb::DeleteCalibrationRequest>,
    ) -> Result<Response<pb::DeleteCalibrationResponse>, Status> {
        let name = request.into_inner().name;
        let service = self.service.clone();
        tokio::task::spawn_blocking(move || service.delete_calibration(&name))
            .await
            .map_err(|e| Status::internal(format!("delete task failed: {e}")))?
            .map_err(to_status)?;
        Ok(Response::new(pb::DeleteCalibrationResponse {}))
    }
}
