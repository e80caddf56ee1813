//! A parallel-jaw grasp given by its configuration g = {x, y, z, θ} (dissertation §3.2.2,
//! Figure 3.3 (a)): the jaws' centre and the line they close along, the gripper coming straight
//! down onto the table. This is what the learned-quality search (ch. 3) chooses among and
//! what its training labels were executed with; `PlanHints::parallel_grasp` has graspd
//! realise one with the hand's kinematics (`final_configuration::realise`).

use crate::cloud::{CloudIndex, tangents};
use crate::error::FieldError;
use nalgebra::{Point3, Vector3};

/// Object points this close to the jaws' line are what the jaws close on, m (about a jaw pad's
/// half width).
pub const JAW_TUBE: f64 = 0.006;
/// Least distance between the two jaws' contacts, m: a thinner section is no opposition.
pub const MIN_SPAN: f64 = 0.004;
/// Room a jaw needs beyond the opening to come down beside the object, m (a jaw's thickness
/// and a margin).
pub const JAW_CLEARANCE: f64 = 0.015;
/// Spacing of the balls that find the points near the jaws' line, m
/// (`ParallelGrasp::tube_cover`).
const TUBE_COVER_STEP: f64 = 0.008;

/// g = {x, y, z, θ}: the jaws' centre (x, y on the table, z its height) and the horizontal
/// line they close along (θ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParallelGrasp {
    /// The jaws' centre in the cloud's frame.
    pub centre: Point3<f64>,
    /// Unit direction the jaws close along (either sense), perpendicular to `up`.
    pub axis: Vector3<f64>,
}

impl ParallelGrasp {
    /// g from its table-frame configuration: (x, y) and z along the table frame's axes
    /// (`frame`: origin on the table, unit x, y in it and z up) and θ from its x axis.
    pub fn from_configuration(
        frame: &TableFrame,
        x: f64,
        y: f64,
        z: f64,
        theta: f64,
    ) -> ParallelGrasp {
        ParallelGrasp {
            centre: frame.origin + frame.x * x + frame.y * y + frame.z * z,
            axis: frame.x * theta.cos() + frame.y * theta.sin(),
        }
    }

    /// The grasp checked against `up` (the table's normal): a finite centre, and an axis of
    /// some length that is turned into the table's plane (a tilted axis is projected onto it).
    pub fn checked(&self, up: &Vector3<f64>, field: &str) -> Result<ParallelGrasp, FieldError> {
        if !(self.centre.coords.iter().all(|v| v.is_finite())) {
            return Err(FieldError::new(
                format!("{field}.centre"),
                "must be finite".to_string(),
            ));
        }
        let flat = self.axis - up * self.axis.dot(up);
        let Some(axis) = flat.try_normalize(1e-6).filter(|_| self.axis.norm() > 1e-6) else {
            return Err(FieldError::new(
                format!("{field}.axis"),
                "must be a direction with a component along the table (the jaws close \
                 horizontally; the gripper comes straight down)"
                    .to_string(),
            ));
        };
        Ok(ParallelGrasp {
            centre: self.centre,
            axis,
        })
    }

    /// The opposition the jaws close on: among the object points within [`JAW_TUBE`] of the
    /// jaws' line and within `half_opening` of the centre along it, the two outermost (the
    /// first each jaw meets; of points level along the line, the first in the cloud); None when
    /// the jaws hold nothing, a section thinner than [`MIN_SPAN`], or the object goes on past a
    /// jaw (within [`JAW_CLEARANCE`] beyond the opening: the jaw would come down on it).
    pub fn opposition(
        &self,
        points: &[Point3<f64>],
        index: &CloudIndex,
        half_opening: f64,
    ) -> Option<(usize, usize)> {
        let reach = half_opening + JAW_CLEARANCE;
        let mut lo: Option<(usize, f64)> = None;
        let mut hi: Option<(usize, f64)> = None;
        for i in self.tube_cover(index, reach) {
            let d = points[i] - self.centre;
            let t = d.dot(&self.axis);
            if t.abs() > reach || (d - self.axis * t).norm() > JAW_TUBE {
                continue;
            }
            if t.abs() > half_opening {
                return None;
            }
            if lo.is_none_or(|(k, l)| t < l || (t == l && i < k)) {
                lo = Some((i, t));
            }
            if hi.is_none_or(|(k, h)| t > h || (t == h && i < k)) {
                hi = Some((i, t));
            }
        }
        let ((a, ta), (b, tb)) = (lo?, hi?);
        (tb - ta >= MIN_SPAN).then_some((a, b))
    }

