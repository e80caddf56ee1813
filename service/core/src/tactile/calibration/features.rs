//! The hand features a calibration classifies (issue 16), per window t_seq of a session's
//! tared samples: the vibration spectrum of the dynamic pressure pac (texture: a slide over a
//! material excites the skin at the frequencies its surface sets), the thermal channels (tdc,
//! tac and their change: metal draws heat fastest, foam slowest), the static pressure pdc and
//! the electrode pattern (how the skin deforms). On the real BioTac slides (split by recording,
//! `tests/tactile_calibration.rs`) the spectrum is the strongest single group; the electrodes
//! come next; every group adds.
//!
//! A sensor that gives only its electrodes (a BioTac SP) has its own set
//! ([`Features::electrodes_only`]): the electrodes' means and pattern as above, and how the
//! pattern changed over the window — each electrode's change from the first sample to the
//! last, and the log of that change's size, which a slide makes larger than a held touch.

use super::super::detector::DetectorSample;
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// Samples per spectrum block of the concatenated pac signal (at a BioTac's 2.2 kHz, 58 ms).
const BLOCK: usize = 128;
/// Half-octave bands of the block's spectrum, in DFT bins [lo, hi) (bin k ↔ k·2200/128 Hz:
/// 17 Hz … 1.1 kHz).
const BANDS: [(usize, usize); 11] = [
    (1, 2),
    (2, 3),
    (3, 4),
    (4, 6),
    (6, 8),
    (8, 11),
    (11, 16),
    (16, 23),
    (23, 32),
    (32, 45),
    (45, 65),
];
/// Scalar features beside the bands: tdc, tac, their change over the window, pdc, and the
/// vibration's amplitude.
const SCALARS: usize = 6;

/// The number of features of a window with `electrodes` electrodes.
pub fn feature_count(electrodes: usize) -> usize {
    BANDS.len() + SCALARS + 2 * electrodes
}

/// The number of features of an electrodes-only window of `window_length` samples: the
/// change over the window only when it has two or more.
pub fn electrode_feature_count(electrodes: usize, window_length: usize) -> usize {
    if window_length > 1 {
        3 * electrodes + 1
    } else {
        2 * electrodes
    }
}

/// Computes [`Features::of`] windows; holds the FFT plan (build once per detector).
#[derive(Clone)]
pub struct Features {
    fft: Arc<dyn Fft<f64>>,
    hann: Vec<f64>,
    /// The sensor gives only its electrodes ([`Features::electrodes_only`]).
    electrodes_only: bool,
}

impl std::fmt::Debug for Features {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Features").field("block", &BLOCK).finish()
    }
}

impl Default for Features {
    fn default() -> Self {
        Self {
            fft: FftPlanner::new().plan_fft_forward(BLOCK),
            hann: (0..BLOCK)
                .map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / (BLOCK - 1) as f64).cos())
                .collect(),
            electrodes_only: false,
        }
    }
}

impl Features {
    /// The features of a sensor that gives only its electrodes (module doc).
    pub fn electrodes_only() -> Self {
        Self {
            electrodes_only: true,
            ..Self::default()
        }
    }

    /// The features of a sensor as its calibration reads it.
    pub fn for_sensor(electrodes_only: bool) -> Self {
        if electrodes_only {
            Self::electrodes_only()
        } else {
            Self::default()
        }
    }

    /// The features of one window (oldest sample first, every one with the same electrode
    /// count): ln(1 + mean energy) in each half-octave band of the first-differenced pac signal
    /// (every sample's pac samples in one sequence; the difference keeps the AC-coupled
    /// channel's drift out), mean tdc, mean tac, their change from the first sample to the
    /// last, mean pdc, ln(1 + the pac samples' standard deviation); each electrode's mean, and
    /// the same as a pattern — each over 1 + their sum — which the touch's pressure scales less.
    pub fn of(&self, window: &[DetectorSample]) -> Vec<f64> {
        if self.electrodes_only {
            return electrode_features(window);
        }
        let n = window.len().max(1) as f64;
        let mean = |f: &dyn Fn(&DetectorSample) -> f64| window.iter().map(f).sum::<f64>() / n;
        let pac: Vec<f64> = window
            .iter()
            .flat_map(|s| s.pac_samples.iter().copied())
            .collect();
        let diff: Vec<f64> = pac.windows(2).map(|w| w[1] - w[0]).collect();
        let mut f = self.band_energies(&diff);
        let change = |g: &dyn Fn(&DetectorSample) -> f64| {
            window
                .first()
                .zip(window.last())
                .map_or(0.0, |(a, b)| g(b) - g(a))
        };
        f.push(mean(&|s| s.tdc));
        f.push(mean(&|s| s.tac));
        f.push(change(&|s| s.tdc));
        f.push(change(&|s| s.tac));
        f.push(mean(&|s| s.pdc));
        let m = pac.iter().sum::<f64>() / pac.len().max(1) as f64;
        let var = pac.iter().map(|v| (v - m).powi(2)).sum::<f64>() / pac.len().max(1) as f64;
        f.push(var.sqrt().ln_1p());
        f.extend(electrode_pattern(window));
        f
    }

