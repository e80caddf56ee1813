//! Electrodes-only sensors on real data (issue 16 part 3): the BioTac SP direction-of-slip
//! recordings (../shared/testdata/tactile/biotac_sp/dos_basic, yayaneath/BioTacSP-DoS; no
//! licence: measurement only) carry only the 24 electrodes. Each sequence runs through a session
//! whose finger is `electrodes_only` (layout `biotac_sp`, 50 baseline frames, the model-free
//! detector, slip from the contact centroid's motion at the default 20 mm/s); the recordings have
//! no time stamps, 100 Hz is assumed.
//!
//! What it shows: the touch sequences (`t`, held still) report slip in under 2 % of their
//! frames — the centroid is tracked only for a spot ten times the baseline's noise, without
//! which a steady touch read as slip in 38 % of its frames. The slide sequences (n, s, e, w and
//! the two turns) report slip little more often: these are slow slides with the spot staying
//! put on the skin, which is not what the centroid is for (rolling, turning out of a pinch);
//! telling them from a touch needs a calibration (docs/tactile-calibration.md).
//!
//! `cargo test -p graspd-core --test tactile_electrodes_only -- --nocapture` prints the table.

use graspd_core::tactile::{
    Baseline, ContactEvent, ElectrodePolarity, FingerConfig, FingerReading, Frame, SensorLayout,
    Stabilizer, StabilizerConfig, TareConfig,
};

/// (label, frames, frames in contact, frames with slip) of every sequence.
fn replay(dir: &std::path::Path) -> Vec<(String, usize, usize, usize)> {
    let mut out = Vec::new();
    let mut labels: Vec<_> = std::fs::read_dir(dir).unwrap().flatten().collect();
    labels.sort_by_key(|e| e.file_name());
    for label in labels {
        let mut files: Vec<_> = std::fs::read_dir(label.path()).unwrap().flatten().collect();
        files.sort_by_key(|e| e.file_name());
        for file in files {
            let text = std::fs::read_to_string(file.path()).unwrap();
            let config = StabilizerConfig::for_fingers(vec![FingerConfig {
                name: "ff".into(),
                layout: SensorLayout::biotac_sp(),
                tare: TareConfig {
                    baseline: Baseline::FirstFrames(50),
                    electrode_polarity: ElectrodePolarity::Falling,
                },
                electrodes_only: true,
            }]);
            let mut s = Stabilizer::new(config).unwrap();
            let (mut frames, mut touching, mut slipping) = (0, 0, 0);
            for (k, line) in text.lines().skip(1).enumerate() {
                let electrodes: Vec<f64> = line
                    .split(',')
                    .map(|v| v.trim().parse().expect("a number"))
                    .collect();
                let r = s
                    .step(&Frame {
                        timestamp: 0.01 * k as f64,
                        fingers: vec![FingerReading {
                            electrodes,
                            ..FingerReading::default()
                        }],
                    })
                    .unwrap()
                    .fingers
                    .remove(0);
                if !r.tared {
                    continue;
                }
                frames += 1;
                touching += usize::from(r.event != ContactEvent::NonContact);
                slipping += usize::from(r.event == ContactEvent::Slip);
            }
            out.push((
                label.file_name().to_string_lossy().into_owned(),
                frames,
                touching,
                slipping,
            ));
        }
    }
    out
}

#[test]
fn a_steady_touch_on_a_real_biotac_sp_does_not_read_as_slip() {
    let dir = graspd_testkit::testdata_dir().join("tactile/biotac_sp/dos_basic");
    if !dir.is_dir() {
        eprintln!("skipped: no BioTac SP recordings at {}", dir.display());
        return;
    }
    let runs = replay(&dir);
    assert_eq!(runs.len(), 111, "the Basic set has 111 sequences");
    eprintln!("| label | sequences | frames in contact | frames with slip |\n|---|---:|---:|---:|");
    let mut labels: Vec<&str> = runs.iter().map(|r| r.0.as_str()).collect();
    labels.dedup();
    let share = |pick: &dyn Fn(&str) -> bool, k: usize| {
        let (mut num, mut den) = (0, 0);
        for r in runs.iter().filter(|r| pick(&r.0)) {
            num += if k == 2 { r.2 } else { r.3 };
            den += r.1;
        }
        num as f64 / den.max(1) as f64
    };
    for l in &labels {
        eprintln!(
            "| {l} | {} | {:.1} % | {:.1} % |",
            runs.iter().filter(|r| r.0 == *l).count(),
            100.0 * share(&|x| x == *l, 2),
            100.0 * share(&|x| x == *l, 3)
        );
    }
    let touch_slip = share(&|x| x == "t", 3);
    assert!(
        touch_slip < 0.02,
        "a still touch read as slip in {:.1} % of its frames",
        100.0 * touch_slip
    );
}
