//! Force estimation from the tactile image by a 1-D Gaussian mixture (dissertation ch. 6.4,
//! Eq 6.5–6.7).
//!
//! 1. A GMM with K = 3 components is fitted by EM to the 40 pixel values of t_img (Eq 6.5).
//! 2. The component with the highest mean is the contact cluster c.
//! 3. **P_c(e)** is read as the *posterior responsibility* of the contact component for pixel e,
//!    P(c | e) = π_c N(e | μ_c, σ_c) / Σ_k π_k N(e | μ_k, σ_k) ∈ [0, 1]. The dissertation writes
//!    P_c(e) = N(e | μ_c, δ_c), a density, which is not a probability (it depends on the units and
//!    can exceed 1), so a fixed threshold α would not mean anything across sensors; the posterior is
//!    the probability that "the pixel belongs to the contact cluster" the text describes. A pixel is
//!    contact when P_c(e) ≥ α (Eq 6.6).
//! 4. Contact location p = the mean of a Gaussian fitted to the contact pixels' image coordinates,
//!    each weighted by P_c(e) (its covariance is reported as well); area = the number of contact
//!    pixels (and × the layout's pixel area in mm²).
//! 5. Normal force f = Σ P_c(eᵢ)·eᵢ over the contact pixels (Eq 6.7), in raw tared sensor units;
//!    × a calibration gain when one is configured.
//!
//! EM details: deterministic initialisation (means spread evenly over the value range, at
//! min + (j + ½)/K · (max − min); equal weights; variance = overall variance / K — quantiles would
//! put every initial mean on the background of a mostly untouched image), variance floor (so that
//! constant images and exactly repeated values do not produce singular components), stop when the
//! mean log-likelihood improves by less than `tolerance` (default 1e-5) or after `max_iterations`
//! (default 100).

use super::layout::{IMAGE_COLS, IMAGE_ROWS, SensorLayout};
use super::tactile_image::TactileImage;

/// A 1-D Gaussian mixture (Eq 6.5): weights π_k, means μ_k and variances σ_k².
#[derive(Debug, Clone, PartialEq)]
pub struct Gmm1d {
    pub weights: Vec<f64>,
    pub means: Vec<f64>,
    pub variances: Vec<f64>,
    /// EM iterations run.
    pub iterations: usize,
    /// Mean log-likelihood of the data at the end.
    pub log_likelihood: f64,
}

/// EM settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmOptions {
    pub components: usize,
    pub max_iterations: usize,
    /// Stop when the mean log-likelihood improves by less than this.
    pub tolerance: f64,
    /// Smallest variance of a component, in squared sensor units.
    pub variance_floor: f64,
}

impl Default for EmOptions {
    fn default() -> Self {
        Self {
            components: 3,
            max_iterations: 100,
            tolerance: 1e-5,
            variance_floor: 1e-2,
        }
    }
}

fn normal_pdf(x: f64, mean: f64, var: f64) -> f64 {
    let d = x - mean;
    (-0.5 * d * d / var).exp() / (2.0 * std::f64::consts::PI * var).sqrt()
}

