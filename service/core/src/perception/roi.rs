//! The region of interest (method.md §4, dissertation ch. 4.2.1): mean-shift clustering of the
//! salient pixels of the VOCUS2 map; the region with the highest mean saliency is the ROI, and
//! when depth segmentation has chosen an object, the ROI is that region intersected with the
//! object's pixels.
//!
//! Mean shift runs on a grid of cells (the map box-averaged by [`RegionParams::cell`] pixels) in
//! the joint space (u, v, saliency) with a flat kernel — spatial bandwidth
//! [`RegionParams::spatial_bandwidth`] cells, range bandwidth [`RegionParams::range_bandwidth`] —
//! as in Comaniciu and Meer's mean-shift segmentation. Only cells at or above
//! [`RegionParams::salient_fraction`] of the map's maximum take part: the rest is background.
//! Converged modes closer than half the bandwidths are one region.

use super::saliency::Plane32;

/// Parameters of the salient regions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RegionParams {
    /// Cell side, pixels (the mean shift runs on cells, not pixels, for speed).
    pub cell: usize,
    /// Cells whose mean saliency is below this fraction of the maximum cell are background.
    pub salient_fraction: f32,
    /// Flat-kernel radius in cells.
    pub spatial_bandwidth: f32,
    /// Flat-kernel radius in saliency units ([0, 1]).
    pub range_bandwidth: f32,
    /// Iterations per seed at most.
    pub max_iterations: usize,
    /// Regions of fewer cells are ignored when choosing the ROI (isolated highlights).
    pub min_cells: usize,
}

impl Default for RegionParams {
    /// 8-pixel cells (80 × 60 for VGA), cells ≥ 25 % of the peak, 10-cell / 0.5 bandwidths,
    /// regions of ≥ 4 cells. Chosen on the YCB renders of the Table 5.2 objects: narrower
    /// bandwidths split one object into several regions (the ROI then covered 24–86 % of a can),
    /// these cover ≥ 79 % of every object (the tall chips can least) with no table pixel.
    fn default() -> Self {
        Self {
            cell: 8,
            salient_fraction: 0.25,
            spatial_bandwidth: 10.0,
            range_bandwidth: 0.5,
            max_iterations: 30,
            min_cells: 4,
        }
    }
}

/// The salient regions of a map.
#[derive(Debug, Clone, PartialEq)]
pub struct SalientRegions {
    /// Grid size in cells.
    pub cols: usize,
    pub rows: usize,
    pub cell: usize,
    /// Region per cell (row-major), `None` for background.
    pub labels: Vec<Option<u32>>,
    /// Mean saliency of each region's cells.
    pub mean_saliency: Vec<f32>,
    /// Cells per region.
    pub cells: Vec<usize>,
}

impl SalientRegions {
    /// The region of pixel (u, v), if any.
    pub fn label_at(&self, u: usize, v: usize) -> Option<u32> {
        let (c, r) = (u / self.cell, v / self.cell);
        if c >= self.cols || r >= self.rows {
            return None;
        }
        self.labels[r * self.cols + c]
    }
}

/// Mean-shift regions of the salient cells of `map` (see the module docs). Deterministic.
pub fn salient_regions(map: &Plane32, params: &RegionParams) -> SalientRegions {
    salient_regions_near(map, params, None)
}

