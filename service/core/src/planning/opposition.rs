//! Stage 1: the pregrasping opposition O^s_{h1-h2}(C_o) (Definition 1, Eq 5.1).
//!
//! Two opposing points C_o = (oc1, oc2) — oc1 for the h1 part (thumb or palm), oc2 for the h2
//! part — drawn from the neighbourhood Φ(p_att) of Eq 5.6 with λ₁ object-sized (method.md §3),
//! maximising Q = 0.3·R + 0.7·G subject to S ≥ ε (Eq 5.2). Beyond the hand's limits, an opposition
//! must really oppose: normals at least 120° apart and the line oc1–oc2 inside both friction
//! cones (μ), so that two opposing forces can squeeze the object.

use super::annealing::{Scored, SearchProblem};
use super::evaluation::{Assessment, SearchContext};
use super::slot_set::SlotSet;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// cos 120°: the opposing normals must be at least this far apart.
pub const MAX_NORMAL_COS: f64 = -0.5;

/// The stage-1 search problem.
pub struct OppositionSearch<'c, 'a> {
    pub ctx: &'c SearchContext<'a>,
    pub set: SlotSet,
    pub weights: [f64; 2],
}

impl<'c, 'a> OppositionSearch<'c, 'a> {
    /// Φ(p_att) with radius `lambda` (Eq 5.6), thinned to `opposition_candidates` points.
    pub fn new(ctx: &'c SearchContext<'a>, lambda: f64) -> Self {
        let set = SlotSet::around(
            ctx.points,
            ctx.index,
            &ctx.p_att,
            lambda,
            ctx.options.opposition_candidates,
        );
        Self {
            ctx,
            set,
            weights: ctx.options.stage1_weights,
        }
    }

    /// |Φ_ĝ| of stage 1: ordered pairs (oc1 for h1, oc2 for h2).
    pub fn solution_space(&self) -> f64 {
        (self.set.len() as f64).powi(2)
    }

    /// The opposition-specific constraints and the shared assessment.
    pub fn assess(&self, i: usize, j: usize) -> Assessment {
        let ctx = self.ctx;
        let mut a = ctx.assess(&[i], &[j], self.weights);
        if i == j {
            a.violated(1.0, || "the two opposing points coincide".into());
            return a;
        }
        let (ni, nj) = (ctx.normals.get(i), ctx.normals.get(j));
        let cos_n = ni.dot(&nj);
        a.violated(cos_n - MAX_NORMAL_COS, || {
            format!(
                "normals only {:.0}° apart (opposition needs ≥ 120°)",
                cos_n.clamp(-1.0, 1.0).acos().to_degrees()
            )
        });
        let d = (ctx.points[j] - ctx.points[i]).normalize();
        let (ci, cj) = (-ni.dot(&d), nj.dot(&d));
        a.violated(ctx.cos_friction - ci, || {
            format!(
                "the line oc1–oc2 leaves oc1's friction cone (μ = {})",
                ctx.options.friction
            )
        });
        a.violated(ctx.cos_friction - cj, || {
            format!(
                "the line oc1–oc2 leaves oc2's friction cone (μ = {})",
                ctx.options.friction
            )
        });
        a
    }

    /// A start for the annealing: among random oc1 candidates, each paired with its most
    /// antipodal partner in a random sample, the best-scoring pair.
    pub fn initial(&mut self, rng: &mut ChaCha8Rng) -> Vec<usize> {
        let cands = self.set.points.clone();
        let n = cands.len();
        let a_max = self.ctx.hand.geometry.max_aperture;
        let mut best: Option<(f64, Vec<usize>)> = None;
        for _ in 0..32.min(n) {
            let i = cands[rng.random_range(0..n)];
            let (pi, ni) = (self.ctx.points[i], self.ctx.normals.get(i));
            let mut pick = None;
            let mut pick_score = f64::NEG_INFINITY;
            for _ in 0..48.min(n) {
                let j = cands[rng.random_range(0..n)];
                let d = self.ctx.points[j] - pi;
                let len = d.norm();
                if j == i || len < 1e-6 || len > a_max {
                    continue;
                }
                let d = d / len;
                let score = -ni.dot(&d) + self.ctx.normals.get(j).dot(&d);
                if score > pick_score {
                    pick_score = score;
                    pick = Some(j);
                }
            }
            let Some(j) = pick else { continue };
            let s = self.evaluate(&[i, j], f64::NEG_INFINITY, f64::INFINITY);
            if best.as_ref().is_none_or(|(m, _)| s.merit > *m) {
                best = Some((s.merit, vec![i, j]));
            }
        }
        best.map(|b| b.1)
            .unwrap_or_else(|| vec![cands[0], cands[n - 1]])
    }

    /// Why a configuration is infeasible (None when it is feasible).
    pub fn explain(&self, c: &[usize]) -> Option<String> {
        self.ctx.explain(&self.assess(c[0], c[1]), c, 1)
    }
}

impl SearchProblem for OppositionSearch<'_, '_> {
    fn slots(&self) -> usize {
        2
    }
    fn candidates(&self, _: usize) -> &[usize] {
        &self.set.points
    }
    fn is_candidate(&self, _: usize, p: usize) -> bool {
        self.set.contains(p)
    }
    fn neighbours(&self, _: usize, p: usize) -> &[usize] {
        self.set.neighbours(p, self.ctx.normals)
    }
    fn evaluate(&mut self, c: &[usize], threshold: f64, best: f64) -> Scored {
        let a = self.assess(c[0], c[1]);
        self.ctx.score(&a, c, 1, threshold, best)
    }
}
