//! Runs the facade's blocking, CPU-bound work — plans, hand imports, tactile analyses and
//! calibrations — off the async runtime, at most `max_concurrent_plans` at a time with at most
//! `max_queued_plans` waiting, and logs and counts each plan. Shared by both transports.
//!
//! A request that would wait beyond the queue is shed at once ([`ServiceError::Overloaded`]).
//! A request whose caller gives up (its future is dropped: a passed deadline, a closed
//! connection) leaves the queue; one already on a planner thread finishes there and holds its
//! planner slot and its place until then, so the limits always count the threads really busy.

use crate::facade::{GraspService, PlanRequest, ServiceError};
use crate::ops::metrics::PlanOutcome;
use crate::ops::{Metrics, Transport};
use graspd_core::GraspPlan;
use prometheus_client::metrics::gauge::Gauge;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::Semaphore;

/// How soon a shed caller is told to retry (REST `Retry-After`, gRPC `retry-after-ms`).
pub const SHED_RETRY_AFTER: Duration = Duration::from_secs(1);

#[derive(Debug, Clone)]
pub struct PlanRunner {
    service: GraspService,
    /// Planner threads: `max_concurrent_plans`.
    permits: Arc<Semaphore>,
    /// Places: running plus waiting, `max_concurrent_plans + max_queued_plans`.
    places: Arc<Semaphore>,
    metrics: Metrics,
}

/// Keeps a gauge one higher while alive.
struct GaugeGuard(Gauge);

impl GaugeGuard {
    fn new(gauge: &Gauge) -> Self {
        gauge.inc();
        Self(gauge.clone())
    }
}

impl Drop for GaugeGuard {
    fn drop(&mut self) {
        self.0.dec();
    }
}

impl PlanRunner {
    pub fn new(service: GraspService, metrics: Metrics) -> Self {
        let limits = service.limits();
        let running = limits.max_concurrent_plans.max(1);
        let places = running.saturating_add(limits.max_queued_plans);
        Self {
            permits: Arc::new(Semaphore::new(running)),
            places: Arc::new(Semaphore::new(places.min(Semaphore::MAX_PERMITS))),
            service,
            metrics,
        }
    }

    pub fn service(&self) -> &GraspService {
        &self.service
    }

    pub fn metrics(&self) -> &Metrics {
        &self.metrics
    }

    /// Runs CPU-bound work (`what`: a plan, a hand import, a tactile analysis or calibration)
    /// on a blocking thread within the plans' limits — one pool for all of it, so a burst of
    /// hand imports is shed like one of plans rather than starving the planners (issue 20).
    /// `transport` labels the shedding metric.
    pub async fn run_blocking<T: Send + 'static>(
        &self,
        what: &'static str,
        transport: Transport,
        work: impl FnOnce(GraspService) -> Result<T, ServiceError> + Send + 'static,
    ) -> Result<T, ServiceError> {
        let limits = self.service.limits();
        let Ok(place) = self.places.clone().try_acquire_owned() else {
            self.metrics.shed(transport);
            tracing::debug!(transport = transport.name(), what, "request shed");
            return Err(ServiceError::Overloaded(format!(
                "the server is busy: {} CPU-bound requests (plans, hand imports, tactile analyses) are running and {} waiting (max_concurrent_plans, max_queued_plans); retry in {} s",
                limits.max_concurrent_plans,
                limits.max_queued_plans,
                SHED_RETRY_AFTER.as_secs()
            )));
        };
        let queued = GaugeGuard::new(self.metrics.plans_queued());
        let permit = self
            .permits
            .clone()
            .acquire_owned()
            .await
            .map_err(|_| ServiceError::Internal("the worker pool is closed".into()))?;
        drop(queued);
        let running = GaugeGuard::new(self.metrics.plans_running());
        let service = self.service.clone();
        // The slot, the place and the gauge go with the thread: work whose caller has gone
        // still occupies a worker until it ends.
        tokio::task::spawn_blocking(move || {
            let _held = (permit, place, running);
            work(service)
        })
        .await
        .unwrap_or_else(|e| Err(ServiceError::Internal(format!("{what} task failed: {e}"))))
    }

    /// Plans on a blocking thread ([`Self::run_blocking`]); `transport` labels the log line and
    /// the metrics.
    pub async fn plan(
        &self,
        request: PlanRequest,
        transport: Transport,
    ) -> Result<GraspPlan, ServiceError> {
        let started = Instant::now();
        let result = self
            .run_blocking("planning", transport, move |service| service.plan(request))
            .await;
        if matches!(result, Err(ServiceError::Overloaded(_))) {
            return result;
        }
        let seconds = started.elapsed().as_secs_f64();
        let transport_name = transport.name();
        match &result {
            Ok(plan) => {
                let outcome = if plan.feasible {
                    PlanOutcome::Feasible
                } else {
                    PlanOutcome::Infeasible
                };
                self.metrics.plan_finished(transport, outcome, Some(plan));
                tracing::info!(
                    transport = transport_name,
                    hand = %plan.hand,
                    grasp_type = %plan.grasp_type,
                    feasible = plan.feasible,
                    points = plan.points_used,
                    seconds,
                    "planned"
                )
            }
            Err(ServiceError::Internal(e)) => {
                self.metrics
                    .plan_finished(transport, PlanOutcome::Failed, None);
                tracing::error!(transport = transport_name, error = %e, seconds, "planning failed")
            }
            Err(e) => {
                self.metrics
                    .plan_finished(transport, PlanOutcome::Rejected, None);
                tracing::info!(transport = transport_name, error = %e, seconds, "plan request rejected")
            }
        }
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::facade::{HandChoice, Limits, PlanSource};
    use graspd_core::cloud::PointCloud;
    use nalgebra::Point3;

    fn request(n: usize) -> PlanRequest {
        let points: Vec<Point3<f64>> = (0..n)
            .map(|i| {
                let a = i as f64 * 2.399_963;
                let z = 0.1 * (i as f64 / n as f64);
                Point3::new(0.035 * a.cos(), 0.035 * a.sin(), z)
            })
            .collect();
        PlanRequest {
            source: PlanSource::Cloud(PointCloud::new(points)),
            extra_views: Vec::new(),
            hand: HandChoice::Name("shadow".into()),
            options: Default::default(),
            hints: Default::default(),
            image_hints: Default::default(),
            output: Default::default(),
        }
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn sheds_beyond_the_queue_and_releases_places() {
        let service = GraspService::builtin(Limits {
            max_concurrent_plans: 1,
            max_queued_plans: 1,
            ..Limits::default()
        });
        let metrics = Metrics::new();
        let runner = PlanRunner::new(service, metrics.clone());
        let mut tasks = Vec::new();
        for _ in 0..6 {
            let r = runner.clone();
            tasks.push(tokio::spawn(async move {
                r.plan(request(20_000), Transport::Rest).await
            }));
        }
        let mut shed = 0;
        let mut planned = 0;
        for t in tasks {
            match t.await.unwrap() {
                Ok(_) => planned += 1,
                Err(ServiceError::Overloaded(m)) => {
                    assert!(m.contains("max_queued_plans"), "{m}");
                    shed += 1
                }
                Err(e) => panic!("{e}"),
            }
        }
        assert!(shed >= 1 && planned >= 1, "shed {shed}, planned {planned}");
        assert_eq!(runner.places.available_permits(), 2);
        assert_eq!(runner.permits.available_permits(), 1);
        assert!(runner.plan(request(2000), Transport::Grpc).await.is_ok());
    }
}
