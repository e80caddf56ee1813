//! The one facade that both transports call: the hand catalog, the configured limits, and the
//! validation of a plan request before it reaches the planner. Plain Rust and synchronous (no
//! tonic, axum, tokio or proto types), so it also serves as the library entry point.

use graspd_core::cloud::{Plane, PointCloud};
use graspd_core::{
    FieldError, GraspPlan, HandCatalog, HandDescription, PlanError, PlanHints, PlanInput,
    PlannerOptions,
};
use nalgebra::Point3;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use thiserror::Error;

/// Limits on untrusted input, enforced by the transports (bytes) and by the facade (points).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest gRPC message or REST body, bytes.
    pub max_message_bytes: usize,
    /// Largest cloud, points.
    pub max_points: usize,
    /// Plans computed at once; more wait (planning is CPU-bound).
    pub max_concurrent_plans: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_message_bytes: 32 * 1024 * 1024,
            max_points: 500_000,
            max_concurrent_plans: std::thread::available_parallelism().map_or(2, |n| n.get()),
        }
    }
}

/// What the plan is computed from.
#[derive(Debug, Clone, PartialEq)]
pub enum PlanSource {
    /// A cloud as decoded at the edge; the facade validates it.
    Cloud(PointCloud),
    /// An RGB-D frame. Not implemented yet: the facade answers `Unimplemented`.
    Rgbd,
}

/// Which hand to plan for.
#[derive(Debug, Clone, PartialEq)]
pub enum HandChoice {
    /// A hand of the catalog.
    Name(String),
    /// An inline description, validated like the data files.
    Inline(Box<HandDescription>),
}

/// Hints that only make sense on an image (RGB-D input). Any of them set answers `Unimplemented`
/// rather than being ignored.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ImageHints {
    pub attention_pixel: bool,
    pub region: bool,
    pub most_salient: bool,
}

impl ImageHints {
    pub fn any(&self) -> bool {
        self.attention_pixel || self.region || self.most_salient
    }
}

/// One plan request in domain terms, as both transports produce it.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanRequest {
    pub source: PlanSource,
    pub hand: HandChoice,
    pub options: PlannerOptions,
    pub hints: PlanHints,
    pub image_hints: ImageHints,
}

/// Errors of the facade; each transport maps them to its status codes.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ServiceError {
    /// Bad input (gRPC INVALID_ARGUMENT, HTTP 400).
    #[error(transparent)]
    InvalidArgument(FieldError),
    /// A named thing does not exist (NOT_FOUND, 404).
    #[error(transparent)]
    NotFound(FieldError),
    /// Input over a configured limit (RESOURCE_EXHAUSTED, 413).
    #[error(transparent)]
    TooLarge(FieldError),
    /// Valid but not implemented yet (UNIMPLEMENTED, 501).
    #[error("{0}")]
    Unimplemented(String),
    /// A bug: the planner failed (INTERNAL, 500).
    #[error("internal error: {0}")]
    Internal(String),
}

impl ServiceError {
    /// The offending field, when the error is about one.
    pub fn field(&self) -> Option<&str> {
        match self {
            ServiceError::InvalidArgument(e)
            | ServiceError::NotFound(e)
            | ServiceError::TooLarge(e) => Some(&e.field),
            _ => None,
        }
    }
}

impl From<FieldError> for ServiceError {
    fn from(e: FieldError) -> Self {
        ServiceError::InvalidArgument(e)
    }
}

impl From<PlanError> for ServiceError {
    fn from(e: PlanError) -> Self {
        match e {
            PlanError::InvalidInput(f) => ServiceError::InvalidArgument(f),
            PlanError::Unimplemented(m) => ServiceError::Unimplemented(m),
        }
    }
}

/// The grasp-planning service. Cheap to clone (shared state).
#[derive(Debug, Clone)]
pub struct GraspService {
    inner: Arc<Inner>,
}

#[derive(Debug)]
struct Inner {
    catalog: HandCatalog,
    limits: Limits,
}

impl GraspService {
    pub fn new(catalog: HandCatalog, limits: Limits) -> Self {
        Self {
            inner: Arc::new(Inner { catalog, limits }),
        }
    }

    /// The built-in hands with the given limits.
    pub fn builtin(limits: Limits) -> Self {
        Self::new(HandCatalog::builtin(), limits)
    }

