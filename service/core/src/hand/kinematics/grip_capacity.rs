//! How hard a hand can press at a point (issue 15): the largest force its actuators hold there,
//! from each joint's effort limit (`Joint::effort`, read from the MJCF's actuators or the URDF's
//! `<limit effort>`).
//!
//! A force f at point p loads every joint on the path from the root to p's body: a hinge with
//! torque |(p − a) × f · axis| ≤ |f|·r (r: p's distance from the axis), a slide with at most
//! |f|. Whatever the force's direction, the joints hold it while |f| ≤ min_j effort_j / r_j
//! (min_j effort_j for a slide): the capacity. It counts every limited joint on the path —
//! a finger's flexion joints and a wrist's alike — and ignores joints without a known limit
//! (passive linkage joints, unlimited servos).
//!
//! A fingertip pushed far from its knuckles is weak; a proximal link close to them, or a palm
//! backed by the wrist, is strong: the reason a power grasp holds what a fingertip grasp drops.

use super::forward_kinematics::ForwardKinematics;
use super::hand_model::KinematicHand;
use super::kinematic_tree::JointKind;
use nalgebra::Point3;

/// Shortest lever counted, m: a point on (or next to) a hinge's axis does not make it infinitely
/// strong.
const MIN_LEVER: f64 = 0.005;

/// Where a point's capacity comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GripCapacity {
    /// The force (N) the limited joints on the path hold at the point.
    Limited(f64),
    /// Joints move the point but none has a known limit.
    Unknown,
    /// No joint moves the point (a body fixed to the root: the palm of a hand without a wrist);
    /// what holds it is the arm.
    Fixed,
}

impl KinematicHand {
    /// The capacity at `point` (in the tree's root frame, where `fk` poses the joints) of body
    /// `body` (module doc).
    pub fn grip_capacity(
        &self,
        fk: &ForwardKinematics,
        body: usize,
        point: &Point3<f64>,
    ) -> GripCapacity {
        let mut moved = false;
        let mut least = f64::INFINITY;
        for (j, joint) in self.tree.joints.iter().enumerate() {
            if !self.tree.joint_moves(j, body) {
                continue;
            }
            moved = true;
            let Some(effort) = joint.effort else { continue };
            let force = match joint.kind {
                JointKind::Hinge => {
                    let (anchor, axis) = &fk.joint_axes[j];
                    let r = (point - anchor).cross(axis).norm();
                    effort / r.max(MIN_LEVER)
                }
                JointKind::Slide => effort,
            };
            least = least.min(force);
        }
        match (moved, least.is_finite()) {
            (_, true) => GripCapacity::Limited(least),
            (true, false) => GripCapacity::Unknown,
            (false, false) => GripCapacity::Fixed,
        }
    }

    /// The fingertip grip: the median over fingers of the capacity at the fingertip's contact
    /// point, the hand at its mid configuration — the force a typical fingertip presses with;
    /// `None` when no fingertip has a limited joint.
    pub fn fingertip_grip(&self) -> Option<f64> {
        let q = self.tree.mid_configuration();
        let fk = self.tree.forward(&q).ok()?;
        let mut tips: Vec<f64> = self
            .fingers
            .iter()
            .filter_map(|f| {
                let p = fk.body_poses[f.tip] * f.tip_point;
                match self.grip_capacity(&fk, f.tip, &p) {
                    GripCapacity::Limited(c) => Some(c),
                    _ => None,
                }
            })
            .collect();
        if tips.is_empty() {
            return None;
        }
        tips.sort_by(f64::total_cmp);
        Some(tips[tips.len() / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Finger a: a knuckle (2 N·m) at the palm and a middle joint (0.5 N·m) 5 cm down, its tip
    /// 3 cm further; finger b without actuators.
    const HAND: &str = r#"<mujoco><worldbody><body name="palm">
        <geom type="box" size="0.02 0.02 0.005"/>
        <body name="a1"><joint name="ja1" axis="0 1 0" range="0 1.5"/>
          <geom type="capsule" fromto="0 0 0 0 0 -0.05" size="0.008"/>
          <body name="a2" pos="0 0 -0.05"><joint name="ja2" axis="0 1 0" range="0 1.5"/>
            <body name="a_tip" pos="0 0 -0.03"><geom type="sphere" size="0.008"/></body>
          </body></body>
        <body name="b1" pos="0.1 0 0"><joint name="jb1" axis="0 1 0" range="0 1.5"/>
          <body name="b_tip" pos="0 0 -0.05"><geom type="sphere" size="0.008"/></body>
        </body></body></worldbody>
      <actuator><motor joint="ja1" forcerange="-2 2"/><motor joint="ja2" forcerange="-0.5 0.5"/>
      </actuator></mujoco>"#;

    /// Hand-computed: at the tip the middle joint gives out first (0.5 N·m / 3 cm = 16.7 N,
    /// the knuckle 2 N·m / 8 cm = 25 N); 2 cm below the knuckle only it counts (100 N); the
    /// palm is fixed; finger b's joint has no limit.
    #[test]
    fn capacity_is_the_weakest_joint_over_its_lever() {
        let hand = KinematicHand::from_mjcf_str(HAND, ".").unwrap();
        let t = &hand.tree;
        let fk = t.forward(&vec![0.0; t.joints.len()]).unwrap();
        let body = |n: &str| t.body_index(n).unwrap();
        let cap =
            |b: &str, z: f64, x: f64| hand.grip_capacity(&fk, body(b), &Point3::new(x, 0.0, z));
        match cap("a_tip", -0.08, 0.0) {
            GripCapacity::Limited(f) => assert!((f - 0.5 / 0.03).abs() < 1e-9, "{f}"),
            c => panic!("{c:?}"),
        }
        assert_eq!(cap("a1", -0.02, 0.0), GripCapacity::Limited(100.0));
        assert_eq!(cap("palm", 0.0, 0.0), GripCapacity::Fixed);
        assert_eq!(cap("b_tip", -0.05, 0.1), GripCapacity::Unknown);
        // The fingertip grip is finger a's (the only limited one), at the mid configuration.
        let fk = t.forward(&t.mid_configuration()).unwrap();
        let f = hand
            .fingers
            .iter()
            .find(|f| f.tip == body("a_tip"))
            .unwrap();
        let tip = fk.body_poses[f.tip] * f.tip_point;
        assert_eq!(
            hand.fingertip_grip(),
            match hand.grip_capacity(&fk, f.tip, &tip) {
                GripCapacity::Limited(c) => Some(c),
                _ => None,
            }
        );
    }
}
