//! Grasp configuration optimisation with Bayesian search (dissertation §3.2.3, Eq 3.2–3.6,
//! Algorithm 1), and the Monte-Carlo search it is measured against.
//!
//! The domain G of Eq 3.2 is a finite pool of candidate grasps the caller samples from the depth
//! image (cheap geometry), each with a feature vector scaled so that a unit distance is about
//! where qualities stop being alike; the quality function (the network, the expensive part) is
//! called on pool members only. The search fits the Gaussian process ([`gaussian_process`]) to
//! the grasps queried so far, queries the unqueried member with the largest upper confidence
//! bound (Eq 3.6), and stops when no member's bound exceeds the best quality found (none can do
//! better, as far as the surrogate knows; not before [`MIN_QUERIES`] queries beyond the initial
//! set), when `patience` queries in a row found nothing better, or after `max_calls`.
//!
//! Eq 3.6 as printed weighs the variance, μ + β σ²; here the bound is the usual GP-UCB one,
//! μ + β σ, with β ∈ [2.5, 3] as §3.4 measured. Qualities are probabilities whose spread over a
//! pool is small (σ_f² of a few hundredths), so β σ² is a bonus of a few hundredths that never
//! lifts an unexplored grasp above the best one seen: on the two-hill test below the printed
//! form stopped after its initial set every time, at the lower hill.

pub mod gaussian_process;

use gaussian_process::{GaussianProcess, Kernel, Prior};
use nalgebra::DVector;
use rand::RngExt;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand::seq::SliceRandom;

/// How the Bayesian search runs.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchOptions {
    /// Size of the initial set (spread over the pool by farthest-point sampling).
    pub initial: usize,
    /// β of Eq 3.6 (the weight of the posterior's standard deviation; module doc).
    pub beta: f64,
    /// Quality evaluations at most, the initial set included.
    pub max_calls: usize,
    /// Stop after this many queries in a row without a better quality.
    pub patience: usize,
    pub seed: u64,
}

impl Default for SearchOptions {
    fn default() -> Self {
        Self {
            initial: 20,
            beta: 2.75,
            max_calls: 60,
            patience: 24,
            seed: 0,
        }
    }
}

/// What a search found.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchResult {
    /// Pool index of the best grasp queried.
    pub best: usize,
    /// Its quality (as the quality function returned it).
    pub quality: f64,
    /// The surrogate's posterior at it: mean and standard deviation (the Monte-Carlo search
    /// has none: 0).
    pub posterior_mean: f64,
    pub posterior_std: f64,
    /// Quality evaluations made.
    pub calls: usize,
    /// The best quality found after each call.
    pub best_after: Vec<f64>,
}

/// Bandwidths tried when the kernel is fitted to the data (feature units).
const LENGTHS: [f64; 4] = [0.25, 0.5, 1.0, 2.0];
/// Noise variances tried, as fractions of the function variance.
const NOISE_FRACTIONS: [f64; 2] = [1e-3, 3e-2];
/// Queries after the initial set before the bound may end the search.
const MIN_QUERIES: usize = 10;
/// Least function variance (qualities all alike early on would otherwise give a flat prior).
const MIN_SIGNAL_VARIANCE: f64 = 1e-3;

