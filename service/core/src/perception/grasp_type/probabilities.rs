//! Eq 4.3: the object's grasp-type probabilities from the maps over its region, and s*.

use super::maps::{TypeMaps, scale_index};
use crate::grasp_type::GraspType;

/// Eq 4.3: P(s|O), the mean of map s over the region O, for each type in [`GraspType::ALL`]
/// order. `roi` is a `frame_w × frame_h` row-major mask (the frame the maps come from); each
/// ROI pixel counts with the map pixel covering it ([`TypeMaps::map_pixel`]), so smaller maps
/// weigh their pixels by the ROI's share. All 0 for an empty ROI.
pub fn type_probabilities(
    maps: &TypeMaps,
    roi: &[bool],
    frame_w: usize,
    frame_h: usize,
) -> [f64; 6] {
    assert_eq!(roi.len(), frame_w * frame_h, "ROI mask size");
    let cols: Vec<usize> = (0..frame_w)
        .map(|u| scale_index(u, frame_w, maps.width))
        .collect();
    let n = maps.width * maps.height;
    let mut sums = [0.0f64; 6];
    let mut count = 0usize;
    for v in 0..frame_h {
        let row = scale_index(v, frame_h, maps.height) * maps.width;
        for (u, _) in roi[v * frame_w..(v + 1) * frame_w]
            .iter()
            .enumerate()
            .filter(|(_, in_roi)| **in_roi)
        {
            let j = row + cols[u];
            for (s, sum) in sums.iter_mut().enumerate() {
                *sum += maps.probs[s * n + j] as f64;
            }
            count += 1;
        }
    }
    if count > 0 {
        sums.iter_mut().for_each(|s| *s /= count as f64);
    }
    sums
}

/// s* = argmax of P(s|O) over the types the hand can realise (method.md §4); ties go to the
/// lower index, NaN never wins. `None` when `realisable` is empty.
pub fn choose_type(p: &[f64; 6], realisable: &[GraspType]) -> Option<GraspType> {
    let mut best: Option<(GraspType, f64)> = None;
    for s in GraspType::ALL
        .into_iter()
        .filter(|s| realisable.contains(s))
    {
        let q = p[s.index()];
        match best {
            Some((_, b)) if !(q > b || (b.is_nan() && !q.is_nan())) => {}
            _ => best = Some((s, q)),
        }
    }
    best.map(|(s, _)| s)
}
