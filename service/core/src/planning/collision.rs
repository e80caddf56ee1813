//! Collision check of the posed hand (method.md §3) against the support plane and the scene cloud,
//! with parry3d shapes: the palm as a box behind the palm surface, each finger in use as two
//! capsules — base → a point off the contact (along its normal tilted 45° toward the palm) →
//! the fingertip resting on the contact. Fingers not in the grasp are taken as flexed out of the way (not checked). For the
//! approach the same chains are pre-shaped 2 cm open along the contact normals.
//!
//! Points count as colliding only when they lie deeper than `tolerance` inside a shape, so that the
//! contacts themselves and sensor noise do not; a configuration collides when at least
//! `min_points` points do (single stray points are noise).

use super::grasp_plan::Pose;
use crate::cloud::{CloudIndex, Plane};
use crate::hand::HandDescription;
use nalgebra::{Point3, Vector3};
use parry3d_f64::math::{Pose3, Rot3, Vector as PVec};
use parry3d_f64::query::PointQuery; // contains_local_point
use parry3d_f64::shape::{Capsule, Cuboid};

/// How far the hand may reach below the support plane (contact with the table surface), m.
pub const PLANE_TOLERANCE: f64 = 0.001;

/// Penetration depth below which a point is touching, not colliding, m.
pub const DEFAULT_TOLERANCE: f64 = 0.003;
/// Points that must collide before a configuration counts as colliding.
pub const DEFAULT_MIN_POINTS: usize = 3;

fn pv(p: &Point3<f64>) -> PVec {
    PVec::new(p.x, p.y, p.z)
}

/// The hand's collision geometry in world coordinates.
#[derive(Debug, Clone)]
pub struct PosedHand {
    palm_pose: Pose3,
    palm: Cuboid,
    /// Palm corners in world coordinates (for the plane test).
    palm_corners: [Point3<f64>; 8],
    capsules: Vec<(Point3<f64>, Point3<f64>, f64)>,
}

/// One finger in the grasp: its index in the hand and the contact it rests on.
#[derive(Debug, Clone, Copy)]
pub struct FingerContact {
    pub finger: usize,
    /// Index of the contact point in the searched cloud.
    pub point: usize,
    pub position: Point3<f64>,
    /// Outward normal of the object at the contact.
    pub normal: Vector3<f64>,
}

/// Direction from a contact back along the finger's last segment: the outward normal tilted 45°
/// toward the palm (fingers reach a contact from the palm's side, never from behind the object).
pub fn distal_direction(normal: &Vector3<f64>, approach: &Vector3<f64>) -> Vector3<f64> {
    (normal - approach).try_normalize(1e-9).unwrap_or(*normal)
}

fn palm_geometry(
    hand: &HandDescription,
    pose: &Pose,
    back_off: f64,
) -> (Pose3, Cuboid, [Point3<f64>; 8]) {
    let g = &hand.geometry;
    let half = Vector3::new(
        g.palm_length / 2.0,
        g.palm_width / 2.0,
        g.palm_thickness / 2.0,
    );
    let iso = pose.isometry();
    let center_local = Point3::new(0.0, 0.0, -half.z - back_off);
    let center = iso * center_local;
    let q = pose.orientation;
    let rot = Rot3::from_xyzw(q.i, q.j, q.k, q.w);
    let palm_pose = Pose3::from_parts(pv(&center), rot);
    let mut corners = [Point3::origin(); 8];
    for (k, c) in corners.iter_mut().enumerate() {
        let s = |b: usize| if k >> b & 1 == 1 { 1.0 } else { -1.0 };
        *c = iso * Point3::new(s(0) * half.x, s(1) * half.y, center_local.z + s(2) * half.z);
    }
    (
        palm_pose,
        Cuboid::new(PVec::new(half.x, half.y, half.z)),
        corners,
    )
}

