//! Frames of several sessions stepped together, so that a model shared by the sessions runs
//! once for all the windows due at that moment (issue 16 part 4): the LSTM detector with a
//! dynamic batch axis costs about the same for one window as for dozens, and at 100 Hz the
//! sessions' frames arrive together. Each session's result is what [`Stabilizer::step`] would
//! give it (up to the model's floating-point differences between batch sizes, ~1e-6 in the
//! probabilities).

use super::detector::DetectorSample;
use super::stabilizer::{Frame, FrameResult, Sensed, Stabilizer};
use crate::error::FieldError;
use std::collections::BTreeMap;

/// A session's frame up to its detectors: the frame's timestamp and time step, and each
/// finger's taring and window.
type Begun = ((f64, f64), Vec<Sensed>);

impl Stabilizer {
    /// One frame for each of several sessions: [`Stabilizer::step`] for each, the detections
    /// of the detectors that share a model ([`super::detector::EventDetector::batch_key`]) in
    /// one run per model. Results in the order of `work`; a frame that does not fit its session
    /// fails alone (naming `frame.…`) and changes nothing of that session.
    pub fn step_many(
        work: &mut [(&mut Stabilizer, &Frame)],
    ) -> Vec<Result<FrameResult, FieldError>> {
        // Taring and the windows (Algorithm 5 up to the detectors).
        let begun: Vec<Result<Begun, FieldError>> = work
            .iter_mut()
            .map(|(s, frame)| {
                let at = s.begin(frame)?;
                let sensed = s
                    .fingers_mut()
                    .iter_mut()
                    .zip(&frame.fingers)
                    .map(|(f, r)| f.sense(r))
                    .collect();
                Ok((at, sensed))
            })
            .collect();
        // The fingers due for detection, by shared model; the others detect alone.
        let mut shared: BTreeMap<usize, Vec<(usize, usize)>> = BTreeMap::new();
        for (i, b) in begun.iter().enumerate() {
            let Ok((_, sensed)) = b else { continue };
            for (j, _) in sensed.iter().enumerate().filter(|(_, s)| s.due) {
                let finger = &mut work[i].0.fingers_mut()[j];
                match finger.detector().batch_key() {
                    Some(key) => shared.entry(key).or_default().push((i, j)),
                    None => finger.detect_alone(),
                }
            }
        }
        for members in shared.values() {
            let detections = {
                let windows: Vec<&[DetectorSample]> = members
                    .iter()
                    .map(|&(i, j)| work[i].0.fingers()[j].window_ref())
                    .collect();
                let (i, j) = members[0];
                work[i].0.fingers()[j].detector().detect_many(&windows)
            };
            match detections {
                Some(detections) => {
                    for (&(i, j), d) in members.iter().zip(detections) {
                        work[i].0.fingers_mut()[j].set_detection(d);
                    }
                }
                None => {
                    for &(i, j) in members {
                        work[i].0.fingers_mut()[j].detect_alone();
                    }
                }
            }
        }
        work.iter_mut()
            .zip(begun)
            .map(|((s, frame), b)| b.map(|(at, sensed)| s.finish(frame, at, sensed)))
            .collect()
    }
}

impl Stabilizer {
    /// Whether a finger's detector shares its model with other sessions' (its frames gain from
    /// [`Stabilizer::step_many`]).
    pub fn shares_a_model(&self) -> bool {
        self.fingers()
            .iter()
            .any(|f| f.detector().batch_key().is_some())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tactile::detector::{ContactEvent, Detection, EventDetector, ModelFreeDetector};
    use crate::tactile::layout::SensorLayout;
    use crate::tactile::stabilizer::{FingerConfig, FingerReading, StabilizerConfig};
    use crate::tactile::taring::TareConfig;
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// Shares a batch key but runs no batches: each finger must then detect alone.
    struct Keyed {
        inner: ModelFreeDetector,
        calls: Arc<AtomicUsize>,
    }

    impl EventDetector for Keyed {
        fn detect(&mut self, window: &[DetectorSample]) -> Detection {
            self.calls.fetch_add(1, Ordering::Relaxed);
            self.inner.detect(window)
        }

        fn batch_key(&self) -> Option<usize> {
            Some(7)
        }
    }

    fn session(detector: Box<dyn EventDetector>) -> Stabilizer {
        let finger = FingerConfig {
            electrodes_only: false,
            name: "th".into(),
            layout: SensorLayout::biotac(),
            tare: TareConfig::pretared(),
        };
        Stabilizer::with_detectors(StabilizerConfig::for_fingers(vec![finger]), vec![detector])
            .unwrap()
    }

    fn frame(t: usize) -> Frame {
        let press = if t > 20 { 40.0 } else { 0.0 };
        Frame {
            timestamp: t as f64 * 0.01,
            fingers: vec![FingerReading {
                pdc: press,
                pac: vec![0.0; 22],
                tdc: 0.0,
                tac: 0.0,
                electrodes: (0..19).map(|e| press * (e % 4) as f64).collect(),
            }],
        }
    }

    /// Sessions whose detectors share a key but cannot run a batch are stepped as
    /// `Stabilizer::step` steps them: one detection per due frame each, the same results.
    #[test]
    fn a_shared_key_without_batches_detects_each_window_alone() {
        let (many, one) = (Arc::new(AtomicUsize::new(0)), Arc::new(AtomicUsize::new(0)));
        let keyed = |calls: &Arc<AtomicUsize>| -> Box<dyn EventDetector> {
            Box::new(Keyed {
                inner: ModelFreeDetector::default(),
                calls: calls.clone(),
            })
        };
        let (mut a, mut b) = (session(keyed(&many)), session(keyed(&many)));
        let mut alone = session(keyed(&one));
        let mut contact = false;
        for t in 0..60 {
            let f = frame(t);
            let want = alone.step(&f).unwrap();
            let got = Stabilizer::step_many(&mut [(&mut a, &f), (&mut b, &f)]);
            for g in got {
                assert_eq!(g.unwrap(), want, "frame {t}");
            }
            contact |= want.fingers[0].event != ContactEvent::NonContact;
        }
        assert!(contact, "the press is seen");
        let once = one.load(Ordering::Relaxed);
        assert!(once >= 10, "{once} detections");
        assert_eq!(many.load(Ordering::Relaxed), 2 * once);
    }
}
