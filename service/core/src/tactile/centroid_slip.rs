//! Slip seen as the contact moving on the skin (issue 16, part 5): an object that turns about
//! the pinch axis or rolls out of the fingers makes no vibration for pac to hear (the skin rolls
//! with it instead of sliding under it), but the pressed spot moves across the electrodes. The
//! contact centroid is the electrodes' positions (mm, the layout's) weighted by their tared
//! pressure; its speed over the last [`SPAN`] frames above a session's threshold counts as slip.
//! Not in the dissertation (its slip comes from the detector alone, Eq 6.9); off unless the
//! session sets `centroid_slip_mm_s`.

use super::layout::SensorLayout;
use std::collections::VecDeque;

/// The pressed spot must stand this many times the electrodes' baseline noise above it before
/// its centroid is tracked: on the real BioTac SP recordings (baseline noise about 9 counts) a
/// spot barely above the noise wanders fast enough to read as slip on a steady touch.
pub const SPOT_SNR: f64 = 10.0;

/// Frames the centroid's speed is measured over (50 ms at a BioTac's 100 Hz: long enough that a
/// count of noise on a lightly pressed pad does not read as motion, short enough to catch an
/// object before it has rolled out).
pub const SPAN: usize = 5;

/// The pressure-weighted centre of the tared electrodes, mm; None when nothing presses, or
/// when the most pressed electrode stands less than [`SPOT_SNR`] times `noise` (the baseline's
/// electrode noise, when known) above its baseline.
pub fn contact_centroid(
    layout: &SensorLayout,
    tared_electrodes: &[f64],
    noise: Option<f64>,
) -> Option<[f64; 2]> {
    let peak = tared_electrodes.iter().copied().fold(0.0, f64::max);
    if peak < SPOT_SNR * noise.unwrap_or(0.0) {
        return None;
    }
    let (mut w, mut x, mut y) = (0.0, 0.0, 0.0);
    for (p, &e) in layout.electrodes.iter().zip(tared_electrodes) {
        let e = e.max(0.0);
        w += e;
        x += e * p[0];
        y += e * p[1];
    }
    (w > 1e-9).then(|| [x / w, y / w])
}

/// The centroid's recent positions while in contact; emptied when contact is lost.
#[derive(Debug, Clone, Default)]
pub struct CentroidTracker {
    recent: VecDeque<(f64, [f64; 2])>,
}

