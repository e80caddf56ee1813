//! The `_bio.csv` / `_cw.csv` / `_cv.csv` recordings of `POST /v1/tactile/analyze` and
//! `graspctl stabilize`: the input is split at 0x00 bytes into bio, cw and cv texts; a parsed
//! recording is then run through a stabilizer session.
#![no_main]
use graspd_core::tactile::layout::SensorLayout;
use graspd_core::tactile::stabilizer::FingerConfig;
use graspd_core::tactile::{Recording, StabilizerConfig, TareConfig, analyze};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let mut parts = text.split('\0');
    let bio = parts.next().unwrap_or("");
    let cw = parts.next();
    let cv = parts.next();
    let Ok(recording) = Recording::from_csv(bio, cw, cv) else {
        return;
    };
    let frames = recording.frames();
    for layout in [SensorLayout::biotac(), SensorLayout::biotac_sp()] {
        let config = StabilizerConfig::for_fingers(vec![FingerConfig {
            name: "f".into(),
            layout,
            tare: TareConfig::pretared(),
            electrodes_only: recording.electrodes_only,
        }]);
        let _ = analyze(config, &frames);
    }
});
