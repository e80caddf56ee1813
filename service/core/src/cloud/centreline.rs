//! The centreline of an elongated object lying on the table (a banana, a cucumber, a bent tool
//! handle, a box lying on its side), for a completion that mirrors the visible side across it
//! (`cloud::completion`): such an object is mirror-symmetric about the vertical surface through
//! its centreline, which may curve, while no half turn about one vertical axis maps a curved
//! object onto itself (a banana turned half a turn is bent the other way: its image lies where
//! the camera saw the table, and free-space carving leaves almost nothing of it).
//!
//! - e1, e2: the principal directions of the visible points' horizontal spread (e1 the long
//!   one); the object counts as elongated when its 5–95 % extent along e1 is at least
//!   [`ELONGATION`] times that along e2;
//! - the points are cut into slices across e1; in each, the **ridge**: the middle (along e2) of
//!   the slice's points within [`RIDGE_BAND`] of its highest one. A lying tube's highest line
//!   runs straight above its axis, and a camera above the table sees a few mm down both sides
//!   of it; a box's top face is seen whole, its middle is the box's;
//! - the centreline s(t) = a₀ + a₁t + a₂t² along e1 (t) is the ridges' least-squares fit,
//!   weighted by their point counts: a straight object gets a straight line, a curved one its
//!   bend, and noise on single slices is smoothed away.

use nalgebra::{Point3, Vector2, Vector3};

/// Footprint extent ratio (long over short) from which an object counts as elongated.
pub const ELONGATION: f64 = 2.0;
/// A slice's ridge: its points within this of its highest one, m.
pub const RIDGE_BAND: f64 = 0.004;
/// Slice length along the centreline, m (at most [`MAX_SLICES`] slices).
pub const SLICE: f64 = 0.01;
/// Most slices along the centreline.
pub const MAX_SLICES: usize = 24;

/// A centreline s(t) in the horizontal frame (e1, e2) of the support plane (normal `up`).
#[derive(Debug, Clone, PartialEq)]
pub struct Centreline {
    pub e1: Vector3<f64>,
    pub e2: Vector3<f64>,
    pub up: Vector3<f64>,
    /// s(t) = c[0] + c[1]·t + c[2]·t², t and s the coordinates along e1 and e2 (m).
    pub c: [f64; 3],
}

impl Centreline {
    /// The centreline of `points` (module rules); None when they are not elongated or too few
    /// slices have points. `up` is a unit vector.
    pub fn fit(points: &[Point3<f64>], up: &Vector3<f64>) -> Option<Self> {
        if points.len() < 20 {
            return None;
        }
        let (a, b) = super::tangents(up);
        // The horizontal spread's principal directions (2 × 2 covariance, closed form).
        let flat: Vec<Vector2<f64>> = points
            .iter()
            .map(|p| Vector2::new(p.coords.dot(&a), p.coords.dot(&b)))
            .collect();
        let n = flat.len() as f64;
        let mean = flat.iter().sum::<Vector2<f64>>() / n;
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for q in &flat {
            let d = q - mean;
            sxx += d.x * d.x;
            sxy += d.x * d.y;
            syy += d.y * d.y;
        }
        let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let e1 = a * angle.cos() + b * angle.sin();
        let e2 = up.cross(&e1);
        let coords: Vec<(f64, f64, f64)> = points
            .iter()
            .map(|p| (p.coords.dot(&e1), p.coords.dot(&e2), p.coords.dot(up)))
            .collect();
        let (t_lo, t_hi) = percentile_range(coords.iter().map(|c| c.0));
        let (s_lo, s_hi) = percentile_range(coords.iter().map(|c| c.1));
        if t_hi - t_lo < ELONGATION * (s_hi - s_lo).max(1e-6) {
            return None;
        }
        let slices = (((t_hi - t_lo) / SLICE).ceil() as usize).clamp(3, MAX_SLICES);
        let width = (t_hi - t_lo) / slices as f64;
        // The slice of t; the 5 % beyond each end (the tips) are in none.
        let slice_of = |t: f64| {
            let k = ((t - t_lo) / width).floor();
            (k >= 0.0 && (k as usize) < slices).then_some(k as usize)
        };
        let mut top = vec![f64::NEG_INFINITY; slices];
        for &(t, _, z) in &coords {
            if let Some(k) = slice_of(t) {
                top[k] = top[k].max(z);
            }
        }
        let mut band = vec![(f64::INFINITY, f64::NEG_INFINITY, 0usize); slices];
        for &(t, s, z) in &coords {
            let Some(k) = slice_of(t) else { continue };
            if z >= top[k] - RIDGE_BAND {
                let e = &mut band[k];
                *e = (e.0.min(s), e.1.max(s), e.2 + 1);
            }
        }
        // Weighted least squares of the ridges, t centred on the extent's middle.
        let t0 = 0.5 * (t_lo + t_hi);
        let mut ata = nalgebra::Matrix3::<f64>::zeros();
        let mut atb = Vector3::<f64>::zeros();
        let mut used = 0;
        for (k, &(lo, hi, count)) in band.iter().enumerate() {
            if count < 3 {
                continue;
            }
            used += 1;
            let t = t_lo + (k as f64 + 0.5) * width - t0;
            let row = Vector3::new(1.0, t, t * t);
            ata += row * row.transpose() * count as f64;
            atb += row * (0.5 * (lo + hi)) * count as f64;
        }
        if used < 3 {
            return None;
        }
        let x = ata.lu().solve(&atb)?;
        // Back to t measured from the origin: s(t) = x0 + x1 (t − t0) + x2 (t − t0)².
        let c = [
            x[0] - x[1] * t0 + x[2] * t0 * t0,
            x[1] - 2.0 * x[2] * t0,
            x[2],
        ];
        Some(Self { e1, e2, up: *up, c })
    }