impl PosedHand {
    /// The hand at the final grasp: palm at `pose` (touching the object when `palm_contact`), the
    /// listed fingers resting on their contacts.
    pub fn at_grasp(
        hand: &HandDescription,
        pose: &Pose,
        fingers: &[FingerContact],
        palm_contact: bool,
    ) -> Self {
        // A palm in contact is backed off by the tolerance so that touching is not colliding.
        let back = if palm_contact { DEFAULT_TOLERANCE } else { 0.0 };
        let (palm_pose, palm, palm_corners) = palm_geometry(hand, pose, back);
        let iso = pose.isometry();
        let r = hand.geometry.finger_width / 2.0;
        let approach = pose.orientation * Vector3::z();
        let capsules = fingers
            .iter()
            .flat_map(|f| {
                let finger = &hand.fingers[f.finger];
                let base = iso * Point3::from(finger.base);
                let tip = f.position + f.normal * r;
                let pre = tip + distal_direction(&f.normal, &approach) * (0.35 * finger.length);
                [(base, pre, r), (pre, tip, r)]
            })
            .collect();
        Self {
            palm_pose,
            palm,
            palm_corners,
            capsules,
        }
    }

    /// The hand pre-shaped for the approach: the grasp's finger chains with each fingertip backed
    /// off `margin` along its contact normal (slightly open around the object, as a hand
    /// approaches before it closes), the whole hand moved by `shift` (e.g. back along the
    /// approach to the pre-grasp).
    pub fn preshaped(
        hand: &HandDescription,
        pose: &Pose,
        fingers: &[FingerContact],
        margin: f64,
        shift: Vector3<f64>,
    ) -> Self {
        let approach = pose.orientation * Vector3::z();
        let opened: Vec<FingerContact> = fingers
            .iter()
            .map(|f| FingerContact {
                position: f.position + distal_direction(&f.normal, &approach) * margin,
                ..*f
            })
            .collect();
        let moved = Pose {
            position: pose.position + shift,
            orientation: pose.orientation,
        };
        let mut h = Self::at_grasp(hand, &moved, &[], false);
        let r = hand.geometry.finger_width / 2.0;
        h.capsules = Self::at_grasp(hand, pose, &opened, false)
            .capsules
            .into_iter()
            .map(|(a, b, _)| (a + shift, b + shift, r))
            .collect();
        h
    }

    /// Least signed distance of the hand geometry to the plane (negative: below it).
    pub fn plane_clearance(&self, plane: &Plane) -> f64 {
        let palm = self
            .palm_corners
            .iter()
            .map(|c| plane.distance(c))
            .fold(f64::INFINITY, f64::min);
        self.capsules
            .iter()
            .flat_map(|(a, b, r)| [plane.distance(a) - r, plane.distance(b) - r])
            .fold(palm, f64::min)
    }