    /// The cloud points in a row of small balls along the jaws' line from −`reach` to
    /// `reach` that together cover every point within [`JAW_TUBE`] of it (some more than
    /// once): the tube's points without visiting the whole object, which one ball about the
    /// centre did (the learned-quality search tests up to 6,000 lines a plan; on a cluttered
    /// table's segmented object that ball took a third of the request).
    fn tube_cover<'a>(
        &'a self,
        index: &'a CloudIndex,
        reach: f64,
    ) -> impl Iterator<Item = usize> + 'a {
        // A point at most JAW_TUBE off the line lies within half a step along it of a ball's
        // centre; the margin covers rounding.
        let radius = ((TUBE_COVER_STEP / 2.0).powi(2) + JAW_TUBE.powi(2)).sqrt() + 1e-6;
        let steps = (2.0 * reach / TUBE_COVER_STEP).ceil() as usize;
        (0..=steps).flat_map(move |k| {
            let at = self.centre + self.axis * (-reach + k as f64 * TUBE_COVER_STEP);
            index.within_unsorted(&at, radius)
        })
    }

    /// The grasp moved along its line to the middle of the section its jaws close on (where
    /// a gripper whose jaws close symmetrically is put), with that opposition; None as
    /// [`Self::opposition`].
    pub fn centred(
        &self,
        points: &[Point3<f64>],
        index: &CloudIndex,
        half_opening: f64,
    ) -> Option<(ParallelGrasp, (usize, usize))> {
        let (a, b) = self.opposition(points, index, half_opening)?;
        let mid = ((points[a] - self.centre).dot(&self.axis)
            + (points[b] - self.centre).dot(&self.axis))
            / 2.0;
        let g = ParallelGrasp {
            centre: self.centre + self.axis * mid,
            axis: self.axis,
        };
        let o = g.opposition(points, index, half_opening)?;
        Some((g, o))
    }
}

/// A frame on the table: origin on it, z its normal (up), x and y in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableFrame {
    pub origin: Point3<f64>,
    pub x: Vector3<f64>,
    pub y: Vector3<f64>,
    pub z: Vector3<f64>,
}

