//! How sure a benchmark's numbers are: the Wilson interval of a success rate, and the paired
//! comparison of two runs on the same seeds (`graspd-sim compare BASE NEW`) with McNemar's exact
//! test on the trials that changed. A change to the commands a hand receives reshuffles the
//! chaotic contact outcomes of many trials (a slower close alone moved the Allegro's Table 5.2
//! count 134 → 126 → 142 of 160, docs/sim-benchmark.md), so a difference is only a finding when
//! the trials that flipped are lopsided enough.

use crate::SimError;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// z of a two-sided 95 % interval.
pub const Z_95: f64 = 1.959_963_984_540_054;

/// The Wilson score interval of `k` successes in `n` trials at `z` (the interval that stays
/// inside [0, 1] and keeps its coverage near 0 and 1, where the normal approximation does not);
/// (0, 1) for no trials.
pub fn wilson(k: usize, n: usize, z: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (n, p) = (n as f64, k as f64 / n as f64);
    let z2 = z * z;
    let denom = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denom;
    let half = z * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / denom;
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// Two-sided exact McNemar p-value of `lost` trials that held before and failed after against
/// `gained` that failed before and held after: the binomial probability, at one half, of a split
/// at least as lopsided; 1 when nothing changed.
pub fn mcnemar_exact(lost: usize, gained: usize) -> f64 {
    let n = lost + gained;
    let k = lost.min(gained);
    // Σ_{i ≤ k} C(n, i) / 2ⁿ, summed in logs so that large n does not overflow.
    let ln_half_n = -(n as f64) * std::f64::consts::LN_2;
    let mut ln_c = 0.0; // ln C(n, 0)
    let mut tail = 0.0;
    for i in 0..=k {
        if i > 0 {
            ln_c += ((n - i + 1) as f64).ln() - (i as f64).ln();
        }
        tail += (ln_c + ln_half_n).exp();
    }
    (2.0 * tail).min(1.0)
}

/// The part of a `results.json` record a comparison reads.
#[derive(Debug, Clone, Deserialize)]
pub struct Trial {
    pub hand: String,
    pub object: String,
    pub seed: u64,
    pub outcome: String,
}

#[derive(Deserialize)]
struct Results {
    records: Vec<Trial>,
}

/// Reads the trials of a bench's `results.json`.
pub fn read_trials(path: &Path) -> Result<Vec<Trial>, SimError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| SimError::Input(format!("{}: {e}", path.display())))?;
    let r: Results = serde_json::from_str(&text).map_err(|e| {
        SimError::Input(format!(
            "{}: not a graspd-sim results.json ({e})",
            path.display()
        ))
    })?;
    Ok(r.records)
}

/// Paired counts of one hand (and object): trials in both runs, held in each, and the flips.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Paired {
    pub trials: usize,
    pub held_base: usize,
    pub held_new: usize,
    /// Held in the base run, failed in the new one.
    pub lost: usize,
    /// Failed in the base run, held in the new one.
    pub gained: usize,
}

impl Paired {
    fn add(&mut self, base: bool, new: bool) {
        self.trials += 1;
        self.held_base += usize::from(base);
        self.held_new += usize::from(new);
        self.lost += usize::from(base && !new);
        self.gained += usize::from(!base && new);
    }

    /// McNemar's exact p-value of the flips.
    pub fn p_value(&self) -> f64 {
        mcnemar_exact(self.lost, self.gained)
    }
}

/// The comparison of two runs: per hand, and per hand and object, over the trials (hand,
/// object, seed) both runs have.
#[derive(Debug, Clone, Default)]
pub struct Comparison {
    pub hands: BTreeMap<String, Paired>,
    pub cells: BTreeMap<(String, String), Paired>,
    /// Trials of either run the other lacks.
    pub unpaired: usize,
}

/// Pairs `base` and `new` by (hand, object, seed).
pub fn compare(base: &[Trial], new: &[Trial]) -> Comparison {
    let key = |t: &Trial| (t.hand.clone(), t.object.clone(), t.seed);
    let held = |t: &Trial| t.outcome == "success";
    let new_by_key: BTreeMap<_, bool> = new.iter().map(|t| (key(t), held(t))).collect();
    let base_keys: std::collections::BTreeSet<_> = base.iter().map(key).collect();
    let mut c = Comparison {
        unpaired: new.iter().filter(|t| !base_keys.contains(&key(t))).count(),
        ..Default::default()
    };
    for t in base {
        let Some(&n) = new_by_key.get(&key(t)) else {
            c.unpaired += 1;
            continue;
        };
        c.hands.entry(t.hand.clone()).or_default().add(held(t), n);
        c.cells
            .entry((t.hand.clone(), t.object.clone()))
            .or_default()
            .add(held(t), n);
    }
    c
}

