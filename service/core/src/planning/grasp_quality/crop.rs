//! The quality network's view of a parallel-jaw grasp g = {x, y, z, θ} (dissertation §3.2.2,
//! Figure 3.4): the depth image around the grasp, turned so that the jaws close along its rows,
//! and the grasp's configuration.
//!
//! Choice where the text leaves it open: the "depth image" is the object's height map over
//! the table seen straight down (its visible points dropped along the table's normal), not
//! the camera's depth image — the gripper comes straight down (Figure 3.3 (a)), the crop then
//! does not depend on where the camera stands, and a cloud input has one as well as an RGB-D
//! frame. Two channels: each cell's highest point relative to the grasp height, and whether
//! any object point fell in it (a cell with none is table, or not seen).

use crate::planning::parallel_grasp::{ParallelGrasp, TableFrame};
use nalgebra::Point3;

/// Cells along each side of the crop.
pub const CROP: usize = 32;
/// Cell size, m: the crop spans 128 mm, the 2F-85's 85 mm opening and its fingers' width.
pub const CELL: f64 = 0.004;
/// Heights relative to the grasp are clipped to ±this and scaled to ±1, m.
pub const HEIGHT_RANGE: f64 = 0.06;
/// The configuration's height is given in units of this, m.
pub const HEIGHT_UNIT: f64 = 0.1;
/// Channels of the crop.
pub const CHANNELS: usize = 2;

/// The crop (CHANNELS × CROP × CROP, row-major; rows along the jaws' axis) and the
/// configuration features ([the grasp's height above the table / HEIGHT_UNIT]).
#[derive(Debug, Clone, PartialEq)]
pub struct GraspView {
    pub crop: Vec<f32>,
    pub configuration: [f32; 1],
}

/// The view of grasp `g` of the object whose visible points are `points`, on the table
/// `table` (z up). Cell (r, c) covers u ∈ [(c − 16) CELL, (c − 15) CELL) along the jaws' axis
/// and v ∈ [(r − 16) CELL, (r − 15) CELL) along up × axis, about the grasp's centre.
pub fn grasp_view(points: &[Point3<f64>], table: &TableFrame, g: &ParallelGrasp) -> GraspView {
    let z_g = (g.centre - table.origin).dot(&table.z);
    let u_axis = g.axis;
    let v_axis = table.z.cross(&u_axis);
    let half = (CROP / 2) as f64;
    let mut top = vec![f64::NEG_INFINITY; CROP * CROP];
    for p in points {
        let d = p - g.centre;
        let c = (d.dot(&u_axis) / CELL + half).floor();
        let r = (d.dot(&v_axis) / CELL + half).floor();
        if c < 0.0 || r < 0.0 || c >= CROP as f64 || r >= CROP as f64 {
            continue;
        }
        let k = r as usize * CROP + c as usize;
        top[k] = top[k].max((p - table.origin).dot(&table.z));
    }
    let mut crop = vec![0f32; CHANNELS * CROP * CROP];
    for (k, &h) in top.iter().enumerate() {
        let (height, seen) = if h.is_finite() { (h, 1.0) } else { (0.0, 0.0) };
        crop[k] = ((height - z_g).clamp(-HEIGHT_RANGE, HEIGHT_RANGE) / HEIGHT_RANGE) as f32;
        crop[CROP * CROP + k] = seen;
    }
    GraspView {
        crop,
        configuration: [(z_g / HEIGHT_UNIT) as f32],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// A block's top, 30 mm up, sampled every mm over x ∈ [−10, 9], y ∈ [−20, 19] mm, under a
    /// grasp 20 mm up closing along y. By hand: u = y gives columns ⌊y/4 + 16⌋ = 11…20, and
    /// v = (z × y)·p = −x ∈ [−9, 10] mm gives rows 13…18; those 60 cells read
    /// (30 − 20)/60 = 1/6 and seen, every other cell the table, (0 − 20)/60 = −1/3, unseen; the
    /// configuration is 20 mm / 100 mm = 0.2.
    #[test]
    fn a_block_under_the_grasp_reads_as_computed_by_hand() {
        let mut points = Vec::new();
        for i in -10..10 {
            for j in -20..20 {
                points.push(Point3::new(i as f64 * 0.001, j as f64 * 0.001, 0.03));
            }
        }
        let table = TableFrame {
            origin: Point3::origin(),
            x: Vector3::x(),
            y: Vector3::y(),
            z: Vector3::z(),
        };
        let g = ParallelGrasp {
            centre: Point3::new(0.0, 0.0, 0.02),
            axis: Vector3::y(),
        };
        let view = grasp_view(&points, &table, &g);
        assert_eq!(view.configuration, [0.2]);
        let mut block = 0;
        for r in 0..CROP {
            for c in 0..CROP {
                let (h, seen) = (
                    view.crop[r * CROP + c],
                    view.crop[CROP * CROP + r * CROP + c],
                );
                let inside = (11..=20).contains(&c) && (13..=18).contains(&r);
                if seen == 1.0 {
                    assert!(inside, "cell ({r}, {c}) seen");
                    assert!((h - 1.0 / 6.0).abs() < 1e-6, "{h}");
                    block += 1;
                } else {
                    assert!((h + 1.0 / 3.0).abs() < 1e-6, "{h}");
                }
            }
        }
        assert_eq!(block, 10 * 6);
    }
}