impl TableFrame {
    /// The frame of the plane with normal `up` that lies `height_of_over` below `over`, its
    /// in-plane axes [`tangents`] of `up`.
    pub fn under(over: &Point3<f64>, up: &Vector3<f64>, height_of_over: f64) -> TableFrame {
        let z = up.normalize();
        let (x, y) = tangents(&z);
        TableFrame {
            origin: over - z * height_of_over,
            x,
            y,
            z,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 60 × 40 × 30 mm box's visible faces, 2 mm apart, on a table at z = 0.
    fn box_points() -> Vec<Point3<f64>> {
        let mut p = Vec::new();
        for i in 0..=30 {
            for j in 0..=20 {
                let (x, y) = (-0.03 + i as f64 * 0.002, -0.02 + j as f64 * 0.002);
                p.push(Point3::new(x, y, 0.03));
            }
            for k in 0..=15 {
                let (x, z) = (-0.03 + i as f64 * 0.002, k as f64 * 0.002);
                p.push(Point3::new(x, -0.02, z));
                p.push(Point3::new(x, 0.02, z));
            }
        }
        for j in 0..=20 {
            for k in 0..=15 {
                let (y, z) = (-0.02 + j as f64 * 0.002, k as f64 * 0.002);
                p.push(Point3::new(-0.03, y, z));
                p.push(Point3::new(0.03, y, z));
            }
        }
        p
    }

    /// The opposition by its definition: every point of the cloud looked at.
    fn opposition_by_scan(
        g: &ParallelGrasp,
        points: &[Point3<f64>],
        half_opening: f64,
    ) -> Option<(usize, usize)> {
        let reach = half_opening + JAW_CLEARANCE;
        let tube: Vec<(usize, f64)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| (i, p - g.centre))
            .filter(|(_, d)| {
                let t = d.dot(&g.axis);
                t.abs() <= reach && (d - g.axis * t).norm() <= JAW_TUBE
            })
            .map(|(i, d)| (i, d.dot(&g.axis)))
            .collect();
        if tube.iter().any(|(_, t)| t.abs() > half_opening) {
            return None;
        }
        let lo = tube
            .iter()
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))?;
        let hi = tube
            .iter()
            .min_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)))?;
        (hi.1 - lo.1 >= MIN_SPAN).then_some((lo.0, hi.0))
    }

    /// The row of small balls finds what a look at every point finds, on the box (whose grid
    /// puts many points level along a line) and on a scattered cloud, for lines through,
    /// beside and past them.
    #[test]
    fn the_tube_cover_finds_the_opposition_every_point_gives() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut scattered = Vec::new();
        for _ in 0..3000 {
            let (a, z) = (
                rng.random_range(0.0..std::f64::consts::TAU),
                rng.random_range(0.0..0.08),
            );
            let r = 0.03 + rng.random_range(-0.002..0.002);
            scattered.push(Point3::new(r * a.cos(), r * a.sin(), z));
        }
        let (mut found, mut none) = (0, 0);
        for points in [box_points(), scattered] {
            let index = CloudIndex::new(&points);
            for k in 0..2000 {
                let theta = if k % 4 == 0 {
                    std::f64::consts::FRAC_PI_2 * (k / 4 % 2) as f64
                } else {
                    rng.random_range(0.0..std::f64::consts::PI)
                };
                let g = ParallelGrasp {
                    centre: Point3::new(
                        rng.random_range(-0.06..0.06),
                        rng.random_range(-0.06..0.06),
                        rng.random_range(0.0..0.04),
                    ),
                    axis: Vector3::new(theta.cos(), theta.sin(), 0.0),
                };
                let half = rng.random_range(0.01..0.045);
                let fast = g.opposition(&points, &index, half);
                assert_eq!(
                    fast,
                    opposition_by_scan(&g, &points, half),
                    "{g:?}, half {half}"
                );
                match fast {
                    Some(_) => found += 1,
                    None => none += 1,
                }
            }
        }
        assert!(found > 200 && none > 200, "{found} found, {none} none");
    }

    /// Jaws closing along y at the box's mid-height meet its ±20 mm faces; along x, its
    /// ±30 mm ends; above the box, or opened too little to reach the ends, nothing.
    #[test]
    fn the_jaws_close_on_the_outermost_points_of_their_line() {
        let points = box_points();
        let index = CloudIndex::new(&points);
        let g = ParallelGrasp {
            centre: Point3::new(0.004, 0.0, 0.015),
            axis: Vector3::y(),
        };
        let (a, b) = g.opposition(&points, &index, 0.0425).unwrap();
        assert!((points[a].y + 0.02).abs() < 1e-9 && (points[b].y - 0.02).abs() < 1e-9);
        assert!((points[a].x - 0.004).abs() <= JAW_TUBE && (points[a].z - 0.015).abs() <= JAW_TUBE);
        let g = ParallelGrasp {
            axis: -Vector3::x(),
            ..g
        };
        let (a, b) = g.opposition(&points, &index, 0.0425).unwrap();
        assert!((points[a].x - 0.03).abs() < 1e-9 && (points[b].x + 0.03).abs() < 1e-9);
        let above = ParallelGrasp {
            centre: Point3::new(0.0, 0.0, 0.05),
            ..g
        };
        assert_eq!(above.opposition(&points, &index, 0.0425), None);
        // Opened 25 mm each side along x the jaws reach neither end face (the box is 60 mm
        // long): nothing between them.
        assert_eq!(g.opposition(&points, &index, 0.025), None);
        // Off centre by 10 mm along y the jaws still span the 40 mm section; centred, the
        // grasp sits at its middle.
        let off = ParallelGrasp {
            centre: Point3::new(0.004, 0.01, 0.015),
            axis: Vector3::y(),
        };
        let (c, (a, b)) = off.centred(&points, &index, 0.0425).unwrap();
        assert!(c.centre.y.abs() < 1e-9 && (points[b].y - points[a].y - 0.04).abs() < 1e-9);
    }

    /// g from {x, y, z, θ} in a table frame, and the checks naming the field.
    #[test]
    fn configuration_and_checks() {
        let frame = TableFrame::under(&Point3::new(0.1, 0.2, 0.5), &Vector3::z(), 0.5);
        assert!((frame.origin - Point3::new(0.1, 0.2, 0.0)).norm() < 1e-12);
        assert!((frame.x.cross(&frame.y) - frame.z).norm() < 1e-12 && frame.x.dot(&frame.z) == 0.0);
        let g = ParallelGrasp::from_configuration(
            &frame,
            0.01,
            0.02,
            0.03,
            std::f64::consts::FRAC_PI_2,
        );
        let want = frame.origin + frame.x * 0.01 + frame.y * 0.02 + Vector3::z() * 0.03;
        assert!((g.centre - want).norm() < 1e-12 && (g.centre.z - 0.03).abs() < 1e-12);
        assert!((g.axis - frame.y).norm() < 1e-12);
        let tilted = ParallelGrasp {
            axis: Vector3::new(1.0, 0.0, 1.0),
            ..g
        };
        let flat = tilted
            .checked(&Vector3::z(), "hints.parallel_grasp")
            .unwrap();
        assert!((flat.axis - Vector3::x()).norm() < 1e-12);
        let vertical = ParallelGrasp {
            axis: Vector3::z(),
            ..g
        };
        let e = vertical
            .checked(&Vector3::z(), "hints.parallel_grasp")
            .unwrap_err();
        assert_eq!(e.field, "hints.parallel_grasp.axis");
        let nan = ParallelGrasp {
            centre: Point3::new(f64::NAN, 0.0, 0.0),
            ..g
        };
        let e = nan
            .checked(&Vector3::z(), "hints.parallel_grasp")
            .unwrap_err();
        assert_eq!(e.field, "hints.parallel_grasp.centre");
    }
}