impl CentroidTracker {
    /// Records the frame at `timestamp` (s): its centroid while in contact, None out of contact
    /// (which forgets the track). Returns the centroid's speed over the last [`SPAN`] frames,
    /// mm/s, once that many frames in contact are known.
    pub fn push(&mut self, timestamp: f64, centroid: Option<[f64; 2]>) -> Option<f64> {
        let Some(c) = centroid else {
            self.recent.clear();
            return None;
        };
        self.recent.push_back((timestamp, c));
        if self.recent.len() > SPAN + 1 {
            self.recent.pop_front();
        }
        if self.recent.len() <= SPAN {
            return None;
        }
        let (t0, c0) = self.recent.front()?;
        let dt = timestamp - t0;
        (dt > 0.0).then(|| ((c[0] - c0[0]).powi(2) + (c[1] - c0[1]).powi(2)).sqrt() / dt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tactile::LayoutSpec;

    /// A session of one finger on `layout` (5 baseline frames, falling electrodes, windows of
    /// 8 readings every reading) with the session's `centroid_slip_mm_s`.
    fn session(
        layout: &SensorLayout,
        electrodes_only: bool,
        centroid_slip_mm_s: Option<f64>,
    ) -> crate::tactile::Stabilizer {
        use crate::tactile::{Baseline, ElectrodePolarity, FingerConfig, StabilizerConfig};
        let mut c = StabilizerConfig::for_fingers(vec![FingerConfig {
            electrodes_only,
            name: "ff".into(),
            layout: layout.clone(),
            tare: crate::tactile::TareConfig {
                baseline: Baseline::FirstFrames(5),
                electrode_polarity: ElectrodePolarity::Falling,
            },
        }]);
        c.window_length = 8;
        c.stride = 1;
        c.centroid_slip_mm_s = centroid_slip_mm_s;
        crate::tactile::Stabilizer::new(c).unwrap()
    }

    fn pad() -> SensorLayout {
        SensorLayout::from_spec(LayoutSpec {
            name: "pad".into(),
            description: String::new(),
            electrodes: vec![[0.0, 0.0], [4.0, 0.0], [0.0, 2.0], [4.0, 2.0]],
        })
        .unwrap()
    }

    /// Weighted by pressure; electrodes pulled below their baseline weigh nothing.
    #[test]
    fn the_centroid_is_the_pressure_weighted_mean_of_the_electrodes() {
        let c = contact_centroid(&pad(), &[3.0, 1.0, 0.0, -5.0], None).unwrap();
        assert_eq!(c, [1.0, 0.0]); // (3·0 + 1·4) / 4
        let c = contact_centroid(&pad(), &[1.0, 1.0, 1.0, 1.0], None).unwrap();
        assert_eq!(c, [2.0, 1.0]);
        assert_eq!(contact_centroid(&pad(), &[0.0, -1.0, 0.0, 0.0], None), None);
        // A spot under ten times the baseline's noise is not tracked.
        assert_eq!(
            contact_centroid(&pad(), &[3.0, 1.0, 0.0, 0.0], Some(0.5)),
            None
        );
        assert!(contact_centroid(&pad(), &[3.0, 1.0, 0.0, 0.0], Some(0.2)).is_some());
    }

    /// A spot moving 0.5 mm a frame at 100 Hz moves 50 mm/s, reported from the sixth frame in
    /// contact on; losing contact forgets the track.
    #[test]
    fn the_speed_is_measured_over_the_span_and_restarts_after_contact_is_lost() {
        let mut t = CentroidTracker::default();
        for k in 0..SPAN {
            assert_eq!(t.push(k as f64 * 0.01, Some([0.5 * k as f64, 1.0])), None);
        }
        for k in SPAN..SPAN + 4 {
            let v = t
                .push(k as f64 * 0.01, Some([0.5 * k as f64, 1.0]))
                .unwrap();
            assert!((v - 50.0).abs() < 1e-9, "{v}");
        }
        assert_eq!(t.push(0.1, None), None);
        assert_eq!(t.push(0.11, Some([9.0, 9.0])), None);
    }

    /// A session end to end: a classic BioTac pressed by a spot that rolls 0.6 mm a frame along
    /// the finger (60 mm/s at 100 Hz, from its tip 9 mm towards its base) with no pac vibration. The detector alone calls it
    /// contact; with `centroid_slip_mm_s` = 20 it slips and f_d rises by δf_s, while the same
    /// spot held still stays contact.
    #[test]
    fn a_rolling_contact_slips_only_with_the_option_and_a_still_one_never() {
        use crate::tactile::{ContactEvent, FingerReading, Frame};
        let layout = SensorLayout::biotac();
        let run = |option: Option<f64>, speed_mm_per_frame: f64| {
            let mut s = session(&layout, false, option);
            let law = s.config().law;
            let (x0, y0) = (4.0, 0.0);
            let mut last = None;
            for i in 0..20 {
                let pressed = i >= 5;
                let cx = x0 - speed_mm_per_frame * (i as f64 - 5.0).max(0.0);
                let electrodes = layout
                    .electrodes
                    .iter()
                    .map(|p| {
                        let d2 = (p[0] - cx).powi(2) + (p[1] - y0).powi(2);
                        3000.0
                            - if pressed {
                                200.0 * (-d2 / 32.0).exp()
                            } else {
                                0.0
                            }
                    })
                    .collect();
                let r = FingerReading {
                    pdc: 2000.0 + if pressed { 80.0 } else { 0.0 },
                    pac: vec![2000.0; 22],
                    tdc: 2500.0,
                    tac: 2000.0,
                    electrodes,
                };
                last = Some(
                    s.step(&Frame {
                        timestamp: 0.01 * i as f64,
                        fingers: vec![r],
                    })
                    .unwrap()
                    .fingers
                    .remove(0),
                );
            }
            (last.unwrap(), law)
        };
        let (plain, law) = run(None, 0.6);
        assert_eq!(plain.event, ContactEvent::Contact);
        assert_eq!(plain.desired_force, law.f0);
        let (rolling, _) = run(Some(20.0), 0.6);
        assert_eq!(rolling.event, ContactEvent::Slip);
        assert_eq!(rolling.desired_force, law.f0 + law.delta_slip);
        let p = rolling.event_probabilities;
        assert_eq!(p[1], 0.0);
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-9);
        let (still, _) = run(Some(20.0), 0.0);
        assert_eq!(still.event, ContactEvent::Contact);
    }

    /// An electrodes-only finger (a BioTac SP read through its 24 electrodes): frames without
    /// pac, their pdc/tdc/tac not read (huge values change nothing). The press is contact from
    /// the electrodes alone; the spot rolling 0.6 mm a frame slips at the default 20 mm/s with
    /// no session option. The same empty pac on an ordinary finger is refused naming the field.
    #[test]
    fn an_electrodes_only_finger_touches_and_slips_from_its_electrodes() {
        use crate::tactile::{ContactEvent, FingerReading, Frame};
        let layout = SensorLayout::biotac_sp();
        let reading = |i: usize, speed: f64, pdc: f64| {
            let cx = -4.0 - speed * (i as f64 - 5.0).max(0.0);
            FingerReading {
                pdc,
                pac: Vec::new(),
                tdc: pdc,
                tac: pdc,
                electrodes: layout
                    .electrodes
                    .iter()
                    .map(|p| {
                        let d2 = (p[0] - cx).powi(2) + p[1].powi(2);
                        3300.0
                            - if i >= 5 {
                                200.0 * (-d2 / 32.0).exp()
                            } else {
                                0.0
                            }
                    })
                    .collect(),
            }
        };
        let run = |speed: f64| {
            let mut s = session(&layout, true, None);
            let mut last = None;
            for i in 0..20 {
                let frame = Frame {
                    timestamp: 0.01 * i as f64,
                    fingers: vec![reading(i, speed, if i % 2 == 0 { 1e6 } else { -1e6 })],
                };
                last = Some(s.step(&frame).unwrap().fingers.remove(0));
            }
            last.unwrap()
        };
        let still = run(0.0);
        assert_eq!(still.event, ContactEvent::Contact);
        assert!(still.force > 0.0);
        assert_eq!(run(0.6).event, ContactEvent::Slip);
        let mut ordinary = session(&layout, false, None);
        let e = ordinary
            .step(&Frame {
                timestamp: 0.0,
                fingers: vec![reading(0, 0.0, 0.0)],
            })
            .unwrap_err();
        assert_eq!(e.field, "frame.fingers[0].pac");
        assert!(e.message.contains("electrodes_only"), "{e}");
    }
}