    /// Number of cloud points deeper than `tolerance` inside the hand geometry, counting at most
    /// `limit` (the search only needs to know whether a configuration collides).
    pub fn points_inside(
        &self,
        points: &[Point3<f64>],
        index: &CloudIndex,
        tolerance: f64,
        limit: usize,
    ) -> usize {
        // "Deeper than the tolerance inside a shape" = inside the shape shrunk by the tolerance;
        // points are tested in each shape's local frame (cheap exact tests, no projections).
        let mut seen: Vec<usize> = Vec::new();
        let he = self.palm.half_extents;
        let shrunk = Cuboid::new(PVec::new(
            (he.x - tolerance).max(1e-6),
            (he.y - tolerance).max(1e-6),
            (he.z - tolerance).max(1e-6),
        ));
        let t = self.palm_pose.translation;
        for i in index.within_unsorted(&Point3::new(t.x, t.y, t.z), he.length()) {
            let local = self.palm_pose.inverse_transform_point(pv(&points[i]));
            if shrunk.contains_local_point(local) {
                seen.push(i);
                if seen.len() >= limit {
                    return seen.len();
                }
            }
        }
        for (a, b, r) in &self.capsules {
            let mid = Point3::from((a.coords + b.coords) / 2.0);
            let cap = Capsule::new(pv(a), pv(b), (r - tolerance).max(1e-6));
            for i in index.within_unsorted(&mid, (b - a).norm() / 2.0 + r) {
                if !seen.contains(&i) && cap.contains_local_point(pv(&points[i])) {
                    seen.push(i);
                    if seen.len() >= limit {
                        return seen.len();
                    }
                }
            }
        }
        seen.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hand::HandCatalog;
    use crate::planning::hand_pose::{finger_frame, hand_pose};

    fn grid_plane() -> Vec<Point3<f64>> {
        (0..400)
            .map(|i| {
                Point3::new(
                    (i % 20) as f64 * 0.01 - 0.1,
                    (i / 20) as f64 * 0.01 - 0.1,
                    0.0,
                )
            })
            .collect()
    }

    #[test]
    fn hand_above_the_table_is_clear_and_below_it_is_not() {
        let c = HandCatalog::builtin();
        let hand = c.get("parallel_gripper").unwrap();
        let frame = finger_frame(&Vector3::x(), &[-Vector3::z()]).unwrap();
        let table = Plane::through(&Point3::origin(), Vector3::z());
        let pts = grid_plane();
        let idx = CloudIndex::new(&pts);
        let contacts = |z: f64| {
            [
                FingerContact {
                    finger: 0,
                    point: 0,
                    position: Point3::new(-0.03, 0.0, z),
                    normal: -Vector3::x(),
                },
                FingerContact {
                    finger: 1,
                    point: 1,
                    position: Point3::new(0.03, 0.0, z),
                    normal: Vector3::x(),
                },
            ]
        };
        // Contacts 5 cm up, palm 4 cm above them: clear of the table and its points.
        let pose = hand_pose(&Point3::new(0.0, 0.0, 0.05), &frame, 0.04);
        let posed = PosedHand::at_grasp(hand, &pose, &contacts(0.05), false);
        assert!(posed.plane_clearance(&table) > 0.0);
        assert_eq!(
            posed.points_inside(&pts, &idx, DEFAULT_TOLERANCE, usize::MAX),
            0
        );
        // Contacts 5 mm up: the fingertips (radius 11 mm) reach into the table.
        let pose = hand_pose(&Point3::new(0.0, 0.0, 0.005), &frame, 0.04);
        let posed = PosedHand::at_grasp(hand, &pose, &contacts(0.005), false);
        assert!(posed.plane_clearance(&table) < -0.005);
        assert!(posed.points_inside(&pts, &idx, DEFAULT_TOLERANCE, usize::MAX) > 0);
    }

    #[test]
    fn preshaped_fingers_back_off_and_follow_the_shift() {
        let c = HandCatalog::builtin();
        let hand = c.get("parallel_gripper").unwrap();
        let frame = finger_frame(&Vector3::x(), &[-Vector3::z()]).unwrap();
        let pose = hand_pose(&Point3::new(0.0, 0.0, 0.05), &frame, 0.04);
        let contacts = [
            FingerContact {
                finger: 0,
                point: 0,
                position: Point3::new(-0.03, 0.0, 0.05),
                normal: -Vector3::x(),
            },
            FingerContact {
                finger: 1,
                point: 1,
                position: Point3::new(0.03, 0.0, 0.05),
                normal: Vector3::x(),
            },
        ];
        // At the grasp a point 1 cm outside the right contact is inside the fingertip capsule.
        let probe = vec![Point3::new(0.04, 0.0, 0.05)];
        let idx = CloudIndex::new(&probe);
        let closed = PosedHand::at_grasp(hand, &pose, &contacts, false);
        assert_eq!(closed.points_inside(&probe, &idx, 0.0, usize::MAX), 1);
        // Pre-shaped 2 cm open (along the normal tilted toward the palm), the fingertip has moved;
        // shifted 8 cm up, nothing is near.
        let open = PosedHand::preshaped(hand, &pose, &contacts, 0.02, Vector3::zeros());
        let dir = distal_direction(&Vector3::x(), &-Vector3::z());
        let tip = Point3::new(0.03, 0.0, 0.05) + dir * 0.02 + Vector3::x() * 0.011;
        let idx_tip = CloudIndex::new(std::slice::from_ref(&tip));
        assert_eq!(
            open.points_inside(std::slice::from_ref(&tip), &idx_tip, 0.0, usize::MAX),
            1
        );
        let up = PosedHand::preshaped(hand, &pose, &contacts, 0.02, Vector3::new(0.0, 0.0, 0.08));
        assert_eq!(
            up.points_inside(std::slice::from_ref(&tip), &idx_tip, 0.0, usize::MAX),
            0
        );
        let table = Plane::through(&Point3::origin(), Vector3::z());
        assert!(up.plane_clearance(&table) > closed.plane_clearance(&table));
    }
}
