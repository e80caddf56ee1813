//! Grasp-type detection (method.md §4, dissertation ch. 4.2.2): a fully convolutional network
//! gives six pixel-wise probability maps, one per grasp type (Eq 4.1–4.2); the object's type
//! probabilities are the maps' means over its region (Eq 4.3); the attention point is the
//! strongest mean-shift mode of the chosen type's map inside the region (its 3-D point is found
//! on the target's points by [`super::information`]).
//!
//! The network runs in ONNX Runtime through `ort`, loaded at run time
//! ([`crate::onnx_runtime::init_onnx_runtime`]: `ORT_DYLIB_PATH` or an explicit path;
//! `scripts/fetch-onnxruntime.sh` fetches the library).
//!
//! # Model contract (docs/model-contract.md)
//!
//! - **Input**: exactly one, float32, shape `[1, C, H, W]` (the batch may be dynamic) with
//!   C = 3 (R, G, B) or C = 4 (R, G, B, depth). H and W are fixed in the model or dynamic
//!   (`-1`): a fixed size makes graspd resize the frame (bilinear) to H × W, a dynamic one
//!   feeds the frame at its own size.
//! - **Normalisation**: colour channels are `(x / 255 − mean) / std` with the ImageNet mean
//!   (0.485, 0.456, 0.406) and std (0.229, 0.224, 0.225) unless the model's metadata
//!   (`custom_metadata_map`) has `graspd.mean` / `graspd.std`, each three comma-separated
//!   numbers. Depth is in metres, 0 where the sensor gave no reading, never normalised.
//! - **Output**: exactly one, float32, `[1, 6, H', W']` of *logits* in [`GraspType::ALL`] order.
//!   graspd applies the sigmoid itself (Eq 4.1–4.2: six independent binary problems, a pixel may
//!   afford several types, so no softmax across types). H', W' may be smaller than the input
//!   (strided networks); map pixels are spread evenly over the frame.
//!
//! Load-time checks ([`GraspTypeModel::load`]) name what was found against what the contract
//! needs, so that a wrongly exported model fails at start, not at the first request.
//!
//! One file per part: [`model`] (the network and its contract), [`maps`] (Eq 4.1–4.2),
//! [`probabilities`] (Eq 4.3, s*), [`attention`] (p_att).

mod attention;
mod maps;
mod model;
mod probabilities;

pub use attention::*;
pub use maps::*;
pub use model::*;
pub use probabilities::*;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp_type::GraspType;
    use crate::onnx_runtime::fmt_dims;

    fn maps_with(width: usize, height: usize, f: impl Fn(usize, usize, usize) -> f32) -> TypeMaps {
        let mut probs = Vec::with_capacity(NUM_TYPES * width * height);
        for s in 0..NUM_TYPES {
            for v in 0..height {
                for u in 0..width {
                    probs.push(f(s, u, v));
                }
            }
        }
        TypeMaps {
            width,
            height,
            probs,
        }
    }

    #[test]
    fn resampling_taps() {
        // Same size: the identity.
        for (o, &(i0, _, a)) in bilinear_taps(5, 5).iter().enumerate() {
            assert_eq!((i0, a), (o, 0.0));
        }
        // Half size: the mean of each pair.
        assert_eq!(bilinear_taps(4, 2), vec![(0, 1, 0.5), (2, 3, 0.5)]);
        // Up-sampling clamps at the borders.
        assert_eq!(bilinear_taps(2, 4)[0], (0, 1, 0.0));
        assert_eq!(bilinear_taps(2, 4)[3], (1, 1, 0.0));
        for (src, dst) in [(10, 3), (7, 7), (640, 81)] {
            for taps in area_weights(src, dst) {
                let sum: f32 = taps.iter().map(|t| t.1).sum();
                assert!((sum - 1.0).abs() < 1e-5);
            }
        }
        assert_eq!(scale_index(5, 64, 32), 2);
        assert_eq!(scale_index(63, 64, 32), 31);
        assert_eq!(scale_index(7, 10, 10), 7);
    }

    #[test]
    fn shapes_are_formatted_with_their_symbols() {
        assert_eq!(fmt_dims(&[1, 5, 60, 80], &[]), "[1, 5, 60, 80]");
        let syms = ["N".to_string(), String::new(), "H".into(), String::new()];
        assert_eq!(fmt_dims(&[-1, 3, -1, -1], &syms), "[N, 3, H, ?]");
        assert_eq!(sigmoid(0.0), 0.5);
        assert_eq!(sigmoid(-200.0), 0.0);
        assert_eq!(sigmoid(200.0), 1.0);
    }

    #[test]
    fn eq_4_3_weighs_small_maps_by_roi_share() {
        // 2 × 1 maps over a 4 × 2 frame: the left map pixel covers frame columns 0–1.
        let maps = maps_with(2, 1, |s, u, _| if u == 0 { s as f32 / 10.0 } else { 1.0 });
        // Three ROI pixels on the left, one on the right.
        let roi = [true, true, false, false, true, false, true, false];
        let p = type_probabilities(&maps, &roi, 4, 2);
        for (s, p) in p.iter().enumerate() {
            let want = (3.0 * (s as f32 / 10.0) as f64 + 1.0) / 4.0;
            assert!((p - want).abs() < 1e-12, "{s}: {p} vs {want}");
        }
    }

    #[test]
    fn attention_finds_the_peak_of_a_gaussian_bump() {
        let (w, h) = (120, 90);
        let bump = |u: usize, v: usize, c: (f64, f64), a: f64, r: f64| {
            a * (-((u as f64 - c.0).powi(2) + (v as f64 - c.1).powi(2)) / (2.0 * r * r)).exp()
        };
        let maps = maps_with(w, h, |s, u, v| {
            if s == GraspType::Tripod.index() {
                (bump(u, v, (33.3, 60.7), 0.9, 6.0) + bump(u, v, (90.0, 20.0), 0.6, 10.0)) as f32
            } else {
                0.0
            }
        });
        let roi = vec![true; w * h];
        for bw in [3.0, 8.0, 15.0] {
            let (x, y) = attention_pixel(&maps, GraspType::Tripod, &roi, w, h, bw).unwrap();
            assert!(
                (x - 33.3).hypot(y - 60.7) < 1.0,
                "bandwidth {bw}: ({x}, {y})"
            );
        }
        // All-zero map in the ROI: no attention.
        assert_eq!(
            attention_pixel(&maps, GraspType::Pinch, &roi, w, h, 8.0),
            None
        );
    }
}