/// [`salient_regions`] seeded only from the salient cells that overlap `window` ([u_min,
/// v_min, u_max, v_max) pixels): the kernel still reads every salient cell, so each seed there
/// converges as on the whole map, and the cells outside stay unlabelled (a region's mean
/// saliency and size are then those of its cells in the window). With the target known, the
/// ROI only needs the regions over it: a frame with many objects then costs what one object
/// costs. `None`: every salient cell.
pub fn salient_regions_near(
    map: &Plane32,
    params: &RegionParams,
    window: Option<[u32; 4]>,
) -> SalientRegions {
    let cell = params.cell.max(1);
    let (cols, rows) = (map.width.div_ceil(cell), map.height.div_ceil(cell));
    let mut grid = vec![0f32; cols * rows];
    for (r, row) in grid.chunks_mut(cols).enumerate() {
        for (c, g) in row.iter_mut().enumerate() {
            let (u0, v0) = (c * cell, r * cell);
            let (u1, v1) = ((u0 + cell).min(map.width), (v0 + cell).min(map.height));
            let mut sum = 0.0;
            for v in v0..v1 {
                sum += map.data[v * map.width + u0..v * map.width + u1]
                    .iter()
                    .sum::<f32>();
            }
            *g = sum / ((u1 - u0) * (v1 - v0)) as f32;
        }
    }
    let peak = grid.iter().copied().fold(0.0, f32::max);
    let threshold = params.salient_fraction * peak;
    // Salient cells as points (u, v, s/h_r · h_s): one Euclidean radius h_s covers both bandwidths.
    let scale = params.spatial_bandwidth / params.range_bandwidth.max(1e-6);
    let salient: Vec<usize> = (0..grid.len())
        .filter(|&i| peak > 0.0 && grid[i] >= threshold)
        .collect();
    let feature =
        |i: usize| -> [f32; 3] { [(i % cols) as f32, (i / cols) as f32, grid[i] * scale] };
    // The seeds: the salient cells overlapping the window.
    let in_window = |i: usize| {
        window.is_none_or(|[u0, v0, u1, v1]| {
            let (c, r) = (i % cols, i / cols);
            let cell_of = |p: u32| p as usize / cell;
            (cell_of(u0)..=cell_of(u1.saturating_sub(1))).contains(&c)
                && (cell_of(v0)..=cell_of(v1.saturating_sub(1))).contains(&r)
        })
    };
    let seeds: Vec<usize> = salient.iter().copied().filter(|&i| in_window(i)).collect();
    let feats: Vec<[f32; 3]> = seeds.iter().map(|&i| feature(i)).collect();
    let mut is_salient = vec![false; grid.len()];
    for &i in &salient {
        is_salient[i] = true;
    }
    let hs = params.spatial_bandwidth;
    let h2 = hs * hs;
    let mut modes: Vec<[f32; 3]> = Vec::new();
    let mut labels = vec![None; grid.len()];
    let merge2 = h2 / 4.0;
    for (k, start) in feats.iter().enumerate() {
        let mut x = *start;
        for _ in 0..params.max_iterations {
            let (mut acc, mut n) = ([0f32; 3], 0usize);
            // Only cells within the spatial bandwidth can be in the kernel: scan that window.
            let span = |c: f32, len: usize| {
                let lo = (c - hs).floor().max(0.0) as usize;
                let hi = ((c + hs).ceil().max(0.0) as usize).min(len - 1);
                lo..=hi
            };
            for r in span(x[1], rows) {
                for c in span(x[0], cols) {
                    let i = r * cols + c;
                    if !is_salient[i] {
                        continue;
                    }
                    let f = feature(i);
                    if dist2(&f, &x) <= h2 {
                        for d in 0..3 {
                            acc[d] += f[d];
                        }
                        n += 1;
                    }
                }
            }
            // n ≥ 1: the seed lies within its own kernel on the first step and the mean of
            // points in a ball stays within reach of them afterwards.
            let next = acc.map(|a| a / n.max(1) as f32);
            let moved = dist2(&next, &x);
            x = next;
            if moved < 1e-4 {
                break;
            }
        }
        let label = match modes.iter().position(|m| dist2(m, &x) <= merge2) {
            Some(j) => j,
            None => {
                modes.push(x);
                modes.len() - 1
            }
        };
        labels[seeds[k]] = Some(label as u32);
    }
    let mut sums = vec![0f32; modes.len()];
    let mut cells = vec![0usize; modes.len()];
    for (i, l) in labels.iter().enumerate() {
        if let Some(l) = l {
            sums[*l as usize] += grid[i];
            cells[*l as usize] += 1;
        }
    }
    let mean_saliency = sums
        .iter()
        .zip(&cells)
        .map(|(s, n)| s / (*n).max(1) as f32)
        .collect();
    SalientRegions {
        cols,
        rows,
        cell,
        labels,
        mean_saliency,
        cells,
    }
}

