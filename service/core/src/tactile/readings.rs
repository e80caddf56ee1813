//! What a session reads (`FingerReading`, `Frame`) and how one finger's readings become the
//! detector's samples (`SampleSource`: taring, the pac vibration), one home for a stabilizer
//! session and for fitting a calibration on recordings.

use super::detector::{DetectorSample, pac_vibration};
use super::taring::{Tare, TareConfig, TaredReading};
use serde::{Deserialize, Serialize};

/// One finger's reading in a frame (raw sensor units). JSON: `{"pdc": …, "pac": [...], "tdc": …,
/// "tac": …, "electrodes": [...]}`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FingerReading {
    pub pdc: f64,
    /// One value, or the 22 samples a BioTac driver delivers per frame.
    pub pac: Vec<f64>,
    pub tdc: f64,
    pub tac: f64,
    pub electrodes: Vec<f64>,
}

/// One frame: a timestamp (s) and one reading per session finger, in session order.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Frame {
    pub timestamp: f64,
    pub fingers: Vec<FingerReading>,
}

/// A finger's readings turned into the detector's samples exactly as a session does it (one
/// home for a session and for fitting a calibration on recordings): tared, with the pac
/// vibration of the module doc, and none while the baseline is still being collected.
#[derive(Debug, Clone)]
pub struct SampleSource {
    tare: Tare,
    prev_single_pac: Option<f64>,
    /// Only the electrodes are read (`FingerConfig::electrodes_only`): pdc, tdc, tac and pac
    /// count as 0 and no pac.
    electrodes_only: bool,
}

impl SampleSource {
    pub fn new(tare: TareConfig, electrodes: usize) -> Self {
        Self {
            tare: Tare::new(tare, electrodes),
            prev_single_pac: None,
            electrodes_only: false,
        }
    }

    /// The same source reading only the electrodes of each reading.
    pub fn electrodes_only(self, electrodes_only: bool) -> Self {
        Self {
            electrodes_only,
            ..self
        }
    }

    /// Whether the baseline is complete.
    pub fn is_ready(&self) -> bool {
        self.tare.is_ready()
    }

    /// The electrodes' noise over the baseline (`Tare::electrode_noise`).
    pub fn electrode_noise(&self) -> Option<f64> {
        self.tare.electrode_noise()
    }

    /// The reading tared, and its detector sample when the baseline was complete before it.
    pub fn next(&mut self, r: &FingerReading) -> (TaredReading, Option<DetectorSample>) {
        let was_ready = self.tare.is_ready();
        let (pdc, tdc, tac, pac) = if self.electrodes_only {
            (0.0, 0.0, 0.0, &[][..])
        } else {
            (r.pdc, r.tdc, r.tac, &r.pac[..])
        };
        let tared = self.tare.apply(pdc, tdc, tac, &r.electrodes);
        let vibration = pac_vibration(pac, self.prev_single_pac);
        self.prev_single_pac = (pac.len() == 1).then(|| pac[0]);
        let sample = was_ready.then(|| DetectorSample {
            pdc: tared.pdc,
            // No pac channel (an electrodes-only sensor): level 0.
            pac: pac.iter().sum::<f64>() / pac.len().max(1) as f64,
            pac_vibration: vibration,
            pac_samples: pac.to_vec(),
            tdc: tared.tdc,
            tac: tared.tac,
            electrodes: tared.electrodes.clone(),
        });
        (tared, sample)
    }
}