/// Bayesian search for the pool member with the highest quality (Eq 3.2, Algorithm 1).
/// `quality` is called with pool indices (the initial set in one batch, then one at a time) and
/// returns their qualities. None for an empty pool.
pub fn bayesian_search<E>(
    features: &[Vec<f64>],
    mut quality: impl FnMut(&[usize]) -> Result<Vec<f64>, E>,
    options: &SearchOptions,
) -> Result<Option<SearchResult>, E> {
    let n = features.len();
    if n == 0 {
        return Ok(None);
    }
    let mut rng = StdRng::seed_from_u64(options.seed);
    let budget = options.max_calls.clamp(1, n);
    let first = farthest_points(features, options.initial.clamp(1, budget), &mut rng);
    let mut queried = first.clone();
    let mut values = quality(&first)?;
    let mut best_after = Vec::with_capacity(budget);
    let mut best = 0;
    for (i, v) in values.iter().enumerate() {
        if *v > values[best] {
            best = i;
        }
        best_after.push(values[best]);
    }
    let mut is_queried = vec![false; n];
    first.iter().for_each(|&i| is_queried[i] = true);
    let mut since_better = 0;
    let mut correlations = Correlations::default();
    first.iter().for_each(|&q| correlations.add(features, q));
    let mut gp = fit(features, &queried, &values, &correlations);
    while queried.len() < budget && since_better < options.patience {
        let Some((model, length)) = &gp else { break };
        // Eq 3.6 over the unqueried members.
        let sf2 = model.kernel().signal_variance;
        let rows = &correlations.rows[*length];
        let next = (0..n)
            .filter(|&i| !is_queried[i])
            .map(|i| {
                let ks = DVector::from_iterator(rows.len(), rows.iter().map(|r| sf2 * r[i]));
                let (mu, var) = model.posterior_of(ks);
                (i, mu + options.beta * var.sqrt())
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((next, bound)) = next else { break };
        // Nothing can beat the best, as far as the surrogate knows — once it has seen
        // MIN_QUERIES beyond the initial set (fitted to that set alone it is often too sure).
        if bound <= values[best] && queried.len() >= first.len() + MIN_QUERIES {
            break;
        }
        let q = quality(&[next])?[0];
        is_queried[next] = true;
        queried.push(next);
        values.push(q);
        if q > values[best] {
            best = values.len() - 1;
            since_better = 0;
        } else {
            since_better += 1;
        }
        best_after.push(values[best]);
        correlations.add(features, next);
        gp = fit(features, &queried, &values, &correlations);
    }
    let (posterior_mean, posterior_std) = gp.as_ref().map_or((values[best], 0.0), |(m, _)| {
        let (mu, var) = m.posterior(&features[queried[best]]);
        (mu, var.sqrt())
    });
    Ok(Some(SearchResult {
        best: queried[best],
        quality: values[best],
        posterior_mean,
        posterior_std,
        calls: queried.len(),
        best_after,
    }))
}

/// The Monte-Carlo search (§3.2.3's baseline): `calls` pool members drawn at random, in one
/// batch, ranked by their quality. None for an empty pool.
pub fn monte_carlo_search<E>(
    pool: usize,
    mut quality: impl FnMut(&[usize]) -> Result<Vec<f64>, E>,
    calls: usize,
    seed: u64,
) -> Result<Option<SearchResult>, E> {
    if pool == 0 {
        return Ok(None);
    }
    let mut rng = StdRng::seed_from_u64(seed);
    let mut drawn: Vec<usize> = (0..pool).collect();
    drawn.shuffle(&mut rng);
    drawn.truncate(calls.clamp(1, pool));
    let values = quality(&drawn)?;
    let mut best = 0;
    let mut best_after = Vec::with_capacity(values.len());
    for (i, v) in values.iter().enumerate() {
        if *v > values[best] {
            best = i;
        }
        best_after.push(values[best]);
    }
    Ok(Some(SearchResult {
        best: drawn[best],
        quality: values[best],
        posterior_mean: values[best],
        posterior_std: 0.0,
        calls: drawn.len(),
        best_after,
    }))
}

/// The process fitted to the queried grasps, its kernel the most probable of a small grid
/// (bandwidth × noise) with the function variance of the data; with the index of its
/// bandwidth in [`LENGTHS`].
fn fit(
    features: &[Vec<f64>],
    queried: &[usize],
    values: &[f64],
    correlations: &Correlations,
) -> Option<(GaussianProcess, usize)> {
    let points: Vec<Vec<f64>> = queried.iter().map(|&i| features[i].clone()).collect();
    let m = values.iter().sum::<f64>() / values.len() as f64;
    let var = values.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / values.len() as f64;
    let signal_variance = var.max(MIN_SIGNAL_VARIANCE);
    let kernels: Vec<Kernel> = LENGTHS
        .iter()
        .flat_map(|&length| {
            NOISE_FRACTIONS.iter().map(move |&f| Kernel {
                length,
                signal_variance,
                noise_variance: f * signal_variance,
            })
        })
        .collect();
    let length_of = |k: usize| k / NOISE_FRACTIONS.len();
    let gp = GaussianProcess::fit_evidence_covariances(
        &points,
        values,
        &kernels,
        Prior::DataMean,
        |k, i, j| signal_variance * correlations.rows[length_of(k)][i][queried[j]],
    )?;
    let length = LENGTHS.iter().position(|&l| l == gp.kernel().length)?;
    Some((gp, length))
}

/// The kernel's correlations ([`gaussian_process::correlation`]) of each queried grasp with
/// every pool member, per bandwidth of [`LENGTHS`], in the order queried: computed once a
/// grasp, where every fit (8 kernels × n² pairs) and every bound (pool × n) would compute them
/// again — the search's cost, the same numbers.
#[derive(Default)]
struct Correlations {
    rows: [Vec<Vec<f64>>; LENGTHS.len()],
}

impl Correlations {
    fn add(&mut self, features: &[Vec<f64>], queried: usize) {
        for (rows, &length) in self.rows.iter_mut().zip(&LENGTHS) {
            let q = &features[queried];
            rows.push(
                features
                    .iter()
                    .map(|f| gaussian_process::correlation(length, q, f))
                    .collect(),
            );
        }
    }
}

/// `k` pool members spread by farthest-point sampling from a random first one.
fn farthest_points(features: &[Vec<f64>], k: usize, rng: &mut StdRng) -> Vec<usize> {
    let n = features.len();
    let d2 =
        |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum() };
    let mut chosen = vec![rng.random_range(0..n)];
    let mut nearest: Vec<f64> = features
        .iter()
        .map(|f| d2(f, &features[chosen[0]]))
        .collect();
    while chosen.len() < k.min(n) {
        let (far, _) = nearest
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .expect("non-empty pool");
        chosen.push(far);
        for (i, f) in features.iter().enumerate() {
            nearest[i] = nearest[i].min(d2(f, &features[far]));
        }
    }
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    /// A 40 × 40 grid over [0, 4]² with a broad hill (its top 0.6 at (1, 1), width 0.9) and a
    /// narrower, higher one (0.95 at (3, 2.5), width 0.6): the search must not settle on the
    /// first. (With the higher hill 0.45 wide, one seed in five never sees it: the initial set
    /// lands no point within 0.9 of it and the fitted bandwidth, 1, rules it out.)
    fn landscape() -> (Vec<Vec<f64>>, Vec<f64>) {
        let mut features = Vec::new();
        let mut q = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                let (x, y) = (i as f64 * 0.1, j as f64 * 0.1);
                let hill = |cx: f64, cy: f64, h: f64, w: f64| {
                    h * (-((x - cx).powi(2) + (y - cy).powi(2)) / (2.0 * w * w)).exp()
                };
                features.push(vec![x, y]);
                q.push(hill(1.0, 1.0, 0.6, 0.9).max(hill(3.0, 2.5, 0.95, 0.6)));
            }
        }
        (features, q)
    }

    /// The Bayesian search reaches the quality the Monte-Carlo search finds with 300 calls
    /// with at most a fifth of them (issue 18's measure), on several seeds; both count their
    /// calls truly.
    #[test]
    fn bayesian_search_reaches_monte_carlo_quality_with_a_fifth_of_the_calls() {
        let (features, q) = landscape();
        for seed in 0..5 {
            let mut calls = 0;
            let mc = monte_carlo_search::<Infallible>(
                features.len(),
                |idx| {
                    calls += idx.len();
                    Ok(idx.iter().map(|&i| q[i]).collect())
                },
                300,
                seed,
            )
            .unwrap()
            .unwrap();
            assert_eq!((mc.calls, calls), (300, 300));
            let mut calls = 0;
            let bo = bayesian_search::<Infallible>(
                &features,
                |idx| {
                    calls += idx.len();
                    Ok(idx.iter().map(|&i| q[i]).collect())
                },
                &SearchOptions {
                    seed,
                    ..Default::default()
                },
            )
            .unwrap()
            .unwrap();
            assert_eq!(bo.calls, calls);
            let reached = bo
                .best_after
                .iter()
                .position(|&b| b >= mc.quality)
                .map(|i| i + 1);
            println!(
                "seed {seed}: MC {:.4} in 300 calls; BO {:.4} in {} calls, MC's quality after {reached:?}",
                mc.quality, bo.quality, bo.calls
            );
            assert!(reached.is_some_and(|c| c <= 60), "seed {seed}: {reached:?}");
            assert!(bo.quality > 0.9, "seed {seed}: settled at {}", bo.quality);
            assert_eq!(q[bo.best], bo.quality);
            // The surrogate's uncertainty at the best grasp is small: it was observed there.
            assert!(bo.posterior_std < 0.1, "{}", bo.posterior_std);
        }
    }

    /// The quality function's error ends the search and comes back; an empty pool gives None.
    #[test]
    fn errors_and_empty_pools() {
        let (features, _) = landscape();
        let r = bayesian_search(
            &features,
            |_| Err("network down"),
            &SearchOptions::default(),
        );
        assert_eq!(r, Err("network down"));
        let none = bayesian_search::<Infallible>(&[], |_| Ok(vec![]), &SearchOptions::default());
        assert_eq!(none, Ok(None));
        let none = monte_carlo_search::<Infallible>(0, |_| Ok(vec![]), 10, 0);
        assert_eq!(none, Ok(None));
    }
}
