//! Stage 2 and the orchestration of the dual-stage search (ch. 5.4.2, Algorithm 4).
//!
//! Stage 2 places the m final contacts C_g near the pregrasping opposition: the h1-side contacts in
//! Φ(oc1, λ₂), the h2-side contacts in Φ(oc2, λ₂ + the fingers' half span) (Eq 5.6 with
//! p_ref = C_o), maximising Q = 0.7·R + 0.3·G subject to S ≥ ε. Fingers on one side must be
//! at least a finger width and at most the hand's splay apart, and every contact must push toward
//! the other side. The "without opposition" ablation (Table 5.1) runs the same problem with every
//! slot drawing from the whole cloud.

use super::annealing::{Annealed, Schedule, Scored, SearchProblem, anneal};
use super::evaluation::{Assessment, SearchContext};
use super::grasp_plan::StageStats;
use super::opposition::OppositionSearch;
use super::request::PlannerMode;
use super::slot_set::SlotSet;
use nalgebra::{Point3, Vector3};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

/// cos 75°: a contact's normal must point at least this much away from the other side.
const MIN_PUSH_COS: f64 = 0.2588;

/// Stage 2 (or the ablation) as a search problem: slots 0..k1 are the h1 side, the rest h2.
pub struct ContactSearch<'c, 'a> {
    pub ctx: &'c SearchContext<'a>,
    pub slots: Vec<SlotSet>,
    /// Where each slot's contact is aimed (stage 2); empty for the ablation.
    targets: Vec<Point3<f64>>,
    pub k1: usize,
    pub weights: [f64; 2],
}

impl<'c, 'a> ContactSearch<'c, 'a> {
    /// Stage 2 around the opposition (oc1, oc2): each contact gets its own neighbourhood
    /// Φ(target, λ₂) (Eq 5.6 with p_ref = C_o), the h2 fingers' targets spread along the
    /// opposition's lateral axis `frame_y` at the fingers' spacing.
    pub fn around(
        ctx: &'c SearchContext<'a>,
        oc: (usize, usize),
        lambda: f64,
        frame_y: &Vector3<f64>,
    ) -> Self {
        let k1 = ctx.grasp.h1_count();
        let k2 = ctx.grasp.h2_fingers.len();
        let spacing = finger_spacing(ctx);
        let offsets = |k: usize| (0..k).map(move |f| (f as f64 - (k as f64 - 1.0) / 2.0) * spacing);
        let targets: Vec<Point3<f64>> = offsets(k1)
            .map(|o| ctx.points[oc.0] + frame_y * o)
            .chain(offsets(k2).map(|o| ctx.points[oc.1] + frame_y * o))
            .collect();
        let slots = targets
            .iter()
            .map(|t| {
                SlotSet::around(
                    ctx.points,
                    ctx.index,
                    t,
                    lambda,
                    ctx.options.contact_candidates,
                )
            })
            .collect();
        Self {
            ctx,
            slots,
            targets,
            k1,
            weights: ctx.options.stage2_weights,
        }
    }

    /// The ablation: every slot draws from the whole cloud.
    pub fn whole_cloud(ctx: &'c SearchContext<'a>) -> Self {
        let m = ctx.grasp.contact_count();
        Self {
            ctx,
            slots: vec![SlotSet::whole(ctx.points.len()); m],
            targets: Vec::new(),
            k1: ctx.grasp.h1_count(),
            weights: ctx.options.stage2_weights,
        }
    }

    /// |Φ_ĝ|: the product of the slots' candidate counts (ordered, as the text's 120³).
    pub fn solution_space(&self) -> f64 {
        self.slots.iter().map(|c| c.len() as f64).product()
    }

    /// Whether some slot has no candidate (λ₂ too small for the cloud's density).
    pub fn has_empty_slot(&self) -> bool {
        self.slots.iter().any(SlotSet::is_empty)
    }

    /// A start at the candidates nearest each slot's target (distinct points).
    pub fn initial_at_targets(&self) -> Vec<usize> {
        let mut config: Vec<usize> = Vec::with_capacity(self.slots.len());
        for (slot, target) in self.slots.iter().zip(&self.targets) {
            let pick = slot
                .points
                .iter()
                .copied()
                .filter(|i| !config.contains(i))
                .min_by(|&a, &b| {
                    (self.ctx.points[a] - target)
                        .norm_squared()
                        .total_cmp(&(self.ctx.points[b] - target).norm_squared())
                })
                .unwrap_or(slot.points[0]);
            config.push(pick);
        }
        config
    }