fn dist2(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

/// The ROI as a row-major pixel mask of the map's size (method.md §4): the region with the
/// highest mean saliency (of at least [`RegionParams::min_cells`] cells). With `object` (the
/// target's pixel mask from depth segmentation), only regions overlapping the object compete and
/// the ROI is the winner intersected with the object; when no salient region touches the object
/// (a dull object chosen by a hint), the ROI is the object's mask. Without an object and without
/// any salient region, `None`.
pub fn region_of_interest(
    regions: &SalientRegions,
    width: usize,
    height: usize,
    object: Option<&[bool]>,
    params: &RegionParams,
) -> Option<Vec<bool>> {
    let n = regions.mean_saliency.len();
    let mut overlap = vec![0usize; n];
    if let Some(obj) = object {
        for v in 0..height {
            for u in 0..width {
                if obj[v * width + u]
                    && let Some(l) = regions.label_at(u, v)
                {
                    overlap[l as usize] += 1;
                }
            }
        }
    }
    let best = (0..n)
        .filter(|&l| regions.cells[l] >= params.min_cells.max(1))
        .filter(|&l| object.is_none() || overlap[l] > 0)
        .max_by(|&a, &b| {
            regions.mean_saliency[a]
                .total_cmp(&regions.mean_saliency[b])
                .then(b.cmp(&a))
        });
    let Some(best) = best else {
        return object.map(<[bool]>::to_vec);
    };
    let mut roi = vec![false; width * height];
    for v in 0..height {
        for u in 0..width {
            let i = v * width + u;
            roi[i] = regions.label_at(u, v) == Some(best as u32) && object.is_none_or(|o| o[i]);
        }
    }
    Some(roi)
}

/// The bounding box [u_min, u_max) × [v_min, v_max) of a mask, `None` if it is empty.
pub fn mask_box(mask: &[bool], width: usize) -> Option<[u32; 4]> {
    let mut b: Option<[u32; 4]> = None;
    for (i, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
        let (u, v) = ((i % width) as u32, (i / width) as u32);
        b = Some(match b {
            None => [u, v, u + 1, v + 1],
            Some([a, c, d, e]) => [a.min(u), c.min(v), d.max(u + 1), e.max(v + 1)],
        });
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map_with(blobs: &[(usize, usize, usize, f32)], w: usize, h: usize) -> Plane32 {
        let mut data = vec![0.0; w * h];
        for &(u0, v0, side, s) in blobs {
            for v in v0..v0 + side {
                for u in u0..u0 + side {
                    data[v * w + u] = s;
                }
            }
        }
        Plane32 {
            width: w,
            height: h,
            data,
        }
    }

    #[test]
    fn two_separate_blobs_are_two_regions_and_the_brighter_is_the_roi() {
        // 160×120, blobs of 32 px (4×4 cells of 8 px) far apart.
        let map = map_with(&[(16, 16, 32, 0.6), (96, 64, 32, 1.0)], 160, 120);
        let params = RegionParams::default();
        let r = salient_regions(&map, &params);
        assert_eq!(r.mean_saliency.len(), 2, "{r:?}");
        assert_eq!(r.cells, vec![16, 16]);
        let roi = region_of_interest(&r, 160, 120, None, &params).unwrap();
        assert_eq!(mask_box(&roi, 160), Some([96, 64, 128, 96]));
        assert_eq!(roi.iter().filter(|m| **m).count(), 32 * 32);
    }

    #[test]
    fn the_object_mask_restricts_the_competition_and_the_roi() {
        let map = map_with(&[(16, 16, 32, 0.6), (96, 64, 32, 1.0)], 160, 120);
        let params = RegionParams::default();
        let r = salient_regions(&map, &params);
        // The object is the dimmer blob's left half: the brighter region does not touch it.
        let mut obj = vec![false; 160 * 120];
        for v in 16..48 {
            for u in 16..32 {
                obj[v * 160 + u] = true;
            }
        }
        let roi = region_of_interest(&r, 160, 120, Some(&obj), &params).unwrap();
        assert_eq!(roi, obj);
        // An object no salient region touches: the ROI is the object.
        let mut far = vec![false; 160 * 120];
        far[119 * 160] = true;
        assert_eq!(
            region_of_interest(&r, 160, 120, Some(&far), &params).unwrap(),
            far
        );
    }

    /// Seeded in a window, the regions over it are those of the whole map; the cells outside
    /// stay unlabelled.
    #[test]
    fn regions_near_a_window_are_those_of_the_whole_map_there() {
        let map = map_with(&[(16, 16, 32, 0.6), (96, 64, 32, 1.0)], 160, 120);
        let params = RegionParams::default();
        let all = salient_regions(&map, &params);
        let near = salient_regions_near(&map, &params, Some([16, 16, 48, 48]));
        assert_eq!(near.mean_saliency.len(), 1, "{near:?}");
        for v in (0..120).step_by(8) {
            for u in (0..160).step_by(8) {
                if (16..48).contains(&u) && (16..48).contains(&v) {
                    assert_eq!(near.label_at(u, v).is_some(), all.label_at(u, v).is_some());
                } else {
                    assert_eq!(near.label_at(u, v), None, "({u}, {v})");
                }
            }
        }
        let k = all.label_at(20, 20).unwrap() as usize;
        assert_eq!(near.mean_saliency[0], all.mean_saliency[k]);
        assert_eq!(near.cells[0], all.cells[k]);
    }

    #[test]
    fn a_uniform_map_has_no_region() {
        let map = map_with(&[], 64, 48);
        let r = salient_regions(&map, &RegionParams::default());
        assert!(r.mean_saliency.is_empty());
        assert!(region_of_interest(&r, 64, 48, None, &RegionParams::default()).is_none());
    }

    #[test]
    fn mask_box_is_half_open() {
        let mut m = vec![false; 20];
        m[6] = true; // (1, 1) in a 5-wide mask
        m[13] = true; // (3, 2)
        assert_eq!(mask_box(&m, 5), Some([1, 1, 4, 3]));
        assert_eq!(mask_box(&[false; 4], 2), None);
    }
}
