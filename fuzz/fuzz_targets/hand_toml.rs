//! Hand descriptions (the TOML of `service/hands/`, the inline hand of `graspctl --hand-file`):
//! parse and validate, then use the planner's derived figures of a valid hand.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(hand) = graspd_core::hand::parse_hand_toml(&text) {
        if hand.validate().is_ok() {
            let _ = hand.realisable_types();
            let _ = hand.finger_span();
            let _ = hand.max_finger_spread();
            for m in 2..6 {
                let _ = hand.a_max(m);
            }
        }
    }
});
