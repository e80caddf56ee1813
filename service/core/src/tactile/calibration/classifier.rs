//! The light classifier a calibration fits in the server (issue 16): linear discriminant
//! analysis with a shared, shrunk covariance. Each feature is standardised; each class has its
//! mean; the within-class covariance is pooled over the classes and shrunk toward a multiple of
//! the identity by the Ledoit–Wolf formula (Ledoit & Wolf 2004, as scikit-learn's
//! `LinearDiscriminantAnalysis(solver="lsqr", shrinkage="auto")`), so that tens of correlated
//! features fit from a few recordings without a singular covariance. With each label's prior
//! π_c its share of the examples (as there: a label seen rarely is predicted rarely),
//! P(c | x) ∝ π_c exp(w_cᵀz − ½ μ_cᵀw_c), Σ w_c = μ_c. One pass over the examples and one
//! Cholesky solve: milliseconds for thousands of windows, no iteration, no seed.
//!
//! Labels may name a *kind* within a class after a slash (`plastic/eva`): each full label gets
//! its own mean, and [`LinearDiscriminant::class_probabilities`] adds the kinds of a class up —
//! a class made of unlike materials is then several Gaussians, not one spread over them all.

use crate::error::FieldError;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Separates a class from its kind in a label.
pub const KIND_SEPARATOR: char = '/';

/// A fitted linear discriminant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinearDiscriminant {
    /// The labels fitted (class, or class/kind), sorted; `weights` and `bias` in this order.
    pub labels: Vec<String>,
    /// Per feature: mean and standard deviation over all examples (standardisation).
    pub offset: Vec<f64>,
    pub scale: Vec<f64>,
    /// Per label: w = Σ⁻¹μ over the standardised features, and −½ μᵀw + ln π.
    pub weights: Vec<Vec<f64>>,
    pub bias: Vec<f64>,
    /// The Ledoit–Wolf shrinkage used, in [0, 1].
    pub shrinkage: f64,
}

impl LinearDiscriminant {
    /// Fits on `(label, features)` examples: at least two classes (labels before the
    /// [`KIND_SEPARATOR`]), every example with the same number of finite features. `field`
    /// names the input in errors.
    pub fn fit(examples: &[(String, Vec<f64>)], field: &str) -> Result<Self, FieldError> {
        let Some((_, first)) = examples.first() else {
            return Err(FieldError::new(field, "no examples"));
        };
        let dim = first.len();
        if dim == 0 {
            return Err(FieldError::new(field, "examples have no features"));
        }
        for (k, (_, x)) in examples.iter().enumerate() {
            if x.len() != dim {
                return Err(FieldError::new(
                    field,
                    format!("example {k} has {} features, the first {dim}", x.len()),
                ));
            }
            if let Some(i) = x.iter().position(|v| !v.is_finite()) {
                return Err(FieldError::new(
                    field,
                    format!("example {k}: feature {i} is not finite"),
                ));
            }
        }
        let mut labels: Vec<String> = examples.iter().map(|(c, _)| c.clone()).collect();
        labels.sort();
        labels.dedup();
        let mut classes: Vec<&str> = labels.iter().map(|l| class_of(l)).collect();
        classes.dedup();
        if classes.len() < 2 {
            return Err(FieldError::new(
                field,
                format!(
                    "one class only ({}): a classifier needs two or more",
                    classes[0]
                ),
            ));
        }
        let n = examples.len();
        let offset: Vec<f64> = (0..dim)
            .map(|i| examples.iter().map(|(_, x)| x[i]).sum::<f64>() / n as f64)
            .collect();
        let scale: Vec<f64> = (0..dim)
            .map(|i| {
                let v = examples
                    .iter()
                    .map(|(_, x)| (x[i] - offset[i]).powi(2))
                    .sum::<f64>()
                    / n as f64;
                if v > 0.0 { v.sqrt() } else { 1.0 }
            })
            .collect();
        let z = DMatrix::from_fn(n, dim, |r, i| (examples[r].1[i] - offset[i]) / scale[i]);
        let label_of: Vec<usize> = examples
            .iter()
            .map(|(l, _)| labels.binary_search(l).unwrap_or(0))
            .collect();
        let mut means = DMatrix::<f64>::zeros(labels.len(), dim);
        let mut counts = vec![0.0; labels.len()];
        for (r, &k) in label_of.iter().enumerate() {
            counts[k] += 1.0;
            for i in 0..dim {
                means[(k, i)] += z[(r, i)];
            }
        }
        for (k, c) in counts.iter().enumerate() {
            for i in 0..dim {
                means[(k, i)] /= c;
            }
        }
        let centred = DMatrix::from_fn(n, dim, |r, i| z[(r, i)] - means[(label_of[r], i)]);
        let (covariance, shrinkage) = ledoit_wolf(&centred);
        let Some(chol) = covariance.cholesky() else {
            return Err(FieldError::new(
                field,
                "the features' covariance is singular (every feature constant?)",
            ));
        };
        let mut weights = Vec::with_capacity(labels.len());
        let mut bias = Vec::with_capacity(labels.len());
        for (k, count) in counts.iter().enumerate() {
            let mu = DVector::from_iterator(dim, means.row(k).iter().copied());
            let w = chol.solve(&mu);
            bias.push(-0.5 * mu.dot(&w) + (count / n as f64).ln());
            weights.push(w.iter().copied().collect());
        }
        Ok(Self {
            labels,
            offset,
            scale,
            weights,
            bias,
            shrinkage,
        })
    }