impl Gmm1d {
    /// Fits the mixture to `data` by EM (Eq 6.5) from the deterministic initialisation (module
    /// doc). `data` must not be empty.
    ///
    /// Not warm-started from the previous frame: on the real recordings that changed the contact
    /// area in 74 % of the frames (EM on 40 pixels has many local optima), so every frame starts
    /// from the same initialisation and the result depends on the image alone.
    pub fn fit(data: &[f64], opt: &EmOptions) -> Self {
        assert!(!data.is_empty(), "GMM fit needs data");
        let k = opt.components.max(1);
        let n = data.len() as f64;
        let lo = data.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = data.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mean = data.iter().sum::<f64>() / n;
        let var = data.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        let mut g = Self {
            weights: vec![1.0 / k as f64; k],
            means: (0..k)
                .map(|j| lo + (j as f64 + 0.5) / k as f64 * (hi - lo))
                .collect(),
            variances: vec![(var / k as f64).max(opt.variance_floor); k],
            iterations: 0,
            log_likelihood: f64::NEG_INFINITY,
        };
        // EM over the distinct values with their multiplicities: identical to EM over all
        // pixels, and cheaper — sensor counts are integers and the filled pixels of the tactile
        // image repeat their neighbours, so the 40 pixels of a real BioTac image hold fewer
        // distinct values.
        let mut sorted = data.to_vec();
        sorted.sort_by(f64::total_cmp);
        let mut values: Vec<f64> = Vec::with_capacity(sorted.len());
        let mut counts: Vec<f64> = Vec::with_capacity(sorted.len());
        for x in sorted {
            match values.last() {
                Some(&last) if last == x => *counts.last_mut().expect("same length") += 1.0,
                _ => {
                    values.push(x);
                    counts.push(1.0);
                }
            }
        }
        let mut resp = vec![0.0; values.len() * k];
        // Per component: π_j / sqrt(2π σ_j²) and −1 / (2σ_j²), computed once per iteration.
        let mut scale = vec![0.0; k];
        let mut exponent = vec![0.0; k];
        let mut prev = f64::NEG_INFINITY;
        for it in 0..opt.max_iterations {
            for j in 0..k {
                scale[j] = g.weights[j] / (2.0 * std::f64::consts::PI * g.variances[j]).sqrt();
                exponent[j] = -0.5 / g.variances[j];
            }
            // E step.
            let mut ll = 0.0;
            // Σ c_i ln s_i as ln Π s_i^c_i: one logarithm per ~dozen values instead of one per
            // value (the E step's logarithms were a sixth of a session's CPU time).
            let mut product = 1.0;
            for (i, (&x, &c)) in values.iter().zip(&counts).enumerate() {
                let row = &mut resp[i * k..(i + 1) * k];
                let mut s = 0.0;
                for (j, rj) in row.iter_mut().enumerate() {
                    let d = x - g.means[j];
                    let a = exponent[j] * d * d;
                    // exp underflows to exactly 0 below −745.2; skip libm's slow underflow path.
                    *rj = if a < -745.2 { 0.0 } else { scale[j] * a.exp() };
                    s += *rj;
                }
                if s > 0.0 && s.is_finite() {
                    row.iter_mut().for_each(|r| *r /= s);
                    let sc = if c == 1.0 { s } else { s.powi(c as i32) };
                    if sc > 0.0 && sc.is_finite() {
                        product *= sc;
                    } else {
                        ll += c * s.ln();
                    }
                    if !(1e-150..=1e150).contains(&product) {
                        ll += product.ln();
                        product = 1.0;
                    }
                } else {
                    // Underflow far from every component: give the value to the nearest mean.
                    let near = (0..k)
                        .min_by(|&a, &b| (x - g.means[a]).abs().total_cmp(&(x - g.means[b]).abs()))
                        .unwrap();
                    row.iter_mut()
                        .enumerate()
                        .for_each(|(j, r)| *r = (j == near) as u8 as f64);
                    ll += -1e3 * c;
                }
            }
            ll += product.ln();
            ll /= n;
            // M step.
            for j in 0..k {
                let nk: f64 = (0..values.len()).map(|i| counts[i] * resp[i * k + j]).sum();
                if nk < 1e-9 {
                    // An empty component keeps its mean and takes the floor variance.
                    g.weights[j] = 1e-9;
                    g.variances[j] = opt.variance_floor.max(var / k as f64);
                    continue;
                }
                let m = values
                    .iter()
                    .zip(&counts)
                    .enumerate()
                    .map(|(i, (x, c))| c * resp[i * k + j] * x)
                    .sum::<f64>()
                    / nk;
                let v = values
                    .iter()
                    .zip(&counts)
                    .enumerate()
                    .map(|(i, (x, c))| c * resp[i * k + j] * (x - m).powi(2))
                    .sum::<f64>()
                    / nk;
                g.weights[j] = nk / n;
                g.means[j] = m;
                g.variances[j] = v.max(opt.variance_floor);
            }
            let wsum: f64 = g.weights.iter().sum();
            g.weights.iter_mut().for_each(|w| *w /= wsum);
            g.iterations = it + 1;
            g.log_likelihood = ll;
            if (ll - prev).abs() < opt.tolerance {
                break;
            }
            prev = ll;
        }
        g
    }

