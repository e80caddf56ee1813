//! Which grasp type a hand with kinematics plans (issue 15): the detected type s* first
//! (method.md §4), then — unless the caller forced a type — the next most probable types the
//! hand realises, while none gives a firm plan; the hand's own plans decide between them
//! (docs/final-configuration.md, "Grasp types").

use super::final_configuration::{FIRM_ROBUSTNESS, FinalConfiguration};
use super::grasp_plan::StageStats;
use crate::hand::{HandDescription, ResolvedGrasp};
use std::time::Instant;

/// How much more robust another grasp type's best plan must be to replace the detected type's
/// (both feasible): the detector saw the object, the robustness figure only the contacts.
pub const DETECTED_TYPE_MARGIN: f64 = 1.25;
/// Most grasp types tried for one request.
pub const MAX_TYPES: usize = 3;

/// One grasp type's search (kinematic hands).
pub struct TypeAttempt {
    pub grasp: ResolvedGrasp,
    pub oppositions: Vec<(usize, usize)>,
    /// Its final configurations, best first.
    pub finals: Vec<FinalConfiguration>,
    /// Stage 1's and the final search's statistics, whether stage 1 met its constraints, and
    /// why not.
    pub stats: (StageStats, StageStats, bool, Option<String>),
    pub started: Instant,
}

impl TypeAttempt {
    /// Whether its best plan is feasible and firm ([`FIRM_ROBUSTNESS`]): no further type is
    /// tried then.
    pub fn firm(&self) -> bool {
        let best = self.finals.first();
        let firm = best.is_some_and(|f| f.feasible && f.robustness.weakest >= FIRM_ROBUSTNESS);
        tracing::debug!(
            grasp_type = %self.grasp.grasp_type,
            feasible = best.is_some_and(|f| f.feasible),
            robustness = best.map(|f| f.robustness.weakest),
            firm,
            "grasp type tried"
        );
        firm
    }
}

/// The attempt to plan with (index into `tried`, the detected type first): feasible first,
/// then the more robust, the detected type keeping its place unless another is
/// [`DETECTED_TYPE_MARGIN`] times as robust; ties (no final at all) go to the earlier, more
/// probable type. None when nothing was tried.
pub fn best(tried: &[TypeAttempt]) -> Option<usize> {
    let key = |k: usize| {
        let f = tried[k].finals.first();
        let margin = if k == 0 { DETECTED_TYPE_MARGIN } else { 1.0 };
        (
            f.is_some_and(|f| f.feasible),
            f.map_or(f64::NEG_INFINITY, |f| f.robustness.weakest * margin),
            -(k as f64),
        )
    };
    (0..tried.len()).max_by(|&a, &b| {
        key(a)
            .partial_cmp(&key(b))
            .unwrap_or(std::cmp::Ordering::Equal)
    })
}

/// The grasp types a kinematic hand tries (at most [`MAX_TYPES`]): the detected one, then the
/// others it realises, most probable first (`scores`, the detector's P(s|O), or the
/// dissertation's order when they tie), skipping those that resolve to the same fingers and
/// family as one already listed.
pub fn plausible_types(
    hand: &HandDescription,
    detected: &ResolvedGrasp,
    scores: &[f64; 6],
) -> Vec<ResolvedGrasp> {
    let family = |g: &ResolvedGrasp| {
        (
            g.h1_fingers.clone(),
            g.h2_fingers.clone(),
            g.h1_part,
            g.grasp_type.is_power(),
        )
    };
    let mut order = hand.realisable_types();
    order.sort_by(|a, b| scores[b.index()].total_cmp(&scores[a.index()]));
    let mut out = vec![detected.clone()];
    for t in order {
        if out.len() >= MAX_TYPES {
            break;
        }
        if let Some(g) = hand.resolve_forced(t)
            && !out.iter().any(|o| family(o) == family(&g))
        {
            out.push(g);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp_type::GraspType;
    use crate::hand::HandCatalog;

    /// The Shadow hand, precision detected: then the most probable other types, one per
    /// distinct realisation (power and large wrap close the same fingers around the object, so
    /// the less probable of them is skipped), at most three in all.
    #[test]
    fn plausible_types_follow_the_detector_and_skip_repeats() {
        let shadow = HandCatalog::builtin().get("shadow").unwrap().clone();
        let detected = shadow.resolve_forced(GraspType::Precision).unwrap();
        // large_wrap, small_wrap, power, pinch, precision, tripod
        let scores = [0.5, 0.05, 0.6, 0.1, 0.7, 0.3];
        let types: Vec<GraspType> = plausible_types(&shadow, &detected, &scores)
            .iter()
            .map(|g| g.grasp_type)
            .collect();
        assert_eq!(types.len(), MAX_TYPES);
        assert_eq!(types[0], GraspType::Precision);
        assert_eq!(types[1], GraspType::Power);
        assert!(!types.contains(&GraspType::LargeWrap), "{types:?}");
        assert_eq!(types[2], GraspType::Tripod);
    }
}