    pub fn limits(&self) -> &Limits {
        &self.inner.limits
    }

    /// All hands of the catalog, by name.
    pub fn list_hands(&self) -> Vec<HandDescription> {
        self.inner.catalog.list().cloned().collect()
    }

    /// One hand; `field` names the name in the error (`name`, `hand_name`).
    pub fn get_hand(&self, name: &str, field: &str) -> Result<HandDescription, ServiceError> {
        self.inner
            .catalog
            .get(name)
            .cloned()
            .ok_or_else(|| ServiceError::NotFound(self.unknown_hand(name, field)))
    }

    /// Registering hands at run time is not implemented yet; inline descriptions work per
    /// request, and the catalog's hands are data files.
    pub fn register_hand(&self) -> Result<(), ServiceError> {
        Err(ServiceError::Unimplemented(
            "registering hands is not implemented yet; send the hand inline as hand_description in each plan request".into(),
        ))
    }

    /// Validates a request and plans (Algorithm 4). Blocking and CPU-bound: async callers run it
    /// on a blocking thread. A planner panic becomes `Internal`, so one bad request cannot take
    /// the service down.
    pub fn plan(&self, request: PlanRequest) -> Result<GraspPlan, ServiceError> {
        let input = self.prepare(request)?;
        match catch_unwind(AssertUnwindSafe(|| graspd_core::plan(input))) {
            Ok(result) => result.map_err(ServiceError::from),
            Err(panic) => {
                let what = panic
                    .downcast_ref::<String>()
                    .map(String::as_str)
                    .or_else(|| panic.downcast_ref::<&str>().copied())
                    .unwrap_or("unknown panic");
                Err(ServiceError::Internal(format!(
                    "the planner failed: {what}"
                )))
            }
        }
    }

    /// Checks a request against the catalog and the limits and turns it into planner input.
    pub fn prepare(&self, request: PlanRequest) -> Result<PlanInput, ServiceError> {
        if request.image_hints.any() {
            return Err(ServiceError::Unimplemented(
                "image hints (attention_pixel, region, most_salient) are not implemented yet; give hints.attention_point in the cloud's frame".into(),
            ));
        }
        let mut cloud = match request.source {
            PlanSource::Cloud(cloud) => cloud,
            PlanSource::Rgbd => {
                return Err(ServiceError::Unimplemented(
                    "RGB-D input is not implemented yet; send a point cloud".into(),
                ));
            }
        };
        let hand = match request.hand {
            HandChoice::Name(name) => self.hand_by_name(&name)?,
            HandChoice::Inline(hand) => {
                hand.validate()
                    .map_err(|e| rename_hand_field(e, "hand_description"))?;
                *hand
            }
        };
        let max_points = self.inner.limits.max_points;
        if cloud.len() > max_points {
            return Err(ServiceError::TooLarge(FieldError::new(
                "cloud.points",
                format!(
                    "{} points exceed the configured limit of {max_points} (max_points)",
                    cloud.len()
                ),
            )));
        }
        cloud.validate("cloud", max_points)?;
        let hints = validate_hints(request.hints, &hand)?;
        validate_options(&request.options)?;
        Ok(PlanInput {
            cloud,
            hand,
            hints,
            options: request.options,
        })
    }

    fn hand_by_name(&self, name: &str) -> Result<HandDescription, ServiceError> {
        self.inner
            .catalog
            .get(name)
            .cloned()
            .ok_or_else(|| ServiceError::InvalidArgument(self.unknown_hand(name, "hand_name")))
    }

    fn unknown_hand(&self, name: &str, field: &str) -> FieldError {
        if name.is_empty() {
            return FieldError::new(
                field,
                format!(
                    "no hand given (known: {})",
                    self.inner.catalog.names().join(", ")
                ),
            );
        }
        FieldError::new(
            field,
            format!(
                "unknown hand '{}' (known: {})",
                name.escape_debug(),
                self.inner.catalog.names().join(", ")
            ),
        )
    }
}

/// The core names inline hands `hand.*`; the API calls the field `hand_description`.
fn rename_hand_field(e: FieldError, to: &str) -> ServiceError {
    let field = match e.field.strip_prefix("hand") {
        Some(rest) => format!("{to}{rest}"),
        None => e.field,
    };
    ServiceError::InvalidArgument(FieldError::new(field, e.message))
}

