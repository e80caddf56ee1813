//! Runs the facade's blocking, CPU-bound planning off the async runtime, at most
//! `max_concurrent_plans` at a time, and logs each plan. Shared by both transports.

use crate::facade::{GraspService, PlanRequest, ServiceError};
use graspd_core::GraspPlan;
use std::sync::Arc;
use std::time::Instant;
use tokio::sync::Semaphore;

#[derive(Debug, Clone)]
pub struct PlanRunner {
    service: GraspService,
    permits: Arc<Semaphore>,
}

impl PlanRunner {
    pub fn new(service: GraspService) -> Self {
        let permits = Arc::new(Semaphore::new(service.limits().max_concurrent_plans.max(1)));
        Self { service, permits }
    }

    pub fn service(&self) -> &GraspService {
        &self.service
    }

    /// Plans on a blocking thread; `transport` labels the log line.
    pub async fn plan(
        &self,
        request: PlanRequest,
        transport: &'static str,
    ) -> Result<GraspPlan, ServiceError> {
        let _permit = self
            .permits
            .acquire()
            .await
            .map_err(|_| ServiceError::Internal("the planner pool is closed".into()))?;
        let service = self.service.clone();
        let started = Instant::now();
        let result = tokio::task::spawn_blocking(move || service.plan(request))
            .await
            .unwrap_or_else(|e| Err(ServiceError::Internal(format!("planning task failed: {e}"))));
        let seconds = started.elapsed().as_secs_f64();
        match &result {
            Ok(plan) => tracing::info!(
                transport,
                hand = %plan.hand,
                grasp_type = %plan.grasp_type,
                feasible = plan.feasible,
                points = plan.points_used,
                seconds,
                "planned"
            ),
            Err(ServiceError::Internal(e)) => {
                tracing::error!(transport, error = %e, seconds, "planning failed")
            }
            Err(e) => tracing::info!(transport, error = %e, seconds, "plan request rejected"),
        }
        result
    }
}
