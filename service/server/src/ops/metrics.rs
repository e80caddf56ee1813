//! Prometheus metrics (`GET /metrics`, OpenMetrics text): requests by transport, route and code,
//! their latency, requests in flight, refusals (unauthenticated, shed), the planner's and the
//! perception's per-stage latency, plans running and queued, open tactile sessions, readiness.
//!
//! Labels stay bounded: routes are the REST route templates and the known gRPC methods (anything
//! else is `unmatched` / `other`), codes are gRPC code names or HTTP statuses.

use super::Transport;
use graspd_core::GraspPlan;
use prometheus_client::encoding::EncodeLabelSet;
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::Registry;
use std::borrow::Cow;
use std::sync::Arc;

/// The content type of the exposition.
pub const CONTENT_TYPE: &str = "application/openmetrics-text; version=1.0.0; charset=utf-8";

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RequestLabels {
    transport: &'static str,
    route: Cow<'static, str>,
    code: Cow<'static, str>,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RouteLabels {
    transport: &'static str,
    route: Cow<'static, str>,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct TransportLabels {
    transport: &'static str,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct StageLabels {
    stage: &'static str,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct PlanLabels {
    transport: &'static str,
    outcome: &'static str,
}

type HistogramFamily<L> = Family<L, Histogram, fn() -> Histogram>;

/// Request latency: 1 ms … about 65 s.
fn request_histogram() -> Histogram {
    Histogram::new(exponential_buckets(0.001, 2.0, 17))
}

/// Stage latency: 0.1 ms … about 13 s.
fn stage_histogram() -> Histogram {
    Histogram::new(exponential_buckets(0.0001, 2.0, 18))
}

/// What a plan ended as, for `graspd_plans_total`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlanOutcome {
    Feasible,
    Infeasible,
    /// Bad input: the facade refused it.
    Rejected,
    /// A bug: the planner failed.
    Failed,
}

impl PlanOutcome {
    fn label(self) -> &'static str {
        match self {
            PlanOutcome::Feasible => "feasible",
            PlanOutcome::Infeasible => "infeasible",
            PlanOutcome::Rejected => "rejected",
            PlanOutcome::Failed => "failed",
        }
    }
}

struct Inner {
    registry: Registry,
    requests: Family<RequestLabels, Counter>,
    errors: Family<RequestLabels, Counter>,
    duration: HistogramFamily<RouteLabels>,
    in_flight: Family<TransportLabels, Gauge>,
    unauthenticated: Family<TransportLabels, Counter>,
    shed: Family<TransportLabels, Counter>,
    plans: Family<PlanLabels, Counter>,
    plan_stages: HistogramFamily<StageLabels>,
    perception_stages: HistogramFamily<StageLabels>,
    plans_running: Gauge,
    plans_queued: Gauge,
    tactile_sessions: Gauge,
    ready: Gauge,
}

/// The service's metrics; cheap to clone (shared).
#[derive(Clone)]
pub struct Metrics {
    inner: Arc<Inner>,
}

impl std::fmt::Debug for Metrics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Metrics")
    }
}

impl Default for Metrics {
    fn default() -> Self {
        Self::new()
    }
}

