//! The six sigmoid probability maps of one frame (Eq 4.1–4.2).

use crate::grasp_type::GraspType;

/// Number of grasp types: the maps of a frame, the model's output channels.
pub const NUM_TYPES: usize = GraspType::ALL.len();

/// The six sigmoid probability maps of one frame (Eq 4.1–4.2).
#[derive(Debug, Clone, PartialEq)]
pub struct TypeMaps {
    /// Size of the maps (the model's output; may be smaller than the frame).
    pub width: usize,
    pub height: usize,
    /// Six planes in [`GraspType::ALL`] order (type-major), each row-major `width × height`.
    pub probs: Vec<f32>,
}

impl TypeMaps {
    /// The map of type `s`, row-major.
    pub fn plane(&self, s: GraspType) -> &[f32] {
        let n = self.width * self.height;
        &self.probs[s.index() * n..(s.index() + 1) * n]
    }

    /// P(s) at map pixel (u_map, v_map).
    pub fn prob(&self, s: GraspType, u_map: usize, v_map: usize) -> f32 {
        self.plane(s)[v_map * self.width + u_map]
    }

    /// The map pixel covering frame pixel (u, v) of the `frame_w × frame_h` frame the maps were
    /// inferred from (pixels outside it are clamped to the border). Map pixels are spread evenly
    /// over the frame, a map half the frame's size giving one map pixel per 2 × 2 frame pixels,
    /// which is what both resizing and strided convolutions do.
    pub fn map_pixel(&self, u: usize, v: usize, frame_w: usize, frame_h: usize) -> (usize, usize) {
        (
            scale_index(u, frame_w, self.width),
            scale_index(v, frame_h, self.height),
        )
    }

    /// The maps reduced (area average) so that neither side exceeds `max_side` (at least 1),
    /// keeping the aspect ratio; unchanged when they already fit. For responses that return the
    /// maps: area averaging keeps each map's mean, so Eq 4.3 over the smaller maps stays close.
    pub fn downsample(&self, max_side: usize) -> TypeMaps {
        let max_side = max_side.max(1);
        let long = self.width.max(self.height);
        if long <= max_side {
            return self.clone();
        }
        let scale = max_side as f64 / long as f64;
        let nw = ((self.width as f64 * scale).round() as usize).clamp(1, max_side);
        let nh = ((self.height as f64 * scale).round() as usize).clamp(1, max_side);
        let (xw, yw) = (area_weights(self.width, nw), area_weights(self.height, nh));
        let mut probs = Vec::with_capacity(NUM_TYPES * nw * nh);
        let mut rows = vec![0.0f32; nw * self.height];
        for s in GraspType::ALL {
            let src = self.plane(s);
            for (y, row) in rows.chunks_mut(nw).enumerate() {
                let src_row = &src[y * self.width..(y + 1) * self.width];
                for (o, taps) in row.iter_mut().zip(&xw) {
                    *o = taps.iter().map(|&(i, w)| w * src_row[i]).sum();
                }
            }
            for taps in &yw {
                for x in 0..nw {
                    probs.push(taps.iter().map(|&(j, w)| w * rows[j * nw + x]).sum());
                }
            }
        }
        TypeMaps {
            width: nw,
            height: nh,
            probs,
        }
    }
}

/// Index of the destination cell (of `dst` over the same extent) covering source cell `i` of
/// `src`: centre-to-cell, so equal sizes give the identity.
pub(super) fn scale_index(i: usize, src: usize, dst: usize) -> usize {
    (((i as f64 + 0.5) * dst as f64 / src.max(1) as f64) as usize).min(dst - 1)
}

/// Area-average taps from `src` cells to `dst` (≤ `src`) cells: (source index, weight) each,
/// the weights of one destination cell summing to 1.
pub(super) fn area_weights(src: usize, dst: usize) -> Vec<Vec<(usize, f32)>> {
    let r = src as f64 / dst as f64;
    (0..dst)
        .map(|o| {
            let (a, b) = (o as f64 * r, (o + 1) as f64 * r);
            (a.floor() as usize..(b.ceil() as usize).min(src))
                .filter_map(|i| {
                    let overlap = b.min(i as f64 + 1.0) - a.max(i as f64);
                    (overlap > 1e-12).then_some((i, (overlap / r) as f32))
                })
                .collect()
        })
        .collect()
}
