//! The planning pipeline (Algorithm 4): support plane, normals, grasp type and attention point,
//! stage 1 (pregrasping opposition), stage 2 (final contacts), hand pose and checks.

use super::types::{GraspPlan, PlanHints, PlannerOptions};
use crate::cloud::PointCloud;
use crate::error::PlanError;
use crate::hand::HandDescription;

/// One planning request in domain terms (already validated at the edge).
#[derive(Debug, Clone)]
pub struct PlanInput {
    pub cloud: PointCloud,
    pub hand: HandDescription,
    pub hints: PlanHints,
    pub options: PlannerOptions,
}

/// Plans a grasp (Algorithm 4). Deterministic for a given input and seed.
pub fn plan(input: PlanInput) -> Result<GraspPlan, PlanError> {
    let _ = input;
    Err(PlanError::Unimplemented("planner under construction".into()))
}