impl Metrics {
    pub fn new() -> Self {
        let mut registry = Registry::with_prefix("graspd");
        let requests = Family::<RequestLabels, Counter>::default();
        registry.register(
            "requests",
            "Requests answered, by transport, route (REST 'METHOD /template', gRPC '/package.Service/Method') and code (gRPC code name or HTTP status)",
            requests.clone(),
        );
        let errors = Family::<RequestLabels, Counter>::default();
        registry.register(
            "request_errors",
            "Requests answered with an error (gRPC code other than OK, HTTP status 400 or more), by transport, route and code",
            errors.clone(),
        );
        let duration: HistogramFamily<RouteLabels> =
            Family::new_with_constructor(request_histogram);
        registry.register(
            "request_duration_seconds",
            "Time from a request's arrival to the end of its answer (streams: their whole life), by transport and route",
            duration.clone(),
        );
        let in_flight = Family::<TransportLabels, Gauge>::default();
        registry.register(
            "requests_in_flight",
            "Requests being handled (open streams included), by transport",
            in_flight.clone(),
        );
        let unauthenticated = Family::<TransportLabels, Counter>::default();
        registry.register(
            "unauthenticated_requests",
            "Requests refused for a missing or wrong bearer token, by transport",
            unauthenticated.clone(),
        );
        let shed = Family::<TransportLabels, Counter>::default();
        registry.register(
            "shed_requests",
            "CPU-bound requests (plans, hand imports, tactile analyses, calibrations) refused because max_concurrent_plans were running and max_queued_plans waiting, by transport",
            shed.clone(),
        );
        let plans = Family::<PlanLabels, Counter>::default();
        registry.register(
            "plans",
            "Plans computed, by transport and outcome (feasible, infeasible, rejected, failed)",
            plans.clone(),
        );
        let plan_stages: HistogramFamily<StageLabels> =
            Family::new_with_constructor(stage_histogram);
        registry.register(
            "plan_stage_duration_seconds",
            "Planner time per stage of each plan (the plan's timings: preprocess, normals, grasp_type, stage1, stage2, finalize, total)",
            plan_stages.clone(),
        );
        let perception_stages: HistogramFamily<StageLabels> =
            Family::new_with_constructor(stage_histogram);
        registry.register(
            "perception_stage_duration_seconds",
            "Perception time per step of each RGB-D plan (decode, saliency, segmentation, roi, grasp_type, total)",
            perception_stages.clone(),
        );
        let plans_running = Gauge::default();
        registry.register(
            "plans_running",
            "CPU-bound requests being computed (plans, hand imports, tactile analyses, calibrations; at most max_concurrent_plans), including those whose caller has gone",
            plans_running.clone(),
        );
        let plans_queued = Gauge::default();
        registry.register(
            "plans_queued",
            "CPU-bound requests waiting for a worker (at most max_queued_plans)",
            plans_queued.clone(),
        );
        let tactile_sessions = Gauge::default();
        registry.register(
            "tactile_sessions_active",
            "Open tactile sessions (Stabilize streams, WebSockets and analyze calls)",
            tactile_sessions.clone(),
        );
        let ready = Gauge::default();
        registry.register(
            "ready",
            "1 while the server is ready (/readyz answers 200), 0 while starting or draining",
            ready.clone(),
        );
        // The refusal counters and the in-flight gauges show 0 before the first event.
        for transport in [Transport::Grpc, Transport::Rest] {
            let labels = TransportLabels {
                transport: transport.name(),
            };
            let _ = unauthenticated.get_or_create(&labels);
            let _ = shed.get_or_create(&labels);
            let _ = in_flight.get_or_create(&labels);
        }
        Self {
            inner: Arc::new(Inner {
                registry,
                requests,
                errors,
                duration,
                in_flight,
                unauthenticated,
                shed,
                plans,
                plan_stages,
                perception_stages,
                plans_running,
                plans_queued,
                tactile_sessions,
                ready,
            }),
        }
    }

    /// A request has arrived: one more in flight.
    pub(crate) fn request_started(&self, transport: Transport) {
        self.inner
            .in_flight
            .get_or_create(&TransportLabels {
                transport: transport.name(),
            })
            .inc();
    }

    /// A request has been answered (or abandoned): one fewer in flight, counted by code.
    pub(crate) fn request_finished(
        &self,
        transport: Transport,
        route: Cow<'static, str>,
        code: Cow<'static, str>,
        error: bool,
        seconds: f64,
    ) {
        let t = transport.name();
        self.inner
            .in_flight
            .get_or_create(&TransportLabels { transport: t })
            .dec();
        let labels = RequestLabels {
            transport: t,
            route,
            code,
        };
        self.inner.requests.get_or_create(&labels).inc();
        if error {
            self.inner.errors.get_or_create(&labels).inc();
        }
        self.inner
            .duration
            .get_or_create(&RouteLabels {
                transport: t,
                route: labels.route,
            })
            .observe(seconds);
    }

