//! Limits on untrusted input and on what one request may cost, configured at start.

use graspd_core::perception::RgbdLimits;
use graspd_core::{FieldError, PlannerOptions};

/// Limits on untrusted input, enforced by the transports (bytes) and by the facade (points).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest gRPC message or REST body, bytes.
    pub max_message_bytes: usize,
    /// Largest cloud, points.
    pub max_points: usize,
    /// Plans computed at once; more wait (planning is CPU-bound).
    pub max_concurrent_plans: usize,
    /// Plan requests waiting for a planner; more are shed (RESOURCE_EXHAUSTED, 503).
    pub max_queued_plans: usize,
    /// Tactile sessions open at once (streams and analyze calls); more are refused
    /// (RESOURCE_EXHAUSTED, 503).
    pub max_tactile_sessions: usize,
    /// Largest RGB-D frame, `width × height` pixels (also what a PNG or JPEG may decode to).
    pub max_image_pixels: usize,
    /// Most further views (`extra_views`) fused into one plan request.
    pub max_views: usize,
    /// Most stage-1 iterations a request may ask for (`options.max_iterations`): what one plan
    /// may cost in CPU. Within the planner's own bound, [`graspd_core::planning::MAX_ITERATIONS`].
    pub max_iterations: usize,
}

/// Default of [`Limits::max_iterations`].
pub const DEFAULT_MAX_ITERATIONS: usize = 100_000;

impl Limits {
    /// A cloud of `n` points (as its message claims, before reading them) within `max_points`;
    /// else TooLarge naming `field`.
    pub fn check_points(&self, n: u64, field: &str) -> Result<(), crate::error::ServiceError> {
        if n > self.max_points as u64 {
            return Err(crate::error::ServiceError::TooLarge(FieldError::new(
                field,
                format!(
                    "{n} points exceed the configured limit of {} (max_points)",
                    self.max_points
                ),
            )));
        }
        Ok(())
    }

    /// The limits' share of the options' rules (their ranges are
    /// `PlannerOptions::validate`'s): how much CPU one request may ask for.
    pub fn check_options(&self, o: &PlannerOptions) -> Result<(), FieldError> {
        if o.max_iterations > self.max_iterations {
            return Err(FieldError::new(
                "options.max_iterations",
                format!(
                    "must be at most {}, this server's limit (max_iterations), got {}",
                    self.max_iterations, o.max_iterations
                ),
            ));
        }
        Ok(())
    }
}

/// Default of [`Limits::max_views`].
pub const DEFAULT_MAX_VIEWS: usize = 8;

/// Default of [`Limits::max_tactile_sessions`].
pub const DEFAULT_MAX_TACTILE_SESSIONS: usize = 64;

/// Default of [`Limits::max_queued_plans`], per planner of `max_concurrent_plans`.
pub const QUEUED_PLANS_PER_PLANNER: usize = 4;

fn default_concurrent_plans() -> usize {
    std::thread::available_parallelism().map_or(2, |n| n.get())
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_message_bytes: 32 * 1024 * 1024,
            max_points: 500_000,
            max_concurrent_plans: default_concurrent_plans(),
            max_queued_plans: QUEUED_PLANS_PER_PLANNER * default_concurrent_plans(),
            max_tactile_sessions: DEFAULT_MAX_TACTILE_SESSIONS,
            max_image_pixels: RgbdLimits::default().max_pixels,
            max_views: DEFAULT_MAX_VIEWS,
            max_iterations: DEFAULT_MAX_ITERATIONS,
        }
    }
}
