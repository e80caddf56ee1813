//! The hand features a calibration classifies (issue 16), per window t_seq of a session's
//! tared samples: the vibration spectrum of the dynamic pressure pac (texture: a slide over a
//! material excites the skin at the frequencies its surface sets), the thermal channels (tdc,
//! tac and their change: metal draws heat fastest, foam slowest), the static pressure pdc and
//! the electrode pattern (how the skin deforms). On the real BioTac slides (split by recording,
//! `tests/tactile_calibration.rs`) the spectrum is the strongest single group; the electrodes
//! come next; every group adds.

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

/// Computes [`Features::of`] windows; holds the FFT plan (build once per detector).
#[derive(Clone)]
pub struct Features {
    fft: Arc<dyn Fft<f64>>,
    hann: Vec<f64>,
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
        }
    }
}

impl Features {
    /// The features of one window (oldest sample first, every one with the same electrode
    /// count): ln(1 + mean energy) in each half-octave band of the first-differenced pac signal
    /// (every sample's pac samples in one sequence; the difference keeps the AC-coupled
    /// channel's drift out), mean tdc, mean tac, their change from the first sample to the
    /// last, mean pdc, ln(1 + the pac samples' standard deviation); each electrode's mean, and
    /// the same as a pattern — each over 1 + their sum — which the touch's pressure scales less.
    pub fn of(&self, window: &[DetectorSample]) -> Vec<f64> {
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
        let electrodes = window.first().map_or(0, |s| s.electrodes.len());
        let means: Vec<f64> = (0..electrodes)
            .map(|e| mean(&|s| s.electrodes.get(e).copied().unwrap_or(0.0)))
            .collect();
        let total = 1.0 + means.iter().sum::<f64>();
        f.extend(&means);
        f.extend(means.iter().map(|v| v / total));
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
}
