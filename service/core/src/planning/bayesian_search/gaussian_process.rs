//! The surrogate of the Bayesian search (dissertation §3.2.3): a Gaussian process over grasp
//! features with the squared-exponential kernel (Eq 3.3–3.4) and its posterior at a new grasp
//! (Eq 3.5).
//!
//! Choice where the text leaves it open: Eq 3.3 takes a zero mean function; the qualities are
//! probabilities in [0, 1], so the process models them less their mean (a constant mean
//! function equal to the data's), and far from every observation the posterior returns to that
//! mean instead of to zero. [`Prior::Zero`] keeps the text's form. The hyper-parameters
//! {l, σ_f², σ_n²} are "learned from the training data": [`GaussianProcess::fit_evidence`]
//! takes the one of a grid with the largest log marginal likelihood.

use nalgebra::{DMatrix, DVector};

/// The kernel's hyper-parameters (Eq 3.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kernel {
    /// Bandwidth l, in feature units.
    pub length: f64,
    /// Function variance σ_f².
    pub signal_variance: f64,
    /// Noise variance σ_n².
    pub noise_variance: f64,
}

impl Kernel {
    /// k(g_i, g_j) of Eq 3.4 without the noise term (i ≠ j, or the latent function at one
    /// point).
    pub fn covariance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.signal_variance * correlation(self.length, a, b)
    }
}

/// exp(−‖a − b‖² / 2ℓ²): [`Kernel::covariance`] over the signal variance (a caller that keeps
/// these for a fixed bandwidth gets the very covariances the kernel computes).
pub fn correlation(length: f64, a: &[f64], b: &[f64]) -> f64 {
    let d2: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    (-d2 / (2.0 * length * length)).exp()
}

/// The prior mean function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prior {
    /// m(g) = 0 (Eq 3.3 as printed).
    Zero,
    /// m(g) = the mean of the observed qualities.
    DataMean,
}

/// A fitted process: the observations, the kernel and the factorised covariance.
#[derive(Debug, Clone)]
pub struct GaussianProcess {
    kernel: Kernel,
    points: Vec<Vec<f64>>,
    mean: f64,
    /// K(Gⁿ, Gⁿ) + σ_n² I, factorised.
    cholesky: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    /// (K + σ_n² I)⁻¹ (Qⁿ − m).
    alpha: DVector<f64>,
}

impl GaussianProcess {
    /// Fits the process to grasps `points` (feature vectors of one length) with qualities
    /// `values`; None when there are none or the covariance is not positive definite.
    pub fn fit(points: &[Vec<f64>], values: &[f64], kernel: Kernel, prior: Prior) -> Option<Self> {
        Self::fit_covariances(points, values, kernel, prior, |i, j| {
            kernel.covariance(&points[i], &points[j])
        })
    }

    /// [`Self::fit`] with the kernel's covariance between the `i`th and the `j`th of `points`
    /// (noise excluded) given by `covariance(i, j)`.
    pub fn fit_covariances(
        points: &[Vec<f64>],
        values: &[f64],
        kernel: Kernel,
        prior: Prior,
        covariance: impl Fn(usize, usize) -> f64,
    ) -> Option<Self> {
        let n = points.len();
        if n == 0 || values.len() != n {
            return None;
        }
        let mean = match prior {
            Prior::Zero => 0.0,
            Prior::DataMean => values.iter().sum::<f64>() / n as f64,
        };
        let k = DMatrix::from_fn(n, n, |i, j| {
            covariance(i, j) + if i == j { kernel.noise_variance } else { 0.0 }
        });
        let cholesky = k.cholesky()?;
        let y = DVector::from_iterator(n, values.iter().map(|v| v - mean));
        let alpha = cholesky.solve(&y);
        Some(Self {
            kernel,
            points: points.to_vec(),
            mean,
            cholesky,
            alpha,
        })
    }

    /// The fit of `kernels` with the largest log marginal likelihood (the hyper-parameters
    /// learned from the data).
    pub fn fit_evidence(
        points: &[Vec<f64>],
        values: &[f64],
        kernels: &[Kernel],
        prior: Prior,
    ) -> Option<Self> {
        Self::fit_evidence_covariances(points, values, kernels, prior, |k, i, j| {
            kernels[k].covariance(&points[i], &points[j])
        })
    }

    /// [`Self::fit_evidence`] with the `k`th kernel's covariances given by
    /// `covariance(k, i, j)` (as in [`Self::fit_covariances`]).
    pub fn fit_evidence_covariances(
        points: &[Vec<f64>],
        values: &[f64],
        kernels: &[Kernel],
        prior: Prior,
        covariance: impl Fn(usize, usize, usize) -> f64,
    ) -> Option<Self> {
        kernels
            .iter()
            .enumerate()
            .filter_map(|(k, kernel)| {
                Self::fit_covariances(points, values, *kernel, prior, |i, j| covariance(k, i, j))
            })
            .max_by(|a, b| {
                a.log_marginal_likelihood()
                    .total_cmp(&b.log_marginal_likelihood())
            })
    }

