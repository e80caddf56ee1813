//! What the reaching hand keeps clear of (§3.4.2's obstacles, the other objects on the table):
//! oriented boxes, and the support plane. The hand is a sphere of the request's radius about
//! the trajectory's point.

use crate::cloud::Plane;
use crate::error::FieldError;
use nalgebra::{Point3, UnitQuaternion, Vector3};

/// An oriented box: centre, half extents along its own axes, and its orientation (world).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Obstacle {
    pub centre: Point3<f64>,
    pub half_extents: Vector3<f64>,
    pub orientation: UnitQuaternion<f64>,
}

impl Obstacle {
    /// Checks the box; `field` names it in errors.
    pub fn validate(&self, field: &str) -> Result<(), FieldError> {
        if !self.centre.iter().all(|c| c.is_finite()) {
            return Err(FieldError::new(format!("{field}.centre"), "must be finite"));
        }
        if !self.half_extents.iter().all(|h| h.is_finite() && *h > 0.0) {
            return Err(FieldError::new(
                format!("{field}.half_extents"),
                "must be positive and finite",
            ));
        }
        if !self.orientation.coords.iter().all(|c| c.is_finite()) {
            return Err(FieldError::new(
                format!("{field}.orientation"),
                "must be finite",
            ));
        }
        Ok(())
    }

    /// Signed distance from `p` to the box (negative inside: minus the depth) and its gradient
    /// (unit, pointing away from the box).
    pub fn distance(&self, p: &Point3<f64>) -> (f64, Vector3<f64>) {
        let local = self.orientation.inverse() * (p - self.centre);
        let h = self.half_extents;
        let outside = Vector3::new(
            (local.x.abs() - h.x).max(0.0) * local.x.signum(),
            (local.y.abs() - h.y).max(0.0) * local.y.signum(),
            (local.z.abs() - h.z).max(0.0) * local.z.signum(),
        );
        let d = outside.norm();
        if d > 1e-12 {
            return (d, self.orientation * (outside / d));
        }
        // Inside: the nearest face.
        let gaps = [
            h.x - local.x.abs(),
            h.y - local.y.abs(),
            h.z - local.z.abs(),
        ];
        let (axis, depth) = gaps
            .iter()
            .copied()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("three axes");
        let mut n = Vector3::zeros();
        n[axis] = if local[axis] >= 0.0 { 1.0 } else { -1.0 };
        (-depth, self.orientation * n)
    }
}

/// The scene a reach keeps clear of.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    pub obstacles: Vec<Obstacle>,
    pub table: Option<Plane>,
    /// The hand's radius about the trajectory point, m.
    pub hand_radius: f64,
}

impl Scene {
    /// The hand's least clearance to the obstacles at `p` (sphere surface to box; +∞ without
    /// obstacles), the obstacle's index and the gradient.
    pub fn obstacle_clearance(&self, p: &Point3<f64>) -> Option<(f64, usize, Vector3<f64>)> {
        self.obstacles
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let (d, g) = o.distance(p);
                (d - self.hand_radius, i, g)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// Height of `p` above the table (None without one).
    pub fn table_height(&self, p: &Point3<f64>) -> Option<f64> {
        self.table.map(|t| t.distance(p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box 0.2 × 0.1 × 0.1 m turned 90° about z: its x half extent lies along world y.
    #[test]
    fn box_distance_and_direction_by_hand() {
        let o = Obstacle {
            centre: Point3::new(1.0, 0.0, 0.0),
            half_extents: Vector3::new(0.1, 0.05, 0.05),
            orientation: UnitQuaternion::from_axis_angle(
                &Vector3::z_axis(),
                std::f64::consts::FRAC_PI_2,
            ),
        };
        // 0.3 m along world y from the centre: 0.2 m past the long half extent.
        let (d, g) = o.distance(&Point3::new(1.0, 0.3, 0.0));
        assert!(
            (d - 0.2).abs() < 1e-12 && (g - Vector3::y()).norm() < 1e-12,
            "{d} {g}"
        );
        // Corner region: 0.1 past the short face along x and 0.1 past the top.
        let (d, _) = o.distance(&Point3::new(1.15, 0.0, 0.15));
        assert!((d - 0.1f64.hypot(0.1)).abs() < 1e-12, "{d}");
        // Inside, 0.01 m under the +x face (world x is the box's short axis now).
        let (d, g) = o.distance(&Point3::new(1.04, 0.0, 0.0));
        assert!(
            (d + 0.01).abs() < 1e-12 && (g - Vector3::x()).norm() < 1e-12,
            "{d} {g}"
        );
    }
}