    /// P(label | x) for each of `labels`; `x` must have the fitted length.
    pub fn probabilities(&self, x: &[f64]) -> Vec<f64> {
        let z: Vec<f64> = x
            .iter()
            .zip(self.offset.iter().zip(&self.scale))
            .map(|(v, (o, s))| (v - o) / s)
            .collect();
        let score: Vec<f64> = self
            .weights
            .iter()
            .zip(&self.bias)
            .map(|(w, b)| b + w.iter().zip(&z).map(|(a, b)| a * b).sum::<f64>())
            .collect();
        let top = score.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let e: Vec<f64> = score.iter().map(|s| (s - top).exp()).collect();
        let sum: f64 = e.iter().sum();
        e.iter().map(|v| v / sum).collect()
    }

    /// The classes (labels before the kind), sorted, with P(class | x): the sum over its kinds.
    pub fn class_probabilities(&self, x: &[f64]) -> Vec<(&str, f64)> {
        let mut out: std::collections::BTreeMap<&str, f64> = std::collections::BTreeMap::new();
        for (label, p) in self.labels.iter().zip(self.probabilities(x)) {
            *out.entry(class_of(label)).or_default() += p;
        }
        out.into_iter().collect()
    }

    /// The most probable class.
    pub fn classify(&self, x: &[f64]) -> &str {
        self.class_probabilities(x)
            .into_iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map_or("", |(c, _)| c)
    }
}

/// The class a label names: the part before the [`KIND_SEPARATOR`].
pub fn class_of(label: &str) -> &str {
    label.split(KIND_SEPARATOR).next().unwrap_or(label)
}

