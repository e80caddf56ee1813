//! The attention point p_att: the strongest mean-shift mode of map s* inside the region.

use super::maps::{TypeMaps, scale_index};
use crate::grasp_type::GraspType;

/// Seeds per side of the grid over the ROI (at most 8 × 8 = 64 mean-shift runs).
const SEED_GRID: usize = 8;
/// Mean-shift stops when a step is shorter than this (pixels) or after `MAX_ITERATIONS`.
const CONVERGED_PX: f64 = 0.01;
const MAX_ITERATIONS: usize = 100;

/// The attention point p_att (method.md §4): mean-shift over the ROI pixels weighted by map
/// `s_star`, in FRAME pixel coordinates.
///
/// - Kernel: Gaussian with σ = `bandwidth_px`, truncated at 3σ. Gaussian rather than flat so
///   that a seed on a plateau of saturated probabilities still moves towards the plateau's
///   centre instead of stopping wherever its window is full. The bandwidth should be about the
///   size of the graspable part: a plateau much wider than 3σ has many modes.
/// - Seeds: the ROI's bounding box is cut into at most 8 × 8 cells; each seeds at its most
///   probable ROI pixel (first in scan order on ties), so a small strong blob is never missed.
/// - Speed: pixel weights are binned into cells of max(1, ⌊σ/4⌋) pixels that keep their exact
///   weighted centroids; the kernel is evaluated at cell centres.
/// - Modes closer than σ/2 are merged (their mean is the cluster centre); the centre with the
///   highest P(s*) (map pixel under it) wins, ties to the cluster with more seeds, then the
///   first found. Deterministic.
///
/// `None` when the ROI is empty or has no positive weight.
pub fn attention_pixel(
    maps: &TypeMaps,
    s_star: GraspType,
    roi: &[bool],
    frame_w: usize,
    frame_h: usize,
    bandwidth_px: f64,
) -> Option<(f64, f64)> {
    assert_eq!(roi.len(), frame_w * frame_h, "ROI mask size");
    let sigma = if bandwidth_px.is_finite() && bandwidth_px > 0.0 {
        bandwidth_px
    } else {
        1.0
    };
    let plane = maps.plane(s_star);
    let cols: Vec<usize> = (0..frame_w)
        .map(|u| scale_index(u, frame_w, maps.width))
        .collect();
    let weight = |u: usize, v: usize| -> f64 {
        let w = plane[scale_index(v, frame_h, maps.height) * maps.width + cols[u]] as f64;
        if w.is_finite() { w.max(0.0) } else { 0.0 }
    };

    // ROI bounding box.
    let (mut u_lo, mut u_hi, mut v_lo, mut v_hi) = (usize::MAX, 0, usize::MAX, 0);
    for (i, _) in roi.iter().enumerate().filter(|(_, r)| **r) {
        let (u, v) = (i % frame_w, i / frame_w);
        (u_lo, u_hi, v_lo, v_hi) = (u_lo.min(u), u_hi.max(u), v_lo.min(v), v_hi.max(v));
    }
    if u_lo > u_hi {
        return None;
    }
    let (bw, bh) = (u_hi - u_lo + 1, v_hi - v_lo + 1);

    // Binned moments (Σw, Σw·u, Σw·v) and the seed grid's argmax pixels in one pass.
    let f = ((sigma / 4.0).floor() as usize).max(1);
    let (cw, ch) = (bw.div_ceil(f), bh.div_ceil(f));
    let mut m0 = vec![0.0f64; cw * ch];
    let mut mu = vec![0.0f64; cw * ch];
    let mut mv = vec![0.0f64; cw * ch];
    let (gx, gy) = (SEED_GRID.min(bw), SEED_GRID.min(bh));
    let mut seeds: Vec<Option<(f64, usize, usize)>> = vec![None; gx * gy];
    for v in v_lo..=v_hi {
        for u in u_lo..=u_hi {
            if !roi[v * frame_w + u] {
                continue;
            }
            let w = weight(u, v);
            if w <= 0.0 {
                continue;
            }
            let c = ((v - v_lo) / f) * cw + (u - u_lo) / f;
            m0[c] += w;
            mu[c] += w * u as f64;
            mv[c] += w * v as f64;
            let g = ((v - v_lo) * gy / bh) * gx + (u - u_lo) * gx / bw;
            if seeds[g].is_none_or(|(best, _, _)| w > best) {
                seeds[g] = Some((w, u, v));
            }
        }
    }

    let reach = 3.0 * sigma;
    let inv_2s2 = 1.0 / (2.0 * sigma * sigma);
    // Cell centre in frame pixels (cell i spans pixels lo + i·f … lo + i·f + f − 1).
    let centre = |lo: usize, i: usize| lo as f64 + (i * f) as f64 + (f as f64 - 1.0) / 2.0;
    let cell_range = |c: f64, lo: usize, n: usize| -> (usize, usize) {
        let a = ((c - reach - lo as f64) / f as f64).floor().max(0.0) as usize;
        let b = (((c + reach - lo as f64) / f as f64).ceil().max(0.0) as usize).min(n - 1);
        (a.min(n - 1), b)
    };
    let mut kx = Vec::new();
    let mut ky = Vec::new();
    let mut shift = |mut x: f64, mut y: f64| -> Option<(f64, f64)> {
        for _ in 0..MAX_ITERATIONS {
            let (i0, i1) = cell_range(x, u_lo, cw);
            let (j0, j1) = cell_range(y, v_lo, ch);
            kx.clear();
            kx.extend((i0..=i1).map(|i| (-(centre(u_lo, i) - x).powi(2) * inv_2s2).exp()));
            ky.clear();
            ky.extend((j0..=j1).map(|j| (-(centre(v_lo, j) - y).powi(2) * inv_2s2).exp()));
            let (mut s0, mut su, mut sv) = (0.0, 0.0, 0.0);
            for (j, kyj) in (j0..=j1).zip(&ky) {
                for (i, kxi) in (i0..=i1).zip(&kx) {
                    let c = j * cw + i;
                    let k = kxi * kyj;
                    s0 += k * m0[c];
                    su += k * mu[c];
                    sv += k * mv[c];
                }
            }
            if s0 <= 1e-300 {
                return None;
            }
            let (nx, ny) = (su / s0, sv / s0);
            let step = (nx - x).hypot(ny - y);
            (x, y) = (nx, ny);
            if step < CONVERGED_PX {
                break;
            }
        }
        Some((x, y))
    };

    // Clusters: (sum of modes u, sum of modes v, members).
    let mut clusters: Vec<(f64, f64, usize)> = Vec::new();
    for (_, u, v) in seeds.into_iter().flatten() {
        let Some((x, y)) = shift(u as f64, v as f64) else {
            continue;
        };
        let near = clusters.iter_mut().find(|(sx, sy, n)| {
            let k = *n as f64;
            (sx / k - x).hypot(sy / k - y) < sigma / 2.0
        });
        match near {
            Some((sx, sy, n)) => {
                *sx += x;
                *sy += y;
                *n += 1;
            }
            None => clusters.push((x, y, 1)),
        }
    }
    let mut best: Option<(f32, usize, f64, f64)> = None;
    for (sx, sy, n) in clusters {
        let (x, y) = (sx / n as f64, sy / n as f64);
        let u = (x.round().max(0.0) as usize).min(frame_w - 1);
        let v = (y.round().max(0.0) as usize).min(frame_h - 1);
        let (um, vm) = maps.map_pixel(u, v, frame_w, frame_h);
        let p = maps.prob(s_star, um, vm);
        let better = match best {
            None => true,
            Some((bp, bn, _, _)) => p > bp || (p == bp && n > bn),
        };
        if better {
            best = Some((p, n, x, y));
        }
    }
    best.map(|(_, _, x, y)| (x, y))
}