    /// A random start with distinct points (the ablation starts without guidance).
    pub fn initial_random(&self, rng: &mut ChaCha8Rng) -> Vec<usize> {
        let mut config: Vec<usize> = Vec::new();
        for slot in &self.slots {
            let cands = &slot.points;
            let mut p = cands[rng.random_range(0..cands.len())];
            for _ in 0..16 {
                if !config.contains(&p) {
                    break;
                }
                p = cands[rng.random_range(0..cands.len())];
            }
            config.push(p);
        }
        config
    }

    /// Stage-2 constraints and the shared assessment.
    pub fn assess(&self, c: &[usize]) -> Assessment {
        let ctx = self.ctx;
        let (h1, h2) = c.split_at(self.k1);
        let mut a = ctx.assess(h1, h2, self.weights);
        for (k, i) in c.iter().enumerate() {
            if c[..k].contains(i) {
                a.violated(1.0, || "two contacts on the same point".into());
            }
        }
        let Some(frame) = a.frame else { return a };
        let mean = |idx: &[usize]| {
            idx.iter()
                .fold(nalgebra::Vector3::zeros(), |s, &i| s + ctx.points[i].coords)
                / idx.len() as f64
        };
        let Some(closing) = (mean(h2) - mean(h1)).try_normalize(1e-9) else {
            return a;
        };
        for &i in h1 {
            let push = -ctx.normals.get(i).dot(&closing);
            a.violated(MIN_PUSH_COS - push, || {
                "an h1 contact's surface does not face away from the fingers".into()
            });
        }
        for &i in h2 {
            let push = ctx.normals.get(i).dot(&closing);
            a.violated(MIN_PUSH_COS - push, || {
                "an h2 contact's surface does not face away from the thumb side".into()
            });
        }
        let geo = &ctx.hand.geometry;
        let spread = ctx.hand.max_finger_spread();
        for side in [h1, h2] {
            if side.len() < 2 || (ctx.palm_opposition() && std::ptr::eq(side, h1)) {
                continue;
            }
            let mut s: Vec<usize> = side.to_vec();
            s.sort_by(|&p, &q| {
                ctx.points[p]
                    .coords
                    .dot(&frame.y)
                    .total_cmp(&ctx.points[q].coords.dot(&frame.y))
            });
            for w in s.windows(2) {
                let d = (ctx.points[w[1]] - ctx.points[w[0]]).norm();
                a.violated((0.9 * geo.finger_width - d) / geo.finger_width, || {
                    format!(
                        "two fingers' contacts {:.1} mm apart, closer than a finger width",
                        d * 1e3
                    )
                });
                a.violated((d - spread) / spread, || {
                    format!(
                        "neighbouring fingers' contacts {:.1} mm apart, beyond the hand's splay",
                        d * 1e3
                    )
                });
            }
        }
        a
    }

    /// Why a configuration is infeasible (None when it is feasible).
    pub fn explain(&self, c: &[usize]) -> Option<String> {
        self.ctx.explain(&self.assess(c), c, self.k1)
    }
}

/// Distance between neighbouring fingers' contacts to aim for: the mean spacing of the h2
/// fingers' bases, at least 1.1 finger widths.
fn finger_spacing(ctx: &SearchContext) -> f64 {
    ctx.hand
        .mean_finger_spacing(ctx.grasp.h2_fingers.iter().copied())
        .max(ctx.hand.geometry.finger_width * 1.1)
}

impl SearchProblem for ContactSearch<'_, '_> {
    fn slots(&self) -> usize {
        self.slots.len()
    }
    fn candidates(&self, slot: usize) -> &[usize] {
        &self.slots[slot].points
    }
    fn is_candidate(&self, slot: usize, p: usize) -> bool {
        self.slots[slot].contains(p)
    }
    fn neighbours(&self, slot: usize, p: usize) -> &[usize] {
        self.slots[slot].neighbours(p, self.ctx.normals)
    }
    fn evaluate(&mut self, c: &[usize], threshold: f64, best: f64) -> Scored {
        let a = self.assess(c);
        self.ctx.score(&a, c, self.k1, threshold, best)
    }
}

/// A stage-2 run's configuration with the opposition it started from.
struct Stage2Result {
    contacts: Vec<usize>,
    opposition: (usize, usize),
    frame_y: Vector3<f64>,
}