fn finite_point(p: &Point3<f64>, field: &str) -> Result<(), FieldError> {
    if p.coords.iter().all(|v| v.is_finite() && v.abs() <= 1.0e3) {
        Ok(())
    } else {
        Err(FieldError::new(
            field,
            "coordinates must be finite and within ±1000 m",
        ))
    }
}

fn validate_hints(mut hints: PlanHints, hand: &HandDescription) -> Result<PlanHints, FieldError> {
    if let Some(t) = hints.grasp_type
        && !hand.supports(t)
    {
        let can: Vec<&str> = hand.realisable_types().iter().map(|t| t.name()).collect();
        return Err(FieldError::new(
            "hints.grasp_type",
            format!(
                "hand '{}' cannot realise {t} (it realises: {})",
                hand.name,
                can.join(", ")
            ),
        ));
    }
    if let Some(p) = &hints.attention_point {
        finite_point(p, "hints.attention_point")?;
    }
    if let Some(p) = &hints.viewpoint {
        finite_point(p, "hints.viewpoint")?;
    }
    if let Some(plane) = hints.support_plane {
        hints.support_plane = Some(Plane::checked(
            plane.normal,
            plane.offset,
            "hints.support_plane",
        )?);
    }
    if let Some(up) = hints.up {
        let len = up.norm();
        if !len.is_finite() || len < 1e-9 {
            return Err(FieldError::new("hints.up", "must be finite and non-zero"));
        }
        hints.up = Some(up / len);
    }
    Ok(hints)
}

fn check(ok: bool, field: &str, message: impl Into<String>) -> Result<(), FieldError> {
    if ok {
        Ok(())
    } else {
        Err(FieldError::new(format!("options.{field}"), message))
    }
}

fn in_range(v: f64, lo: f64, hi: f64, field: &str) -> Result<(), FieldError> {
    check(
        v.is_finite() && (lo..=hi).contains(&v),
        field,
        format!("must be in [{lo}, {hi}], got {v}"),
    )
}

/// Bounds that keep one request from running away with the CPU or producing nonsense.
pub const MAX_ITERATIONS_LIMIT: usize = 100_000;
pub const MAX_CANDIDATES_LIMIT: usize = 100_000;

