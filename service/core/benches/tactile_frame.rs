//! Per-frame latency of the tactile stabilizer's domain core (model-free detector, GMM force
//! estimation, PID), single thread: p50, p99 and frames/s for 1 and 3 classic-BioTac fingers on a
//! synthetic raw stream (baseline, press, slide with pac vibration).
//! `cargo bench -p graspd-core --bench tactile_frame`.

use graspd_core::tactile::layout::SensorLayout;
use graspd_core::tactile::stabilizer::{
    FingerConfig, FingerReading, Frame, Stabilizer, StabilizerConfig,
};
use graspd_core::tactile::taring::TareConfig;
use std::hint::black_box;
use std::time::Instant;

fn reading(i: usize) -> FingerReading {
    // 0–1 s rest, 1–3 s press, 3–5 s slide, repeating every 5 s at 100 Hz.
    let phase = i % 500;
    let press = if phase >= 100 { 80.0 } else { 0.0 };
    let mut electrodes = vec![3000.0 + (i % 7) as f64; 19];
    if phase >= 100 {
        for e in [16, 17, 1, 9] {
            electrodes[e] -= 150.0 + (i % 13) as f64;
        }
    }
    let amp = if phase >= 300 { 60.0 } else { 2.0 };
    FingerReading {
        pdc: 2000.0 + press + (i % 3) as f64,
        pac: (0..22)
            .map(|j| 2000.0 + if (i + j).is_multiple_of(2) { amp } else { -amp })
            .collect(),
        tdc: 2500.0,
        tac: 2000.0,
        electrodes,
    }
}

fn run(fingers: usize, frames: usize) {
    let config = StabilizerConfig::for_fingers(
        (0..fingers)
            .map(|f| FingerConfig {
                name: format!("f{f}"),
                layout: SensorLayout::biotac(),
                tare: TareConfig::default(),
            })
            .collect(),
    );
    let mut stab = Stabilizer::new(config).unwrap();
    let input: Vec<Frame> = (0..frames)
        .map(|i| Frame {
            timestamp: i as f64 * 0.01,
            fingers: (0..fingers).map(|_| reading(i)).collect(),
        })
        .collect();
    let mut lat = Vec::with_capacity(frames);
    let all = Instant::now();
    for f in &input {
        let t = Instant::now();
        black_box(stab.step(black_box(f)).unwrap());
        lat.push(t.elapsed().as_secs_f64() * 1e6);
    }
    let total = all.elapsed().as_secs_f64();
    lat.sort_by(f64::total_cmp);
    let q = |p: f64| lat[((p * (lat.len() - 1) as f64) as usize).min(lat.len() - 1)];
    println!(
        "{fingers} finger(s): p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs per frame; {:.0} frames/s on one core",
        q(0.5),
        q(0.99),
        lat[lat.len() - 1],
        frames as f64 / total
    );
}

fn main() {
    // `cargo bench` passes `--bench`; `cargo test --benches` runs a short smoke pass.
    let quick = !std::env::args().any(|a| a == "--bench");
    let frames = if quick { 2_000 } else { 50_000 };
    for fingers in [1, 3] {
        run(fingers, frames);
    }
}