impl Comparison {
    /// Markdown: one row per hand (held before → after, with 95 % intervals, the flips and
    /// their p-value), then the objects whose count changed.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let pct = |k: usize, n: usize| 100.0 * k as f64 / n.max(1) as f64;
        let interval = |k: usize, n: usize| {
            let (lo, hi) = wilson(k, n, Z_95);
            format!("{:.0}–{:.0} %", lo * 100.0, hi * 100.0)
        };
        let _ = writeln!(
            s,
            "| hand | held before | held after | lost | gained | p (McNemar, exact) |"
        );
        let _ = writeln!(s, "|---|---|---|---:|---:|---:|");
        for (hand, p) in &self.hands {
            let _ = writeln!(
                s,
                "| {hand} | {}/{} = {:.1} % ({}) | {}/{} = {:.1} % ({}) | {} | {} | {:.3} |",
                p.held_base,
                p.trials,
                pct(p.held_base, p.trials),
                interval(p.held_base, p.trials),
                p.held_new,
                p.trials,
                pct(p.held_new, p.trials),
                interval(p.held_new, p.trials),
                p.lost,
                p.gained,
                p.p_value()
            );
        }
        let changed: Vec<_> = self
            .cells
            .iter()
            .filter(|(_, p)| p.lost + p.gained > 0)
            .collect();
        if !changed.is_empty() {
            let _ = writeln!(
                s,
                "\n| hand | object | held before → after | lost | gained |"
            );
            let _ = writeln!(s, "|---|---|---|---:|---:|");
            for ((hand, object), p) in changed {
                let _ = writeln!(
                    s,
                    "| {hand} | {object} | {} → {} of {} | {} | {} |",
                    p.held_base, p.held_new, p.trials, p.lost, p.gained
                );
            }
        }
        if self.unpaired > 0 {
            let _ = writeln!(
                s,
                "\n{} trials are in one run only (left out).",
                self.unpaired
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 134 of 160 (the Allegro's Table 5.2 count): p̂ = 0.8375, z² = 3.8415; centre
    /// (p̂ + z²/2n)/(1 + z²/n) = 0.84950/1.02401 = 0.82958, half-width
    /// z·√(p̂(1−p̂)/n + z²/4n²)/(1 + z²/n) = 1.95996·0.029801/1.02401 = 0.05704.
    #[test]
    fn wilson_matches_the_hand_computed_interval() {
        let (lo, hi) = wilson(134, 160, Z_95);
        assert!((lo - 0.77254).abs() < 2e-4, "{lo}");
        assert!((hi - 0.88662).abs() < 2e-4, "{hi}");
        // All held: the interval reaches 1 and its lower end is n/(n + z²).
        let (lo, hi) = wilson(20, 20, Z_95);
        assert!((hi - 1.0).abs() < 1e-12);
        assert!((lo - 20.0 / (20.0 + Z_95 * Z_95)).abs() < 1e-12, "{lo}");
        assert_eq!(wilson(0, 0, Z_95), (0.0, 1.0));
    }

    /// Exact binomial tails at one half: 8 flips all one way 2·2⁻⁸; 10 against 2
    /// 2·(1 + 12 + 66)/4096; an even split and no flips 1.
    #[test]
    fn mcnemar_matches_the_binomial_tails() {
        assert!((mcnemar_exact(8, 0) - 0.0078125).abs() < 1e-12);
        assert!((mcnemar_exact(0, 8) - 0.0078125).abs() < 1e-12);
        assert!((mcnemar_exact(10, 2) - 158.0 / 4096.0).abs() < 1e-12);
        assert_eq!(mcnemar_exact(5, 5), 1.0);
        assert_eq!(mcnemar_exact(0, 0), 1.0);
        // Large counts stay finite: 200 against 100 is far beyond chance.
        let p = mcnemar_exact(200, 100);
        assert!(p > 0.0 && p < 1e-7, "{p}");
    }

    fn trial(hand: &str, object: &str, seed: u64, held: bool) -> Trial {
        Trial {
            hand: hand.into(),
            object: object.into(),
            seed,
            outcome: if held { "success" } else { "slipped_lift" }.into(),
        }
    }

    /// Trials pair by hand, object and seed; a trial in one run only is counted apart.
    #[test]
    fn runs_pair_by_hand_object_and_seed() {
        let base = vec![
            trial("a", "x", 0, true),
            trial("a", "x", 1, false),
            trial("a", "y", 0, true),
            trial("b", "x", 0, true),
            trial("b", "x", 9, true),
        ];
        let new = vec![
            trial("a", "x", 1, true),
            trial("a", "x", 0, true),
            trial("a", "y", 0, false),
            trial("b", "x", 0, true),
        ];
        let c = compare(&base, &new);
        let a = c.hands["a"];
        assert_eq!(
            a,
            Paired {
                trials: 3,
                held_base: 2,
                held_new: 2,
                lost: 1,
                gained: 1
            }
        );
        assert_eq!(c.cells[&("a".into(), "x".into())].gained, 1);
        assert_eq!(c.cells[&("a".into(), "y".into())].lost, 1);
        assert_eq!(c.hands["b"].trials, 1);
        assert_eq!(c.unpaired, 1);
        // A trial listed twice in one run pairs twice and never makes the count negative.
        let twice = [base[0].clone(), base[0].clone()];
        assert_eq!(compare(&twice, &new[1..2]).hands["a"].trials, 2);
        assert_eq!(compare(&twice, &new[1..2]).unpaired, 0);
        let md = c.markdown();
        assert!(md.contains("| a | 2/3 = 66.7 %"), "{md}");
        assert!(md.contains("| a | y | 1 → 0 of 1 | 1 | 0 |"), "{md}");
        assert!(!md.contains("| b | x |"), "{md}");
    }
}