    pub(crate) fn unauthenticated(&self, transport: Transport) {
        self.inner
            .unauthenticated
            .get_or_create(&TransportLabels {
                transport: transport.name(),
            })
            .inc();
    }

    pub(crate) fn shed(&self, transport: Transport) {
        self.inner
            .shed
            .get_or_create(&TransportLabels {
                transport: transport.name(),
            })
            .inc();
    }

    pub(crate) fn plans_running(&self) -> &Gauge {
        &self.inner.plans_running
    }

    pub(crate) fn plans_queued(&self) -> &Gauge {
        &self.inner.plans_queued
    }

    /// Counts a plan and, when there is one, observes its stage timings.
    pub(crate) fn plan_finished(
        &self,
        transport: Transport,
        outcome: PlanOutcome,
        plan: Option<&GraspPlan>,
    ) {
        self.inner
            .plans
            .get_or_create(&PlanLabels {
                transport: transport.name(),
                outcome: outcome.label(),
            })
            .inc();
        let Some(plan) = plan else { return };
        let t = &plan.timings;
        for (stage, seconds) in [
            ("preprocess", t.preprocess),
            ("normals", t.normals),
            ("grasp_type", t.grasp_type),
            ("stage1", t.stage1),
            ("stage2", t.stage2),
            ("finalize", t.finalize),
            ("total", t.total),
        ] {
            self.inner
                .plan_stages
                .get_or_create(&StageLabels { stage })
                .observe(seconds);
        }
        if let Some(perception) = &plan.perception {
            let t = &perception.timings;
            for (stage, seconds) in [
                ("decode", t.decode),
                ("saliency", t.saliency),
                ("segmentation", t.segmentation),
                ("roi", t.roi),
                ("grasp_type", t.grasp_type),
                ("total", t.total),
            ] {
                self.inner
                    .perception_stages
                    .get_or_create(&StageLabels { stage })
                    .observe(seconds);
            }
        }
    }

    /// The exposition, with the gauges read at scrape time set first.
    pub fn render(&self, tactile_sessions: usize, ready: bool) -> String {
        self.inner
            .tactile_sessions
            .set(i64::try_from(tactile_sessions).unwrap_or(i64::MAX));
        self.inner.ready.set(i64::from(ready));
        let mut text = String::new();
        // Writing into a String cannot fail.
        let _ = prometheus_client::encoding::text::encode(&mut text, &self.inner.registry);
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exposition_names_labels_and_buckets() {
        let m = Metrics::new();
        m.request_started(Transport::Grpc);
        m.request_finished(
            Transport::Grpc,
            Cow::Borrowed("/graspd.v1.GraspPlanner/PlanGrasp"),
            Cow::Borrowed("OK"),
            false,
            0.02,
        );
        m.request_started(Transport::Rest);
        m.request_finished(
            Transport::Rest,
            Cow::Borrowed("POST /v1/plan"),
            Cow::Borrowed("401"),
            true,
            0.001,
        );
        m.unauthenticated(Transport::Rest);
        m.shed(Transport::Grpc);
        let text = m.render(3, true);
        for needle in [
            "graspd_requests_total{transport=\"grpc\",route=\"/graspd.v1.GraspPlanner/PlanGrasp\",code=\"OK\"} 1",
            "graspd_request_errors_total{transport=\"rest\",route=\"POST /v1/plan\",code=\"401\"} 1",
            "graspd_requests_in_flight{transport=\"grpc\"} 0",
            "graspd_request_duration_seconds_bucket{le=\"0.032\",transport=\"grpc\",route=\"/graspd.v1.GraspPlanner/PlanGrasp\"} 1",
            "graspd_unauthenticated_requests_total{transport=\"rest\"} 1",
            "graspd_shed_requests_total{transport=\"grpc\"} 1",
            "graspd_tactile_sessions_active 3",
            "graspd_ready 1",
            "# EOF",
        ] {
            assert!(text.contains(needle), "missing {needle} in\n{text}");
        }
        assert!(
            !text.contains("graspd_request_errors_total{transport=\"grpc\""),
            "{text}"
        );
    }
}