/// The result of the whole search.
#[derive(Debug, Clone)]
pub struct SearchOutcome {
    /// Final contacts: the first `k1` on the h1 side.
    pub contacts: Vec<usize>,
    pub k1: usize,
    /// The pregrasping opposition (oc1, oc2); for the ablation, the h1/h2 contacts nearest the
    /// centroids of each side.
    pub opposition: (usize, usize),
    pub feasible: bool,
    pub reason: Option<String>,
    pub stage1: StageStats,
    pub stage2: StageStats,
    /// (ω_R, ω_G) of the stage that produced the final contacts.
    pub final_weights: [f64; 2],
    /// Feasible runners-up of the final contacts, best first (earlier optima of the run that
    /// produced them, at most [`MAX_ALTERNATIVES`]): what the planner falls back on when a hard
    /// constraint checked after the search (IK reachability) rejects the best.
    pub alternatives: Vec<Vec<usize>>,
}

/// Runners-up kept in [`SearchOutcome::alternatives`].
pub const MAX_ALTERNATIVES: usize = 4;

/// The earlier optima of a run, best first, without `best`.
fn runners_up(run: &Annealed, best: &[usize]) -> Vec<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = Vec::new();
    for (_, _, c) in run.improvements.iter().rev() {
        if c.as_slice() != best && !out.contains(c) {
            out.push(c.clone());
        }
        if out.len() == MAX_ALTERNATIVES {
            break;
        }
    }
    out
}

fn budget(ctx: &SearchContext, space: f64) -> Schedule {
    let o = ctx.options;
    let want = (o.iteration_fraction * space).ceil();
    let iterations = if want.is_finite() {
        (want as usize).clamp(o.min_iterations, o.max_iterations.max(o.min_iterations))
    } else {
        o.max_iterations
    };
    Schedule::new(iterations, o.min_iterations, o.patience)
}

fn add_run(stats: &mut StageStats, run: &Annealed) {
    if let Some((k, _, _)) = run.improvements.last() {
        stats.best_iteration = stats.iterations + k;
    }
    stats.iterations += run.iterations;
    stats.evaluations += run.evaluations;
    stats.accepted += run.accepted;
    stats.feasible_found |= run.best.is_some();
}

/// λ₁: 0.6·a_max, bounded by how far the object extends from p_att and at least 2 cm.
fn default_lambda1(ctx: &SearchContext) -> f64 {
    let extent = ctx
        .points
        .iter()
        .map(|p| (p - ctx.p_att).norm())
        .fold(0.0, f64::max);
    (0.6 * ctx.hand.geometry.max_aperture)
        .min(extent * 1.01)
        .max(0.02)
}

/// Runs stage 1 with bounded widenings of λ₁. Returns the oppositions to try in order (best first)
/// and whether the best is feasible.
fn stage_one(
    ctx: &SearchContext,
    rng: &mut ChaCha8Rng,
    stats: &mut StageStats,
) -> (Vec<Vec<usize>>, bool) {
    let t = Instant::now();
    let mut lambda = ctx.options.lambda1.unwrap_or_else(|| default_lambda1(ctx));
    let mut fallback: Option<(Vec<usize>, f64)> = None;
    let mut result = (Vec::new(), false);
    for attempt in 0..=ctx.options.restarts {
        let mut prob = OppositionSearch::new(ctx, lambda);
        stats.candidates = prob.set.len();
        stats.solution_space = prob.solution_space();
        stats.restarts = attempt;
        if prob.set.len() >= 2 {
            let init = prob.initial(rng);
            let sched = budget(ctx, prob.solution_space());
            let run = anneal(&mut prob, init, sched, rng);
            add_run(stats, &run);
            if run.best.is_some() {
                // Best first, then the earlier improvements as runners-up.
                let mut list: Vec<Vec<usize>> = run
                    .improvements
                    .iter()
                    .rev()
                    .map(|(_, _, c)| c.clone())
                    .collect();
                list.dedup();
                list.truncate(4);
                result = (list, true);
                break;
            }
            if fallback.as_ref().is_none_or(|f| run.best_any.1 > f.1) {
                fallback = Some(run.best_any.clone());
            }
        }
        lambda *= 1.5;
    }
    if !result.1 {
        result.0 = fallback.map(|f| vec![f.0]).unwrap_or_default();
    }
    stats.seconds = t.elapsed().as_secs_f64();
    result
}

/// Stage 1 alone, the front end of the final-configuration search of a hand with kinematics:
/// the oppositions to try (best first), whether the best meets every stage-1 constraint, the
/// stage's statistics, and why not when it does not.
pub fn opposition_stage(
    ctx: &SearchContext,
    rng: &mut ChaCha8Rng,
) -> (Vec<(usize, usize)>, bool, StageStats, Option<String>) {
    let mut s1 = StageStats::default();
    let (list, ok) = stage_one(ctx, rng, &mut s1);
    let reason = if ok {
        None
    } else {
        list.first().and_then(|c| {
            OppositionSearch::new(ctx, 0.0)
                .explain(c)
                .map(|r| format!("stage 1: {r}"))
        })
    };
    (list.iter().map(|c| (c[0], c[1])).collect(), ok, s1, reason)
}

