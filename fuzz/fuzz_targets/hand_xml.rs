//! MJCF and URDF hand import (`RegisterHand`): the first byte picks the format; the document is
//! read against an empty model directory, so every mesh or include reference must fail cleanly.
#![no_main]
use graspd_core::hand::kinematics::KinematicHand;
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

fn empty_dir() -> &'static std::path::Path {
    static DIR: OnceLock<std::path::PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("graspd-fuzz-empty-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("temp dir");
        d
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    let text = String::from_utf8_lossy(rest);
    let hand = if selector % 2 == 0 {
        KinematicHand::from_mjcf_str(&text, empty_dir())
    } else {
        KinematicHand::from_urdf_str(&text, empty_dir())
    };
    if let Ok(hand) = hand {
        let _ = hand.describe();
    }
});
