//! The extrinsic reward of the rotation tasks (dissertation §7.5.1, Eq 7.12) and the success it
//! defines: the object's orientation within 0.1 rad of the target.

use nalgebra::UnitQuaternion;

/// Orientations closer than this to the target count as reached (Eq 7.12: d_ext > −0.1), rad.
pub const SUCCESS_ANGLE: f64 = 0.1;

/// q_curr ⊖ q_target: the angle of the rotation that takes one orientation to the other, rad,
/// in [0, π] (q and −q are the same orientation).
pub fn orientation_difference(current: &UnitQuaternion<f64>, target: &UnitQuaternion<f64>) -> f64 {
    current.angle_to(target)
}

/// r_ext of Eq 7.12 for d_ext = −(q_curr ⊖ q_target): 50 once within 0.1 rad, falling linearly
/// from 0 to −1 over d_ext ∈ [−5, −0.1], −10 beyond. An angle never exceeds π, so the last
/// branch is where the object has no orientation to compare: it fell out of the hand
/// ([`dropped_reward`]).
pub fn extrinsic_reward(d_ext: f64) -> f64 {
    if d_ext > -SUCCESS_ANGLE {
        50.0
    } else if d_ext >= -5.0 {
        -(d_ext - (-SUCCESS_ANGLE)) / (-5.0 - (-SUCCESS_ANGLE))
    } else {
        -10.0
    }
}

/// r_ext of every step once the object has left the hand: Eq 7.12's "otherwise" (−10).
pub fn dropped_reward() -> f64 {
    extrinsic_reward(f64::NEG_INFINITY)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn eq_7_12_by_hand() {
        assert_eq!(extrinsic_reward(-0.05), 50.0);
        assert_eq!(extrinsic_reward(0.0), 50.0);
        // The ramp: 0 at −0.1, −1 at −5, −0.5 half way (−2.55).
        assert!(extrinsic_reward(-0.1).abs() < 1e-12);
        assert!((extrinsic_reward(-2.55) + 0.5).abs() < 1e-12);
        assert!((extrinsic_reward(-5.0) + 1.0).abs() < 1e-12);
        // −(−1 + 0.1) / (−5 + 0.1) = −0.9 / 4.9.
        assert!((extrinsic_reward(-1.0) + 0.9 / 4.9).abs() < 1e-12);
        assert_eq!(extrinsic_reward(-5.01), -10.0);
        assert_eq!(dropped_reward(), -10.0);
    }

    #[test]
    fn the_difference_is_the_rotation_angle_whatever_the_quaternion_sign() {
        let a = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.3);
        let b = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), -0.5);
        assert!((orientation_difference(&a, &b) - 0.8).abs() < 1e-12);
        // −q is the same orientation as q.
        let minus_b = UnitQuaternion::new_unchecked(-b.into_inner());
        assert!((orientation_difference(&a, &minus_b) - 0.8).abs() < 1e-12);
        // Past π the short way round: 3.5 rad one way is 2π − 3.5 the other.
        let c = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 3.5);
        let d = UnitQuaternion::identity();
        assert!((orientation_difference(&c, &d) - (2.0 * std::f64::consts::PI - 3.5)).abs() < 1e-9);
    }
}