/// Attention points closer than this give one stage 1, m.
const SAME_ATTENTION: f64 = 0.02;

/// Stage 1 (Algorithm 4, lines 3–5) from `ctx`'s attention point and, for a hand with
/// kinematics, also from `centre` — the surface point over the estimated centre of mass, index
/// into the cloud — when it lies more than [`SAME_ATTENTION`] away: the two lists interleaved,
/// best first, without repeats. The detector's attention point (Eq 4.3) may sit at an end of an
/// elongated object (a banana's tip), where no grasp balances the weight; the final search ranks
/// both by what they hold. The statistics and the constraint report are the first run's.
pub fn opposition_stage_about(
    ctx: &SearchContext,
    centre: Option<usize>,
    seed: u64,
) -> (Vec<(usize, usize)>, bool, StageStats, Option<String>) {
    use rand::SeedableRng;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (first, ok, s1, reason) = opposition_stage(ctx, &mut rng);
    let Some(c) = centre.filter(|&c| (ctx.points[c] - ctx.p_att).norm() > SAME_ATTENTION) else {
        return (first, ok, s1, reason);
    };
    let mut centred_ctx = ctx.for_grasp(ctx.grasp, ctx.approach_prefs.clone());
    centred_ctx.p_att = ctx.points[c];
    centred_ctx.n_att = ctx.normals.get(c);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (second, _, _, _) = opposition_stage(&centred_ctx, &mut rng);
    let mut merged: Vec<(usize, usize)> = Vec::with_capacity(first.len() + second.len());
    for k in 0..first.len().max(second.len()) {
        for o in [first.get(k), second.get(k)].into_iter().flatten() {
            if !merged.contains(o) {
                merged.push(*o);
            }
        }
    }
    (merged, ok, s1, reason)
}