fn validate_options(o: &PlannerOptions) -> Result<(), FieldError> {
    in_range(o.epsilon, 0.0, 1.0, "epsilon")?;
    check(
        o.friction.is_finite() && o.friction > 0.0 && o.friction <= 10.0,
        "friction",
        format!("must be in (0, 10], got {}", o.friction),
    )?;
    in_range(o.torsion_gamma, 0.0, 100.0, "torsion_gamma")?;
    for (name, w) in [
        ("stage1_weights", o.stage1_weights),
        ("stage2_weights", o.stage2_weights),
    ] {
        check(
            w.iter().all(|v| v.is_finite() && *v >= 0.0) && w.iter().sum::<f64>() > 0.0,
            name,
            format!("must be two finite non-negative weights, not both zero, got {w:?}"),
        )?;
    }
    check(
        o.iteration_fraction.is_finite()
            && o.iteration_fraction > 0.0
            && o.iteration_fraction <= 1.0,
        "iteration_fraction",
        format!("must be in (0, 1], got {}", o.iteration_fraction),
    )?;
    check(
        o.max_iterations >= 1 && o.max_iterations <= MAX_ITERATIONS_LIMIT,
        "max_iterations",
        format!(
            "must be in [1, {MAX_ITERATIONS_LIMIT}], got {}",
            o.max_iterations
        ),
    )?;
    check(
        o.min_iterations <= o.max_iterations,
        "min_iterations",
        format!(
            "must not exceed max_iterations ({}), got {}",
            o.max_iterations, o.min_iterations
        ),
    )?;
    check(
        o.patience >= 1,
        "patience",
        "must be at least 1".to_string(),
    )?;
    check(
        o.restarts <= 10,
        "restarts",
        format!("must be at most 10, got {}", o.restarts),
    )?;
    for (name, v) in [("lambda1", o.lambda1), ("lambda2", o.lambda2)] {
        if let Some(v) = v {
            check(
                v.is_finite() && v > 0.0 && v <= 1.0,
                name,
                format!("must be a radius in (0, 1] m, got {v}"),
            )?;
        }
    }
    for (name, v) in [
        ("opposition_candidates", o.opposition_candidates),
        ("contact_candidates", o.contact_candidates),
    ] {
        check(
            (1..=MAX_CANDIDATES_LIMIT).contains(&v),
            name,
            format!("must be in [1, {MAX_CANDIDATES_LIMIT}], got {v}"),
        )?;
    }
    check(
        (3..=100).contains(&o.normals_k),
        "normals_k",
        format!("must be in [3, 100], got {}", o.normals_k),
    )?;
    in_range(o.pregrasp_distance, 0.0, 1.0, "pregrasp_distance")?;
    check(
        (3..=64).contains(&o.friction_cone_edges),
        "friction_cone_edges",
        format!("must be in [3, 64], got {}", o.friction_cone_edges),
    )?;
    check(
        o.max_center_offset.is_finite() && o.max_center_offset > 0.0 && o.max_center_offset <= 10.0,
        "max_center_offset",
        format!("must be in (0, 10], got {}", o.max_center_offset),
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use graspd_core::GraspType;
    use nalgebra::Vector3;

    fn cylinder(n: usize) -> PointCloud {
        let pts = (0..n)
            .map(|i| {
                let a = i as f64 * 0.7;
                Point3::new(
                    0.035 * a.cos(),
                    0.035 * a.sin(),
                    0.1 * (i as f64 / n as f64),
                )
            })
            .collect();
        PointCloud::new(pts)
    }

    fn request(hand: &str) -> PlanRequest {
        PlanRequest {
            source: PlanSource::Cloud(cylinder(100)),
            hand: HandChoice::Name(hand.into()),
            options: PlannerOptions::default(),
            hints: PlanHints::default(),
            image_hints: ImageHints::default(),
        }
    }

    fn field_of(r: Result<PlanInput, ServiceError>) -> String {
        r.unwrap_err().field().unwrap_or("-").to_string()
    }

    #[test]
    fn valid_request_prepares() {
        let s = GraspService::builtin(Limits::default());
        let input = s.prepare(request("shadow")).unwrap();
        assert_eq!(input.hand.name, "shadow");
        assert_eq!(input.cloud.len(), 100);
    }

    #[test]
    fn errors_name_the_field() {
        let s = GraspService::builtin(Limits::default());
        let e = s.prepare(request("foo")).unwrap_err();
        assert_eq!(e.field(), Some("hand_name"));
        assert!(
            e.to_string()
                .contains("known: barrett, parallel_gripper, shadow")
        );

        let mut r = request("parallel_gripper");
        r.hints.grasp_type = Some(GraspType::Tripod);
        assert_eq!(field_of(s.prepare(r)), "hints.grasp_type");

        let mut r = request("shadow");
        r.options.epsilon = f64::NAN;
        assert_eq!(field_of(s.prepare(r)), "options.epsilon");

        let mut r = request("shadow");
        r.options.max_iterations = 10_000_000;
        assert_eq!(field_of(s.prepare(r)), "options.max_iterations");

        let mut r = request("shadow");
        r.hints.support_plane = Some(Plane {
            normal: Vector3::zeros(),
            offset: 0.0,
        });
        assert_eq!(field_of(s.prepare(r)), "hints.support_plane");

        let mut hand = s.get_hand("barrett", "name").unwrap();
        hand.geometry.max_aperture = -1.0;
        let mut r = request("shadow");
        r.hand = HandChoice::Inline(Box::new(hand));
        assert_eq!(
            field_of(s.prepare(r)),
            "hand_description.geometry.max_aperture"
        );
    }

    #[test]
    fn limits_and_unimplemented_inputs() {
        let s = GraspService::builtin(Limits {
            max_points: 50,
            ..Limits::default()
        });
        assert!(matches!(
            s.prepare(request("shadow")),
            Err(ServiceError::TooLarge(_))
        ));
        let mut r = request("shadow");
        r.source = PlanSource::Rgbd;
        assert!(matches!(s.prepare(r), Err(ServiceError::Unimplemented(m)) if m.contains("RGB-D")));
        let mut r = request("shadow");
        r.image_hints.most_salient = true;
        assert!(matches!(s.prepare(r), Err(ServiceError::Unimplemented(_))));
    }
}
