//! Baseline taring at session start (issue 5 point 2): the sensor's no-contact offsets are the
//! mean of the first N frames per channel and are subtracted from every later frame.
//!
//! # Sign convention
//! After taring every channel reads **"larger = more contact"**:
//! * `pdc` (fluid pressure) rises under load on every BioTac: tared = value − baseline.
//! * Electrodes: on a real BioTac the raw electrode reading (impedance, 12-bit counts in the
//!   thousands) **falls** when the skin is pressed onto the electrode ([`ElectrodePolarity::Falling`]:
//!   tared = baseline − value). Pre-processed data such as the dexrob BioTac_slide recordings are
//!   already baseline-subtracted and clipped at 0, so larger already means more contact
//!   ([`ElectrodePolarity::Rising`]: tared = value − baseline).
//! * `tdc`, `tac` are tared as value − baseline (no sign flip; the detector interprets them).
//! * `pac` is not tared here: the detector uses its variation (vibration), not its level.
//!
//! [`Baseline::None`] skips taring (baseline 0) for data that is already tared, like the
//! recordings above. While the first N frames are collected the baseline is the running mean of
//! the frames seen so far, and [`Tare::is_ready`] is false; the stabilizer treats those frames as
//! non-contact (the caller promises no contact at session start).

use serde::{Deserialize, Serialize};

/// Which way an electrode reading moves under pressure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ElectrodePolarity {
    /// Raw BioTac impedance counts: they fall under pressure.
    #[default]
    Falling,
    /// Pre-processed deviations: they rise under pressure.
    Rising,
}

impl ElectrodePolarity {
    pub fn sign(self) -> f64 {
        match self {
            Self::Falling => -1.0,
            Self::Rising => 1.0,
        }
    }
}

/// How the baseline is obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Baseline {
    /// Mean of the first N frames of the session.
    FirstFrames(usize),
    /// Data already tared: baseline 0.
    None,
}

/// Taring settings of one finger.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct TareConfig {
    pub baseline: Baseline,
    pub electrode_polarity: ElectrodePolarity,
}

impl Default for TareConfig {
    /// Raw BioTac readings: 50 frames (0.5 s at 100 Hz) of baseline, electrodes falling.
    fn default() -> Self {
        Self {
            baseline: Baseline::FirstFrames(50),
            electrode_polarity: ElectrodePolarity::Falling,
        }
    }
}

impl TareConfig {
    /// For recordings that are already baseline-subtracted (the dexrob BioTac_slide set).
    pub fn pretared() -> Self {
        Self {
            baseline: Baseline::None,
            electrode_polarity: ElectrodePolarity::Rising,
        }
    }
}

/// Tared values of one reading: larger = more contact (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct TaredReading {
    pub pdc: f64,
    pub tdc: f64,
    pub tac: f64,
    pub electrodes: Vec<f64>,
}

/// The running baseline of one finger. Channels: pdc, tdc, tac, electrodes…
#[derive(Debug, Clone)]
pub struct Tare {
    config: TareConfig,
    sum: Vec<f64>,
    /// Sum of squares of the electrodes over the baseline (their noise).
    sum_sq: Vec<f64>,
    count: usize,
}

impl Tare {
    pub fn new(config: TareConfig, electrodes: usize) -> Self {
        Self {
            config,
            sum: vec![0.0; 3 + electrodes],
            sum_sq: vec![0.0; electrodes],
            count: 0,
        }
    }

    /// True once the baseline is complete (always for [`Baseline::None`]).
    pub fn is_ready(&self) -> bool {
        match self.config.baseline {
            Baseline::FirstFrames(n) => self.count >= n,
            Baseline::None => true,
        }
    }

    /// The electrodes' noise over the baseline: the root mean square of their standard
    /// deviations, raw units; None without a baseline of two or more frames (pretared data).
    pub fn electrode_noise(&self) -> Option<f64> {
        let n = self.count as f64;
        if self.count < 2 || self.sum_sq.is_empty() {
            return None;
        }
        let var: f64 = self
            .sum_sq
            .iter()
            .zip(&self.sum[3..])
            .map(|(sq, s)| ((sq - s * s / n) / (n - 1.0)).max(0.0))
            .sum::<f64>()
            / self.sum_sq.len() as f64;
        Some(var.sqrt())
    }

    /// Feeds one raw reading (into the baseline while it is being collected) and returns it tared.
    pub fn apply(&mut self, pdc: f64, tdc: f64, tac: f64, electrodes: &[f64]) -> TaredReading {
        let raw = || {
            [pdc, tdc, tac]
                .into_iter()
                .chain(electrodes.iter().copied())
        };
        if !self.is_ready() {
            for (s, v) in self.sum.iter_mut().zip(raw()) {
                *s += v;
            }
            for (s, v) in self.sum_sq.iter_mut().zip(electrodes) {
                *s += v * v;
            }
            self.count += 1;
        }
        let base: Vec<f64> = if self.count == 0 {
            vec![0.0; self.sum.len()]
        } else {
            self.sum.iter().map(|s| s / self.count as f64).collect()
        };
        let sign = self.config.electrode_polarity.sign();
        TaredReading {
            pdc: pdc - base[0],
            tdc: tdc - base[1],
            tac: tac - base[2],
            electrodes: electrodes
                .iter()
                .zip(&base[3..])
                .map(|(v, b)| sign * (v - b))
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raw_biotac_baseline_is_subtracted_with_falling_electrodes() {
        let mut t = Tare::new(
            TareConfig {
                baseline: Baseline::FirstFrames(2),
                electrode_polarity: ElectrodePolarity::Falling,
            },
            2,
        );
        t.apply(2000.0, 2500.0, 2000.0, &[3000.0, 3100.0]);
        assert!(!t.is_ready());
        t.apply(2002.0, 2500.0, 2000.0, &[3002.0, 3100.0]);
        assert!(t.is_ready());
        // Pressed: pdc up 50, electrode 1 down 201 (impedance falls).
        let r = t.apply(2051.0, 2500.0, 2000.0, &[2800.0, 3100.0]);
        assert_eq!(r.pdc, 50.0);
        assert_eq!(r.electrodes, vec![201.0, 0.0]);
    }

    #[test]
    fn pretared_data_passes_through() {
        let mut t = Tare::new(TareConfig::pretared(), 1);
        assert!(t.is_ready());
        let r = t.apply(30.0, 1.0, 2.0, &[40.0]);
        assert_eq!(
            (r.pdc, r.tdc, r.tac, r.electrodes[0]),
            (30.0, 1.0, 2.0, 40.0)
        );
    }

    /// The baseline's electrode noise: electrode 0 alternates 3000 ± 2 (sample std 2.31 over
    /// four frames), electrode 1 is still; RMS over the two = 2.31/√2.
    #[test]
    fn the_baseline_measures_the_electrodes_noise() {
        let mut t = Tare::new(
            TareConfig {
                baseline: Baseline::FirstFrames(4),
                electrode_polarity: ElectrodePolarity::Falling,
            },
            2,
        );
        assert_eq!(t.electrode_noise(), None);
        for k in 0..4 {
            let e0 = if k % 2 == 0 { 3002.0 } else { 2998.0 };
            t.apply(0.0, 0.0, 0.0, &[e0, 3100.0]);
        }
        let sd0 = (16.0_f64 / 3.0).sqrt();
        let want = (sd0 * sd0 / 2.0).sqrt();
        assert!((t.electrode_noise().unwrap() - want).abs() < 1e-9);
        assert_eq!(Tare::new(TareConfig::pretared(), 2).electrode_noise(), None);
    }
}