    /// The unit horizontal normal of the centreline's vertical surface at `p`'s place along
    /// it, and `p`'s signed distance from that surface (positive along the normal).
    pub fn normal_and_offset(&self, p: &Point3<f64>) -> (Vector3<f64>, f64) {
        let (t, s) = (p.coords.dot(&self.e1), p.coords.dot(&self.e2));
        let s_c = self.c[0] + self.c[1] * t + self.c[2] * t * t;
        let slope = self.c[1] + 2.0 * self.c[2] * t;
        let norm = (1.0 + slope * slope).sqrt();
        let normal = (self.e2 - self.e1 * slope) / norm;
        (normal, (s - s_c) / norm)
    }

    /// `p` mirrored across the centreline's vertical surface, and the surface's normal there.
    pub fn mirror(&self, p: &Point3<f64>) -> (Point3<f64>, Vector3<f64>) {
        let (normal, d) = self.normal_and_offset(p);
        (p - normal * (2.0 * d), normal)
    }
}

/// The 5th and 95th percentiles of `values`.
fn percentile_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    (at(0.05), at(0.95))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The upper half of a tube of radius 1.8 cm bent along s = 0.8·t² (t ∈ [−0.09, 0.09]: a
    /// banana's 6.5 mm sagitta), lying on the table (z = 0), turned 30° about z.
    fn bent_tube(turn: f64) -> Vec<Point3<f64>> {
        let rot = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), turn);
        let mut pts = Vec::new();
        for i in 0..=60 {
            let t = -0.09 + 0.003 * i as f64;
            let s = 0.8 * t * t;
            for k in 0..=18 {
                let phi = std::f64::consts::PI * k as f64 / 18.0;
                let p = Point3::new(t, s + 0.018 * phi.cos(), 0.018 + 0.018 * phi.sin());
                pts.push(rot * p);
            }
        }
        pts
    }

    #[test]
    fn a_bent_tube_has_its_axis_as_centreline() {
        let turn = 30f64.to_radians();
        let pts = bent_tube(turn);
        let c = Centreline::fit(&pts, &Vector3::z()).expect("elongated");
        let rot = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), turn);
        // Points on the tube's axis lie on the centreline's surface; a point 1 cm to the side of
        // the axis is 1 cm from it and mirrors to 1 cm on the other side.
        for i in 0..=10 {
            let t = -0.08 + 0.016 * i as f64;
            let on_axis = rot * Point3::new(t, 0.8 * t * t, 0.03);
            let (n, d) = c.normal_and_offset(&on_axis);
            assert!(d.abs() < 1e-3, "t = {t}: {d}");
            let side = on_axis + n * 0.01;
            let (m, _) = c.mirror(&side);
            assert!((m - (on_axis - n * 0.01)).norm() < 1e-3, "t = {t}: {m}");
        }
    }

    #[test]
    fn round_or_short_objects_have_no_centreline() {
        let mut disc = Vec::new();
        for i in 0..40 {
            let a = std::f64::consts::TAU * i as f64 / 40.0;
            disc.push(Point3::new(0.04 * a.cos(), 0.04 * a.sin(), 0.05));
        }
        assert!(Centreline::fit(&disc, &Vector3::z()).is_none());
        assert!(Centreline::fit(&bent_tube(0.0)[..10], &Vector3::z()).is_none());
    }
}
