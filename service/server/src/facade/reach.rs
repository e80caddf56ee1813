//! PlanReach (issue 18 part 4): a reaching trajectory to a grasp, planned by
//! `graspd_core::reaching` (its rules and bounds are the domain's), panics contained.

use super::{GraspService, ServiceError, guarded};
use graspd_core::reaching::{ReachRequest, Trajectory, plan_reach};
use std::time::Instant;

impl GraspService {
    /// The trajectory and the time it took, ms. A reach that cannot keep its clearance is bad
    /// input naming the obstacle in the way.
    pub fn plan_reach(&self, request: &ReachRequest) -> Result<(Trajectory, f64), ServiceError> {
        let started = Instant::now();
        let trajectory = guarded("the reach planner", || {
            plan_reach(request).map_err(ServiceError::InvalidArgument)
        })?;
        Ok((trajectory, started.elapsed().as_secs_f64() * 1e3))
    }
}