/// The covariance of the rows of `x` (each already centred on its class mean), shrunk toward
/// tr(S)/p · I by the Ledoit–Wolf estimate of the best weight, and that weight.
fn ledoit_wolf(x: &DMatrix<f64>) -> (DMatrix<f64>, f64) {
    let (n, p) = (x.nrows() as f64, x.ncols());
    let s = x.transpose() * x / n;
    let mu = s.trace() / p as f64;
    let mut target = DMatrix::<f64>::zeros(p, p);
    target.fill_diagonal(mu);
    let delta = (&s - &target).norm_squared() / p as f64;
    let x2 = x.map(|v| v * v);
    let beta = ((x2.transpose() * &x2).sum() / n - s.norm_squared()) / (n * p as f64);
    let shrinkage = if delta > 0.0 {
        (beta.min(delta) / delta).clamp(0.0, 1.0)
    } else {
        1.0
    };
    (s * (1.0 - shrinkage) + target * shrinkage, shrinkage)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ex(c: &str, x: &[f64]) -> (String, Vec<f64>) {
        (c.to_string(), x.to_vec())
    }

    /// One feature, by hand: values −1.1, −0.9 (a) and 0.9, 1.1 (b); standardised by
    /// σ = √1.01, class means ∓1/σ, within-class variance 0.01/σ² (one feature: the shrinkage
    /// target is the variance itself), so w_b = (1/σ)/(0.01/σ²) = 100σ and the boundary at 0.
    #[test]
    fn one_feature_by_hand() {
        let d = LinearDiscriminant::fit(
            &[
                ex("a", &[-1.1]),
                ex("a", &[-0.9]),
                ex("b", &[0.9]),
                ex("b", &[1.1]),
            ],
            "recordings",
        )
        .unwrap();
        assert_eq!(d.labels, vec!["a", "b"]);
        let sigma = 1.01f64.sqrt();
        assert!(
            (d.weights[1][0] - 100.0 * sigma).abs() < 1e-9,
            "{:?}",
            d.weights
        );
        assert!(
            (d.bias[1] + 0.5 * 100.0 - 0.5f64.ln()).abs() < 1e-9,
            "{:?}",
            d.bias
        );
        let p = d.probabilities(&[0.0]);
        assert!((p[0] - 0.5).abs() < 1e-12);
        // 0.01 from the boundary: z = 0.01/σ, log-odds 2·100σ·0.01/σ = 2.
        let p = d.probabilities(&[0.01]);
        assert!((p[1] - 1.0 / (1.0 + (-2.0f64).exp())).abs() < 1e-9, "{p:?}");
    }

    /// Two features that move together (a common offset of ±3 in both) and classes apart only
    /// in their difference: the shared covariance sees through the common offset, which a
    /// per-feature (diagonal) model would read as the larger signal.
    #[test]
    fn correlated_features_are_seen_through() {
        let mut examples = Vec::new();
        for (k, common) in [-3.0, -1.0, 1.0, 3.0].iter().enumerate() {
            let e = 0.05 * k as f64;
            examples.push(ex("a", &[common - 0.5 + e, common + 0.5]));
            examples.push(ex("b", &[common + 0.5 - e, common - 0.5]));
        }
        let d = LinearDiscriminant::fit(&examples, "recordings").unwrap();
        assert!(d.shrinkage < 0.5, "{}", d.shrinkage);
        // Far along the common direction, but on b's side of the difference.
        assert_eq!(d.classify(&[-4.6, -5.4]), "b");
        assert_eq!(d.classify(&[5.4, 4.6]), "b");
        assert_eq!(d.classify(&[4.6, 5.4]), "a");
    }

    /// Kinds of a class are separate means whose probabilities add up: class x is two
    /// clusters either side of class y's.
    #[test]
    fn kinds_of_a_class_add_up() {
        let mut examples = Vec::new();
        for e in [-0.1, 0.0, 0.1] {
            examples.push(ex("x/low", &[-2.0 + e]));
            examples.push(ex("x/high", &[2.0 + e]));
            examples.push(ex("y", &[e]));
        }
        let d = LinearDiscriminant::fit(&examples, "recordings").unwrap();
        assert_eq!(d.labels, vec!["x/high", "x/low", "y"]);
        assert_eq!(d.classify(&[-2.0]), "x");
        assert_eq!(d.classify(&[2.0]), "x");
        assert_eq!(d.classify(&[0.0]), "y");
        let c = d.class_probabilities(&[1.0]);
        assert_eq!(c.len(), 2);
        assert!((c[0].1 + c[1].1 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bad_examples_are_refused_naming_the_input() {
        let one = LinearDiscriminant::fit(&[ex("a/1", &[1.0]), ex("a/2", &[2.0])], "recordings");
        assert!(one.unwrap_err().message.contains("one class only (a)"));
        let ragged = LinearDiscriminant::fit(&[ex("a", &[1.0]), ex("b", &[2.0, 3.0])], "r");
        assert!(
            ragged
                .unwrap_err()
                .message
                .contains("example 1 has 2 features")
        );
        let nan = LinearDiscriminant::fit(&[ex("a", &[1.0]), ex("b", &[f64::NAN])], "r");
        let e = nan.unwrap_err();
        assert_eq!(e.field, "r");
        assert!(e.message.contains("not finite"));
        assert!(LinearDiscriminant::fit(&[], "r").is_err());
    }
}