/// Algorithm 4, lines 6–7 (or the ablation): the final contacts.
pub fn search(ctx: &SearchContext, rng: &mut ChaCha8Rng) -> Option<SearchOutcome> {
    let mut s1 = StageStats::default();
    let mut s2 = StageStats::default();
    let k1 = ctx.grasp.h1_count();
    let m = ctx.grasp.contact_count();
    if ctx.options.mode == PlannerMode::WithoutOpposition {
        let t = Instant::now();
        let mut prob = ContactSearch::whole_cloud(ctx);
        s2.candidates = ctx.points.len();
        s2.solution_space = prob.solution_space();
        let mut best: Option<(Vec<usize>, f64, bool)> = None;
        let mut alternatives = Vec::new();
        for attempt in 0..=ctx.options.restarts {
            s2.restarts = attempt;
            let init = prob.initial_random(rng);
            let sched = budget(ctx, prob.solution_space());
            let run = anneal(&mut prob, init, sched, rng);
            add_run(&mut s2, &run);
            let cand = match &run.best {
                Some((c, q)) => (c.clone(), *q, true),
                None => (run.best_any.0.clone(), run.best_any.1, false),
            };
            if best.as_ref().is_none_or(|b| (cand.2, cand.1) > (b.2, b.1)) {
                if cand.2 {
                    alternatives = runners_up(&run, &cand.0);
                }
                best = Some(cand);
            }
            if best.as_ref().is_some_and(|b| b.2) {
                break;
            }
        }
        s2.seconds = t.elapsed().as_secs_f64();
        let (contacts, _, feasible) = best?;
        let reason = if feasible {
            None
        } else {
            prob.explain(&contacts)
        };
        let opposition = (contacts[0], contacts[k1]);
        return Some(SearchOutcome {
            contacts,
            k1,
            opposition,
            feasible,
            reason,
            stage1: s1,
            stage2: s2,
            final_weights: ctx.options.stage2_weights,
            alternatives,
        });
    }

    let (oppositions, stage1_ok) = stage_one(ctx, rng, &mut s1);
    let first = oppositions.first()?.clone();
    let stage1_reason = if stage1_ok {
        None
    } else {
        OppositionSearch::new(ctx, 0.0)
            .explain(&first)
            .map(|r| format!("stage 1: {r}"))
    };
    if m == 2 {
        // Two contacts: the pregrasping opposition is the final grasp (as for the P-Grip).
        return Some(SearchOutcome {
            contacts: first.clone(),
            k1,
            opposition: (first[0], first[1]),
            feasible: stage1_ok,
            reason: stage1_reason,
            stage1: s1,
            stage2: s2,
            final_weights: ctx.options.stage1_weights,
            alternatives: if stage1_ok {
                oppositions[1..].to_vec()
            } else {
                Vec::new()
            },
        });
    }
    let t = Instant::now();
    let lambda2 = ctx
        .options
        .lambda2
        .unwrap_or_else(|| ctx.hand.geometry.finger_width.max(0.015));
    // (contacts, merit, opposition, lateral axis) of the best run, feasible or not.
    let mut fallback: Option<(Stage2Result, f64)> = None;
    let mut found: Option<Stage2Result> = None;
    let mut alternatives = Vec::new();
    'outer: for oc in &oppositions {
        let oc = (oc[0], oc[1]);
        let frame_y = OppositionSearch::new(ctx, 0.0)
            .assess(oc.0, oc.1)
            .frame
            .map(|f| f.y)
            .unwrap_or_else(Vector3::y);
        let mut lambda = lambda2;
        for attempt in 0..=ctx.options.restarts {
            let mut prob = ContactSearch::around(ctx, oc, lambda, &frame_y);
            s2.restarts += usize::from(attempt > 0);
            lambda *= 1.5;
            if prob.has_empty_slot() {
                continue;
            }
            s2.candidates = s2
                .candidates
                .max(prob.slots.iter().map(SlotSet::len).max().unwrap_or(0));
            s2.solution_space = s2.solution_space.max(prob.solution_space());
            let init = prob.initial_at_targets();
            let sched = budget(ctx, prob.solution_space());
            let run = anneal(&mut prob, init, sched, rng);
            add_run(&mut s2, &run);
            if let Some((c, _)) = run.best.clone() {
                alternatives = runners_up(&run, &c);
                found = Some(Stage2Result {
                    contacts: c,
                    opposition: oc,
                    frame_y,
                });
                break 'outer;
            }
            if fallback.as_ref().is_none_or(|f| run.best_any.1 > f.1) {
                fallback = Some((
                    Stage2Result {
                        contacts: run.best_any.0.clone(),
                        opposition: oc,
                        frame_y,
                    },
                    run.best_any.1,
                ));
            }
        }
    }
    s2.seconds = t.elapsed().as_secs_f64();
    // A final grasp that meets every constraint is feasible even if stage 1 had to fall back.
    let (
        Stage2Result {
            contacts,
            opposition: oc,
            frame_y,
        },
        feasible,
    ) = match found {
        Some(r) => (r, true),
        None => (fallback?.0, false),
    };
    let reason = if feasible {
        None
    } else {
        let prob = ContactSearch::around(ctx, oc, lambda2, &frame_y);
        stage1_reason.or_else(|| prob.explain(&contacts).map(|r| format!("stage 2: {r}")))
    };
    Some(SearchOutcome {
        contacts,
        k1,
        opposition: oc,
        feasible,
        reason,
        stage1: s1,
        stage2: s2,
        final_weights: ctx.options.stage2_weights,
        alternatives: if feasible { alternatives } else { Vec::new() },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp_type::GraspType;
    use crate::planning::test_scene::Rod;
    use rand::SeedableRng;

    /// With p_att at one end of a 48 cm rod, the oppositions from the centre's surface point
    /// come in too, interleaved (the first of each run leads): one centred within 5 cm of the
    /// middle, where the end's lie 10 cm or more from it; a centre within 2 cm of p_att adds
    /// nothing.
    #[test]
    fn stage_one_about_the_centre_adds_oppositions_there() {
        let rod = Rod::new(0.48, "barrett", GraspType::Tripod);
        let normals = rod.normals();
        let end = rod.nearest(Point3::new(0.23, 0.0, 0.04));
        let middle = rod.nearest(Point3::new(0.0, 0.0, 0.04));
        let ctx = rod.context(&normals, end);
        let mid_x = |(a, b): (usize, usize)| ((rod.points[a].x + rod.points[b].x) / 2.0).abs();
        let alone = opposition_stage(&ctx, &mut ChaCha8Rng::seed_from_u64(7)).0;
        assert!(!alone.is_empty());
        assert!(alone.iter().all(|&o| mid_x(o) > 0.1), "{alone:?}");
        let (about, ..) = opposition_stage_about(&ctx, Some(middle), 7);
        assert_eq!(about[0], alone[0]);
        assert!(mid_x(about[1]) < 0.05, "{about:?}");
        assert!(alone.iter().all(|o| about.contains(o)));
        let near_end = rod.nearest(Point3::new(0.22, 0.0, 0.04));
        assert_eq!(opposition_stage_about(&ctx, Some(near_end), 7).0, alone);
    }
}