    /// Index of the component with the highest mean (the contact cluster).
    pub fn highest_mean_component(&self) -> usize {
        (0..self.means.len())
            .max_by(|&a, &b| self.means[a].total_cmp(&self.means[b]))
            .unwrap()
    }

    /// Posterior responsibility P(j | x).
    pub fn responsibility(&self, j: usize, x: f64) -> f64 {
        let (mut s, mut pj) = (0.0, 0.0);
        for k in 0..self.means.len() {
            let p = self.weights[k] * normal_pdf(x, self.means[k], self.variances[k]);
            s += p;
            if k == j {
                pj = p;
            }
        }
        if s > 0.0 && s.is_finite() {
            pj / s
        } else {
            // Far outside every component: the nearest mean takes it (the highest for x above all).
            let near = (0..self.means.len())
                .min_by(|&a, &b| {
                    (x - self.means[a])
                        .abs()
                        .total_cmp(&(x - self.means[b]).abs())
                })
                .unwrap();
            (near == j) as u8 as f64
        }
    }
}

/// Contact information Ψ = {p, f, C_img} of one finger (ch. 6.4).
#[derive(Debug, Clone, PartialEq)]
pub struct ContactEstimate {
    /// Normal force f (Eq 6.7): raw tared units, or × the calibration gain when one is set.
    pub force: f64,
    /// Contact centre p in image coordinates (row, col), pixel centres at integers; `None` when
    /// no pixel is contact.
    pub location: Option<[f64; 2]>,
    /// Covariance of the Gaussian fitted to the contact pixels (row/col), pixels².
    pub location_covariance: Option<[[f64; 2]; 2]>,
    /// C_img: contact pixels (row, col, P_c).
    pub contact_pixels: Vec<(usize, usize, f64)>,
    /// |C_img| in pixels and mm² (the layout's pixel pitch).
    pub area_pixels: usize,
    pub area_mm2: f64,
    /// The fitted mixture and the index of its contact component.
    pub gmm: Gmm1d,
    pub contact_component: usize,
}

/// Force estimation settings: α of Eq 6.6, EM options and the optional calibration gain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceEstimator {
    pub alpha: f64,
    pub em: EmOptions,
    /// Newtons per raw unit of Eq 6.7; `None` = report raw units.
    pub calibration_gain: Option<f64>,
}

impl Default for ForceEstimator {
    fn default() -> Self {
        Self {
            alpha: 0.5,
            em: EmOptions::default(),
            calibration_gain: None,
        }
    }
}

impl ForceEstimator {
    /// Ψ = {p, f, C_img} from a tactile image (Eq 6.5–6.7).
    pub fn estimate(&self, img: &TactileImage, layout: &SensorLayout) -> ContactEstimate {
        let data: Vec<f64> = img.pixels().map(|(_, _, v)| v).collect();
        let gmm = Gmm1d::fit(&data, &self.em);
        let c = gmm.highest_mean_component();
        let mut contact = Vec::new();
        for (r, col, v) in img.pixels() {
            let p = gmm.responsibility(c, v);
            // Eq 6.6: contact iff P_c(e) ≥ α.
            if p >= self.alpha {
                contact.push((r, col, p));
            }
        }
        // Eq 6.7: f = Σ P_c(eᵢ)·eᵢ over C_img.
        let raw: f64 = contact
            .iter()
            .map(|&(r, col, p)| p * img.values[r][col])
            .sum();
        let force = raw * self.calibration_gain.unwrap_or(1.0);
        let (location, cov) = weighted_gaussian(&contact);
        ContactEstimate {
            force,
            location,
            location_covariance: cov,
            area_pixels: contact.len(),
            area_mm2: contact.len() as f64 * layout.pixel_area_mm2(),
            contact_pixels: contact,
            gmm,
            contact_component: c,
        }
    }
}

