//! The hand pose from the contacts (method.md §3): approach along −n_att, closing direction from
//! the h1 side to the h2 side, palm at the height h that R (Eq 5.4) assumed, and a pre-grasp pose
//! backed off along the approach.

use super::grasp_plan::Pose;
use super::object_shape::ObjectShape;
use nalgebra::{Matrix3, Point3, Rotation3, UnitQuaternion, Vector3};

/// Orthonormal hand frame: x closing (h1 → h2), y across the fingers, z approach (palm → object).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandFrame {
    pub x: Vector3<f64>,
    pub y: Vector3<f64>,
    pub z: Vector3<f64>,
}

impl HandFrame {
    pub fn rotation(&self) -> UnitQuaternion<f64> {
        let m = Matrix3::from_columns(&[self.x, self.y, self.z]);
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m))
    }
}

/// Frame for finger–finger oppositions (TT–FT, TS–FS): x along `closing`, z the first of
/// `approach_prefs` that is not nearly parallel to x, made perpendicular to it. None when every
/// preference is (nearly) parallel to the closing direction.
pub fn finger_frame(closing: &Vector3<f64>, approach_prefs: &[Vector3<f64>]) -> Option<HandFrame> {
    let x = closing.try_normalize(1e-12)?;
    for a in approach_prefs {
        let perp = a - x * a.dot(&x);
        if perp.norm() > 0.3 * a.norm().max(1e-12) {
            let z = perp.normalize();
            return Some(HandFrame {
                x,
                y: z.cross(&x),
                z,
            });
        }
    }
    None
}

/// Frame for the palm opposition P–FS (small_wrap): z from the palm point toward the finger side,
/// y (across the fingers) along `object_axis` made perpendicular to z, so the fingers wrap around
/// the object's long axis.
pub fn palm_frame(palm_to_fingers: &Vector3<f64>, object_axis: &Vector3<f64>) -> Option<HandFrame> {
    let z = palm_to_fingers.try_normalize(1e-12)?;
    let mut y = object_axis - z * object_axis.dot(&z);
    if y.norm() < 0.2 {
        let other = if z.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        y = other - z * other.dot(&z);
    }
    let y = y.normalize();
    Some(HandFrame {
        x: y.cross(&z),
        y,
        z,
    })
}

/// Palm height h (Eq 5.4): the palm stands on −z of the grasp centre `c`, clear of the object by
/// `clearance` (0 for a palm contact, which touches), and never closer than the object reaches.
pub fn palm_height(shape: &ObjectShape, c: &Point3<f64>, frame: &HandFrame, clearance: f64) -> f64 {
    shape.reach(c, &-frame.z).max(0.0) + clearance
}

/// Pose of the hand frame with the palm at height `h` behind the grasp centre.
pub fn hand_pose(c: &Point3<f64>, frame: &HandFrame, h: f64) -> Pose {
    Pose {
        position: c - frame.z * h,
        orientation: frame.rotation(),
    }
}

/// The pre-grasp pose: the grasp pose backed off by `distance` along the approach.
pub fn pregrasp_pose(grasp: &Pose, frame: &HandFrame, distance: f64) -> Pose {
    Pose {
        position: grasp.position - frame.z * distance,
        orientation: grasp.orientation,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finger_frame_is_right_handed_and_follows_preferences() {
        let f = finger_frame(
            &Vector3::new(2.0, 0.0, 0.0),
            &[Vector3::new(0.0, 0.1, -1.0)],
        )
        .unwrap();
        assert!((f.x - Vector3::x()).norm() < 1e-12);
        assert!(f.z.z < -0.99);
        assert!((f.x.cross(&f.y) - f.z).norm() < 1e-12);
        // Preference parallel to the closing line → next one.
        let g = finger_frame(&Vector3::x(), &[Vector3::x(), Vector3::z()]).unwrap();
        assert!((g.z - Vector3::z()).norm() < 1e-12);
        assert!(finger_frame(&Vector3::x(), &[Vector3::x()]).is_none());
        let q = f.rotation();
        assert!((q * Vector3::z() - f.z).norm() < 1e-9);
    }

    #[test]
    fn palm_is_placed_clear_of_the_object() {
        // A 6 cm cube centred at the origin, approached from +z (hand above, z pointing down).
        let mut pts = Vec::new();
        for i in 0..=6 {
            for j in 0..=6 {
                for k in 0..=6 {
                    pts.push(Point3::new(
                        -0.03 + 0.01 * i as f64,
                        -0.03 + 0.01 * j as f64,
                        -0.03 + 0.01 * k as f64,
                    ));
                }
            }
        }
        let shape = ObjectShape::of(&pts);
        let frame = finger_frame(&Vector3::x(), &[-Vector3::z()]).unwrap();
        let h = palm_height(&shape, &Point3::origin(), &frame, 0.01);
        assert!((h - 0.04).abs() < 1e-9);
        let pose = hand_pose(&Point3::origin(), &frame, h);
        assert!((pose.position - Point3::new(0.0, 0.0, 0.04)).norm() < 1e-9);
        let pre = pregrasp_pose(&pose, &frame, 0.08);
        assert!((pre.position.z - 0.12).abs() < 1e-9);
    }

    #[test]
    fn palm_frame_wraps_the_long_axis() {
        let f = palm_frame(&Vector3::new(0.0, 0.0, -1.0), &Vector3::x()).unwrap();
        assert!((f.y - Vector3::x()).norm() < 1e-12);
        assert!((f.x.cross(&f.y) - f.z).norm() < 1e-12);
    }
}