    /// The posterior of the quality at `g` (Eq 3.5): its mean μ and variance σ² (of the latent
    /// function, without the observation noise).
    pub fn posterior(&self, g: &[f64]) -> (f64, f64) {
        self.posterior_of(DVector::from_iterator(
            self.points.len(),
            self.points.iter().map(|p| self.kernel.covariance(g, p)),
        ))
    }

    /// [`Self::posterior`] at a grasp whose covariances with the fitted points (in their
    /// order, noise excluded) are `ks`.
    pub fn posterior_of(&self, ks: DVector<f64>) -> (f64, f64) {
        let mu = self.mean + ks.dot(&self.alpha);
        // The factor's upper triangle is not read: no copy of L per grasp.
        let v = self.cholesky.l_dirty().solve_lower_triangular(&ks);
        let var = match v {
            Some(v) => (self.kernel.signal_variance - v.norm_squared()).max(0.0),
            None => self.kernel.signal_variance,
        };
        (mu, var)
    }

    /// log p(Qⁿ | Gⁿ, l, σ_f², σ_n²).
    pub fn log_marginal_likelihood(&self) -> f64 {
        let n = self.points.len() as f64;
        let y = self.cholesky.l() * self.cholesky.l().transpose() * &self.alpha;
        let log_det: f64 = self
            .cholesky
            .l()
            .diagonal()
            .iter()
            .map(|d| d.ln())
            .sum::<f64>()
            * 2.0;
        -0.5 * y.dot(&self.alpha) - 0.5 * log_det - 0.5 * n * (2.0 * std::f64::consts::PI).ln()
    }

    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two observations, q(0) = 1 and q(1) = 0, l = 1, σ_f² = 1, σ_n² = 0.01, zero mean; at
    /// g = 0.5, by hand: K = [[1.01, e^−½], [e^−½, 1.01]], k* = e^−⅛ (1, 1),
    /// μ = k*ᵀK⁻¹Q = e^−⅛ (1.01 − e^−½) / (1.01² − e^−1) = 0.545920,
    /// σ² = 1 − 2 e^−¼ / (1.01 + e^−½) = 0.036454.
    #[test]
    fn posterior_matches_the_hand_computed_one() {
        let kernel = Kernel {
            length: 1.0,
            signal_variance: 1.0,
            noise_variance: 0.01,
        };
        let gp = GaussianProcess::fit(&[vec![0.0], vec![1.0]], &[1.0, 0.0], kernel, Prior::Zero)
            .unwrap();
        let (mu, var) = gp.posterior(&[0.5]);
        assert!((mu - 0.545920).abs() < 1e-6, "μ = {mu}");
        assert!((var - 0.036454).abs() < 1e-6, "σ² = {var}");
        // Far from both observations the posterior is the prior: zero mean, variance σ_f².
        let (mu, var) = gp.posterior(&[40.0]);
        assert!(mu.abs() < 1e-12 && (var - 1.0).abs() < 1e-12);
        // With the data's mean as the prior the far posterior returns to it (½).
        let gp = GaussianProcess::fit(
            &[vec![0.0], vec![1.0]],
            &[1.0, 0.0],
            kernel,
            Prior::DataMean,
        )
        .unwrap();
        assert!((gp.posterior(&[40.0]).0 - 0.5).abs() < 1e-12);
        // At an observation the mean is the observation, shrunk by the noise, and the variance
        // small.
        let (mu, var) = gp.posterior(&[0.0]);
        assert!(
            (mu - 1.0).abs() < 0.02 && var < 0.02,
            "μ = {mu}, σ² = {var}"
        );
    }

    /// log p(Q|G) for one observation q = 2 at any g with σ_f² = 1, σ_n² = 1, zero mean:
    /// −q²/(2·2) − ½ ln 2 − ½ ln 2π = −1 − 0.346574 − 0.918939.
    #[test]
    fn evidence_matches_the_hand_computed_one_and_picks_the_kernel() {
        let kernel = Kernel {
            length: 1.0,
            signal_variance: 1.0,
            noise_variance: 1.0,
        };
        let gp = GaussianProcess::fit(&[vec![3.0]], &[2.0], kernel, Prior::Zero).unwrap();
        let want = -1.0 - 0.5 * 2f64.ln() - 0.5 * (2.0 * std::f64::consts::PI).ln();
        assert!((gp.log_marginal_likelihood() - want).abs() < 1e-12);
        // A smooth function sampled densely: the evidence prefers a bandwidth near its scale
        // over one far too short or far too long.
        let xs: Vec<Vec<f64>> = (0..30).map(|i| vec![i as f64 * 0.1]).collect();
        let ys: Vec<f64> = xs.iter().map(|x| (x[0] * 2.0).sin()).collect();
        let kernels: Vec<Kernel> = [0.02, 0.5, 20.0]
            .iter()
            .map(|&length| Kernel {
                length,
                signal_variance: 1.0,
                noise_variance: 1e-4,
            })
            .collect();
        let gp = GaussianProcess::fit_evidence(&xs, &ys, &kernels, Prior::Zero).unwrap();
        assert_eq!(gp.kernel().length, 0.5);
    }
}