/// Mean and covariance of the contact pixels' (row, col), weighted by P_c.
#[allow(clippy::type_complexity)]
fn weighted_gaussian(px: &[(usize, usize, f64)]) -> (Option<[f64; 2]>, Option<[[f64; 2]; 2]>) {
    let w: f64 = px.iter().map(|p| p.2).sum();
    if px.is_empty() || w <= 0.0 {
        return (None, None);
    }
    let mr = px.iter().map(|p| p.2 * p.0 as f64).sum::<f64>() / w;
    let mc = px.iter().map(|p| p.2 * p.1 as f64).sum::<f64>() / w;
    let (mut srr, mut src, mut scc) = (0.0, 0.0, 0.0);
    for &(r, c, p) in px {
        let (dr, dc) = (r as f64 - mr, c as f64 - mc);
        srr += p * dr * dr;
        src += p * dr * dc;
        scc += p * dc * dc;
    }
    (
        Some([mr, mc]),
        Some([[srr / w, src / w], [src / w, scc / w]]),
    )
}

const _: () = assert!(IMAGE_ROWS * IMAGE_COLS == 40);

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Box–Muller standard normal.
    fn gauss(rng: &mut ChaCha8Rng) -> f64 {
        let u1: f64 = rng.random::<f64>().max(1e-12);
        let u2: f64 = rng.random();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }

    #[test]
    fn gmm_recovers_known_components_on_synthetic_tactile_images() {
        // Many synthetic 8×5 images: background ~ N(2, 0.5²) (20 px), rim ~ N(20, 1²) (12 px),
        // contact ~ N(60, 2²) (8 px). Fit per image, average the recovered parameters.
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let truth = [(2.0, 0.5, 20), (20.0, 1.0, 12), (60.0, 2.0, 8)];
        let mut acc = [[0.0; 3]; 3];
        let trials = 50;
        for _ in 0..trials {
            let mut data = Vec::new();
            for &(m, s, n) in &truth {
                for _ in 0..n {
                    data.push(m + s * gauss(&mut rng));
                }
            }
            let g = Gmm1d::fit(&data, &EmOptions::default());
            let mut order: Vec<usize> = (0..3).collect();
            order.sort_by(|&a, &b| g.means[a].total_cmp(&g.means[b]));
            for (t, &j) in order.iter().enumerate() {
                acc[t][0] += g.means[j] / trials as f64;
                acc[t][1] += g.variances[j].sqrt() / trials as f64;
                acc[t][2] += g.weights[j] / trials as f64;
            }
            assert_eq!(g.highest_mean_component(), order[2]);
        }
        for (t, &(m, s, n)) in truth.iter().enumerate() {
            assert!(
                (acc[t][0] - m).abs() < 0.1 * s.max(1.0),
                "mean {t}: {:?}",
                acc[t]
            );
            assert!((acc[t][1] - s).abs() < 0.35 * s, "sd {t}: {:?}", acc[t]);
            assert!(
                (acc[t][2] - n as f64 / 40.0).abs() < 0.02,
                "weight {t}: {:?}",
                acc[t]
            );
        }
    }

    #[test]
    fn gmm_is_deterministic_and_survives_constant_images() {
        let g = Gmm1d::fit(&[5.0; 40], &EmOptions::default());
        assert!(g.means.iter().all(|m| (m - 5.0).abs() < 1e-9));
        assert!(g.variances.iter().all(|v| *v >= 1e-2));
        let data: Vec<f64> = (0..40).map(|i| (i * 7 % 13) as f64).collect();
        assert_eq!(
            Gmm1d::fit(&data, &EmOptions::default()),
            Gmm1d::fit(&data, &EmOptions::default())
        );
    }

    #[test]
    fn contact_location_and_force_match_hand_computed_values() {
        // Background 0 everywhere, a 2×2 blob of 100 at rows 2–3, cols 1–2, and one pixel of
        // 100 at (6, 4)... but the filled image comes straight from values here: 35 zeros and 5
        // pixels of 100. The GMM separates them cleanly: P_c = 1 for the 100s, ≈ 0 for the 0s.
        let mut values = [[0.0; IMAGE_COLS]; IMAGE_ROWS];
        for (r, c) in [(2, 1), (2, 2), (3, 1), (3, 2), (6, 4)] {
            values[r][c] = 100.0;
        }
        let img = TactileImage { values };
        let layout = SensorLayout::custom("sq", vec![[0.0, 0.0], [16.0, 10.0]]).unwrap();
        assert_eq!(layout.pixel_area_mm2(), 2.0 * 2.0);
        let est = ForceEstimator::default().estimate(&img, &layout);
        assert_eq!(est.area_pixels, 5);
        assert_eq!(est.area_mm2, 20.0);
        // f = Σ P_c e = 5 × 1 × 100 (Eq 6.7).
        assert!((est.force - 500.0).abs() < 1e-6, "{}", est.force);
        // p = mean of (2,1),(2,2),(3,1),(3,2),(6,4) = (16/5, 10/5) = (3.2, 2.0).
        let p = est.location.unwrap();
        assert!(
            (p[0] - 3.2).abs() < 1e-9 && (p[1] - 2.0).abs() < 1e-9,
            "{p:?}"
        );
        // Covariance: rows ((−1.2)²·2 + (−0.2)²·2 + 2.8²)/5 = 2.16, cols (1 + 0 + 1 + 0 + 4)/5 =
        // 1.2, cross ((−1.2)(−1) + (−0.2)(−1) + 2.8·2)/5 = 1.4.
        let cov = est.location_covariance.unwrap();
        assert!((cov[0][0] - 2.16).abs() < 1e-9, "{cov:?}");
        assert!((cov[1][1] - 1.2).abs() < 1e-9, "{cov:?}");
        assert!((cov[0][1] - 1.4).abs() < 1e-9, "{cov:?}");
        // Calibration gain scales the force only.
        let cal = ForceEstimator {
            calibration_gain: Some(0.01),
            ..Default::default()
        }
        .estimate(&img, &layout);
        assert!((cal.force - 5.0).abs() < 1e-8);
        assert_eq!(cal.location, est.location);
    }

    #[test]
    fn graded_contact_weights_pixels_by_their_posterior() {
        // Three levels: 0 (30 px), 40 (6 px), 100 (4 px): the contact cluster is the 100s.
        let mut values = [[0.0; IMAGE_COLS]; IMAGE_ROWS];
        for (i, (r, c)) in [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2)]
            .iter()
            .enumerate()
        {
            values[*r][*c] = 40.0 + i as f64 * 0.1;
        }
        for (r, c) in [(7, 3), (7, 4), (6, 3), (6, 4)] {
            values[r][c] = 100.0;
        }
        let img = TactileImage { values };
        let layout = SensorLayout::biotac();
        let est = ForceEstimator::default().estimate(&img, &layout);
        assert_eq!(est.area_pixels, 4);
        assert!((est.force - 400.0).abs() < 1e-6);
        let p = est.location.unwrap();
        assert!((p[0] - 6.5).abs() < 1e-9 && (p[1] - 3.5).abs() < 1e-9);
    }
}