    /// ln(1 + mean energy) in each of [`BANDS`] over the signal's whole [`BLOCK`]s (Hann
    /// window, block mean removed); a signal shorter than a block is zero-padded to one.
    fn band_energies(&self, signal: &[f64]) -> Vec<f64> {
        let mut energy = [0.0; BANDS.len()];
        let blocks = (signal.len() / BLOCK).max(1);
        let mut buf = vec![Complex::new(0.0, 0.0); BLOCK];
        for b in 0..blocks {
            let seg = |i: usize| signal.get(b * BLOCK + i).copied().unwrap_or(0.0);
            let m = (0..BLOCK).map(seg).sum::<f64>() / BLOCK as f64;
            for (i, c) in buf.iter_mut().enumerate() {
                *c = Complex::new((seg(i) - m) * self.hann[i], 0.0);
            }
            self.fft.process(&mut buf);
            for (j, &(lo, hi)) in BANDS.iter().enumerate() {
                energy[j] += buf[lo..hi].iter().map(|c| c.norm_sqr()).sum::<f64>();
            }
        }
        energy.iter().map(|e| (e / blocks as f64).ln_1p()).collect()
    }
}

/// Each electrode's mean over the window, and the same as a pattern — each over 1 + their sum
/// — which the touch's pressure scales less.
fn electrode_pattern(window: &[DetectorSample]) -> Vec<f64> {
    let n = window.len().max(1) as f64;
    let electrodes = window.first().map_or(0, |s| s.electrodes.len());
    let means: Vec<f64> = (0..electrodes)
        .map(|e| {
            window
                .iter()
                .map(|s| s.electrodes.get(e).copied().unwrap_or(0.0))
                .sum::<f64>()
                / n
        })
        .collect();
    let total = 1.0 + means.iter().sum::<f64>();
    let pattern: Vec<f64> = means.iter().map(|v| v / total).collect();
    [means, pattern].concat()
}

/// An electrodes-only window's features ([`electrode_feature_count`]): the pattern of
/// [`electrode_pattern`], then — for a window of two or more samples — each electrode's change
/// from the first sample to the last and ln(1 + that change's norm).
fn electrode_features(window: &[DetectorSample]) -> Vec<f64> {
    let mut f = electrode_pattern(window);
    if let (Some(a), Some(b)) = (window.first(), window.last())
        && window.len() > 1
    {
        let change: Vec<f64> = b
            .electrodes
            .iter()
            .zip(&a.electrodes)
            .map(|(y, x)| y - x)
            .collect();
        let size = change.iter().map(|c| c * c).sum::<f64>().sqrt();
        f.extend(change);
        f.push(size.ln_1p());
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(pac: Vec<f64>, t: f64) -> DetectorSample {
        DetectorSample {
            pdc: 40.0,
            pac: 0.0,
            pac_vibration: 0.0,
            pac_samples: pac,
            tdc: t,
            tac: 2.0 * t,
            electrodes: vec![1.0, 3.0],
        }
    }

    /// A pure tone puts its energy in its own band: a sine at bin 12 (11 ≤ 12 < 16) across
    /// samples of 22 pac values, its first difference a sine of the same frequency.
    #[test]
    fn a_tone_lands_in_its_band() {
        let tone = |i: usize| (std::f64::consts::TAU * 12.0 * i as f64 / BLOCK as f64).sin();
        let window: Vec<DetectorSample> = (0..12)
            .map(|f| {
                sample(
                    (0..22).map(|s| 100.0 * tone(22 * f + s)).collect(),
                    f as f64,
                )
            })
            .collect();
        let x = Features::default().of(&window);
        assert_eq!(x.len(), feature_count(2));
        let bands = &x[..BANDS.len()];
        let top = (0..bands.len())
            .max_by(|&a, &b| bands[a].total_cmp(&bands[b]))
            .unwrap();
        assert_eq!(top, 6, "{bands:?}");
        assert!(
            bands[6] > bands[5] + 3.0 && bands[6] > bands[7] + 3.0,
            "{bands:?}"
        );
        // tdc 0..11 (mean 5.5, change 11), tac twice that, pdc 40; the sine's standard
        // deviation 100/√2 (264 samples, not whole periods: within a percent); electrodes 1
        // and 3, as a pattern 1/5 and 3/5.
        assert_eq!(
            &x[BANDS.len()..BANDS.len() + 5],
            &[5.5, 11.0, 11.0, 22.0, 40.0]
        );
        let amplitude = x[BANDS.len() + 5].exp_m1();
        assert!(
            (amplitude / (100.0 / 2f64.sqrt()) - 1.0).abs() < 0.01,
            "{amplitude}"
        );
        assert_eq!(&x[BANDS.len() + 6..], &[1.0, 3.0, 0.2, 0.6]);
    }

    /// Electrodes only, by hand: the means, the pattern, the change and its size.
    #[test]
    fn electrodes_only_features_are_the_pattern_and_its_change() {
        let at = |e: [f64; 2]| DetectorSample {
            electrodes: e.to_vec(),
            ..sample(Vec::new(), 0.0)
        };
        let window = [at([1.0, 5.0]), at([2.0, 4.0]), at([3.0, 3.0])];
        let x = Features::electrodes_only().of(&window);
        assert_eq!(x.len(), electrode_feature_count(2, 3));
        // Means 2 and 4 (sum 6, pattern over 7); change 3 − 1 = 2 and 3 − 5 = −2, norm √8.
        assert_eq!(&x[..6], &[2.0, 4.0, 2.0 / 7.0, 4.0 / 7.0, 2.0, -2.0]);
        assert!((x[6] - 8f64.sqrt().ln_1p()).abs() < 1e-12);
        // One sample: no change.
        let x = Features::electrodes_only().of(&window[..1]);
        assert_eq!(x, vec![1.0, 5.0, 1.0 / 7.0, 5.0 / 7.0]);
        assert_eq!(x.len(), electrode_feature_count(2, 1));
    }
}
