//! Joint_g of the grasp g = (C_g, Joint_g, Pose_g) for a hand with known kinematics (issue 6 §2):
//! the planned contacts become joint angles by damped least squares (Eq 3.11 form) jointly with a
//! bounded correction of the planned hand pose, and the posed configuration is checked against the
//! support plane and the scene cloud with the hand's own collision geometry.
//!
//! - **Targets**: each finger contact's fingertip contact point (the regional centre of the tip,
//!   see `hand::kinematics::hand_model`) is aimed at the object point pushed out along the
//!   surface normal by the pad's half thickness (half the smallest extent of the tip's collision
//!   geometry), so that the pad touches the surface instead of sinking into it. A palm contact
//!   (small_wrap) has no finger target: the palm pose is the plan's.
//! - **Start**: the planned palm height comes from the parametric rule (the palm just clear of
//!   the object), while a real hand's pads work at their own distance from the palm. Among
//!   [`START_SAMPLES`] seeded workspace samples (and the open pose), the one whose contact points
//!   best match the targets after a common shift t of the hand is taken, with t = the mean
//!   offset, its lateral part bounded by the palm freedom and its approach part only backward
//!   (0 ≤ t_z ≤ 15 cm: backing off along the approach moves the hand away from the object).
//!   The hand frame is shifted by t.
//! - **Solve**: [`KinematicHand::inverse_with_palm`] from that sample in the shifted hand frame;
//!   the palm may move up to [`PalmFreedom`]'s bounds more. A contact set is **reachable** when
//!   every residual is at most [`REACH_TOLERANCE`] (5 mm): the hard constraint of stage 2.
//! - **Fingers not in the grasp** are set, each as a whole, to whichever of four postures (open,
//!   all joints at their lower limits, at their upper limits, at mid range) leaves the posed hand
//!   clearest of the support plane and the cloud (the parametric model leaves them out, "flexed
//!   out of the way"; here they are posed and checked).
//! - **Collision**: the posed convex pieces against the support plane (least signed distance,
//!   `min_plane_clearance`) and the object points (points deeper than
//!   [`collision::DEFAULT_TOLERANCE`] inside a piece).

use super::collision;
use super::types::Pose;
use crate::cloud::Plane;
use crate::error::FieldError;
use crate::hand::HandDescription;
use crate::hand::kinematics::{
    ContactTarget, HandCollision, IkOptions, KinematicHand, PalmFreedom,
};
use nalgebra::{Point3, Vector3};

/// Largest IK residual of a reachable contact, m.
pub const REACH_TOLERANCE: f64 = 0.005;

/// A hand's kinematics prepared for planning: the tree read as a hand, its collision pieces and
/// the solver settings. Built once per hand (catalog entry), shared by every plan.
#[derive(Debug, Clone)]
pub struct KinematicModel {
    pub hand: KinematicHand,
    pub collision: HandCollision,
    /// Per kinematic finger: pad half thickness, m (target offset along the contact normal).
    pub pad_offsets: Vec<f64>,
    pub ik: IkOptions,
    pub palm: PalmFreedom,
    /// The open pose (the postures of fingers not in the grasp start from it).
    pub open: Vec<f64>,
    /// Seeded workspace samples: joint vector and every finger's contact point (hand frame).
    workspace: Vec<(Vec<f64>, Vec<Point3<f64>>)>,
}

/// Workspace samples kept for the IK's start ([`KinematicModel::solve`]).
pub const START_SAMPLES: usize = 512;
/// Seed of those samples.
const START_SEED: u64 = 0x5a11_0c0d;
/// Farthest the hand is backed off along its approach before the IK, m.
const MAX_BACK_OFF: f64 = 0.15;

/// How hard [`KinematicModel::solve`] tries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effort {
    /// Inside the search (every new optimum): one start, no restarts; fingers not in the grasp
    /// stay open; collision counting stops at the noise allowance.
    Search,
    /// The final configuration: restarts, the four postures of the free fingers, full counts and
    /// the pre-grasp and approach poses.
    Final,
}

/// One finger contact to reach, in the world (the plan's frame).
#[derive(Debug, Clone, PartialEq)]
pub struct FingerTarget {
    /// Finger name (as in the hand description).
    pub finger: String,
    pub position: Point3<f64>,
    /// Outward surface normal at the contact.
    pub normal: Vector3<f64>,
}

/// The joint configuration of a planned grasp.
#[derive(Debug, Clone, PartialEq)]
pub struct JointConfiguration {
    /// Joint angles by joint name (rad, or m for slides), every joint of the tree, inside limits.
    pub joints: Vec<(String, f64)>,
    /// Per finger target, in the order given: distance of the reached contact point from its
    /// target, m.
    pub residuals: Vec<f64>,
    /// Every residual ≤ [`REACH_TOLERANCE`].
    pub reachable: bool,
    /// The planned hand pose after the palm correction.
    pub hand_pose: Pose,
    /// The model's root frame (MJCF world body / URDF root link) in the world at the planned
    /// joints and hand pose: where a robot or simulator mounts the model.
    pub root_pose: Pose,
    /// Least signed distance of the posed hand to the support plane, m (None without a plane).
    pub plane_clearance: Option<f64>,
    /// Object points deeper than the tolerance inside the posed hand.
    pub points_in_collision: usize,
    /// The same for the hand at the planned joints at the pre-grasp pose and halfway along the
    /// approach (0 when not checked: [`Effort::Search`]).
    pub pregrasp_points_in_collision: usize,
    pub approach_points_in_collision: usize,
    /// Least plane clearance over the pre-grasp and approach poses, m.
    pub approach_plane_clearance: Option<f64>,
    /// Largest residual, m.
    pub worst_residual: f64,
}

impl JointConfiguration {
    /// The final configuration is clear of the plane (1 mm tolerance) and of the cloud (fewer
    /// points inside than the noise allowance).
    pub fn clear(&self) -> bool {
        self.plane_clearance
            .is_none_or(|c| c >= -super::search_context::PLANE_TOLERANCE)
            && self.points_in_collision < collision::DEFAULT_MIN_POINTS
    }

    /// The pre-grasp and approach poses are clear too.
    pub fn approach_clear(&self) -> bool {
        self.approach_plane_clearance
            .is_none_or(|c| c >= -super::search_context::PLANE_TOLERANCE)
            && self.pregrasp_points_in_collision < collision::DEFAULT_MIN_POINTS
            && self.approach_points_in_collision < collision::DEFAULT_MIN_POINTS
    }

    /// What collides, in words.
    pub fn describe_collision(&self) -> String {
        let mut parts = Vec::new();
        if let Some(c) = self
            .plane_clearance
            .filter(|c| *c < -super::search_context::PLANE_TOLERANCE)
        {
            parts.push(format!("{:.1} mm below the support plane", -c * 1e3));
        }
        for (what, n) in [
            ("final grasp", self.points_in_collision),
            ("pre-grasp", self.pregrasp_points_in_collision),
            ("approach", self.approach_points_in_collision),
        ] {
            if n >= collision::DEFAULT_MIN_POINTS {
                parts.push(format!("{n} cloud points inside the hand at the {what}"));
            }
        }
        if let Some(c) = self
            .approach_plane_clearance
            .filter(|c| *c < -super::search_context::PLANE_TOLERANCE)
        {
            parts.push(format!(
                "{:.1} mm below the support plane on the approach",
                -c * 1e3
            ));
        }
        parts.join("; ")
    }
}

impl KinematicModel {
    /// Prepares a hand: collision pieces, pad offsets and the open pose.
    pub fn new(hand: KinematicHand) -> Result<Self, FieldError> {
        let collision = hand.collision_model()?;
        let pad_offsets = hand
            .fingers
            .iter()
            .map(|f| {
                let bounds =
                    crate::hand::kinematics::hand_model::collision_bounds(&hand.tree, f.tip)
                        .or_else(|| {
                            let p = hand.tree.bodies[f.tip].parent?;
                            crate::hand::kinematics::hand_model::collision_bounds(&hand.tree, p)
                        });
                bounds.map_or(0.0, |(lo, hi)| {
                    let e = hi - lo;
                    0.5 * e.x.min(e.y).min(e.z)
                })
            })
            .collect();
        let open = hand.tree.home_configuration();
        let mut workspace = Vec::with_capacity(START_SAMPLES + 1);
        for q in std::iter::once(open.clone())
            .chain(hand.sample_configurations(START_SAMPLES, START_SEED))
        {
            let tips = hand.fingertips(&q)?;
            workspace.push((q, tips));
        }
        Ok(Self {
            workspace,
            collision,
            pad_offsets,
            ik: IkOptions {
                tolerance: REACH_TOLERANCE,
                restarts: 4,
                max_iterations: 60,
                ..IkOptions::default()
            },
            palm: PalmFreedom::default(),
            open,
            hand,
        })
    }

    /// The validated hand description derived from the kinematics.
    pub fn describe(&self) -> Result<HandDescription, FieldError> {
        self.hand.describe()
    }

    /// Joints for the finger targets with the hand frame planned at `hand_pose`; `points` are the
    /// object points of the scene, `plane` the support plane.
    /// `pregrasp_distance` backs the pre-grasp pose off along the approach ([`Effort::Final`]).
    pub fn solve(
        &self,
        targets: &[FingerTarget],
        hand_pose: &Pose,
        plane: Option<&Plane>,
        points: &[Point3<f64>],
        effort: Effort,
        pregrasp_distance: f64,
    ) -> Result<JointConfiguration, FieldError> {
        let final_effort = effort == Effort::Final;
        let limit = if final_effort {
            usize::MAX
        } else {
            collision::DEFAULT_MIN_POINTS
        };
        let search_opts;
        let opts = if final_effort {
            &self.ik
        } else {
            search_opts = IkOptions {
                restarts: 0,
                ..self.ik.clone()
            };
            &search_opts
        };
        let to_hand = hand_pose.isometry().inverse();
        let mut ik_targets = Vec::with_capacity(targets.len());
        for (i, t) in targets.iter().enumerate() {
            let finger = self.hand.finger_index(&t.finger).ok_or_else(|| {
                FieldError::new(
                    format!("contacts[{i}].finger"),
                    format!("the hand's kinematics have no finger '{}'", t.finger),
                )
            })?;
            let surface = t.position + t.normal * self.pad_offsets[finger];
            ik_targets.push(ContactTarget {
                finger,
                position: to_hand * surface,
            });
        }
        // The start: the workspace sample and hand shift that fit the targets best.
        let lateral = self.palm.max_translation;
        let mut start: Option<(f64, usize, Vector3<f64>)> = None;
        for (k, (_, tips)) in self.workspace.iter().enumerate() {
            let n = ik_targets.len().max(1) as f64;
            let mean = ik_targets
                .iter()
                .fold(Vector3::zeros(), |a, t| a + (tips[t.finger] - t.position))
                / n;
            let shift = Vector3::new(
                mean.x.clamp(-lateral, lateral),
                mean.y.clamp(-lateral, lateral),
                mean.z.clamp(0.0, MAX_BACK_OFF),
            );
            let cost: f64 = ik_targets
                .iter()
                .map(|t| (tips[t.finger] - t.position - shift).norm_squared())
                .sum();
            if start.as_ref().is_none_or(|s| cost < s.0) {
                start = Some((cost, k, shift));
            }
        }
        let (_, k, shift) = start.expect("the open pose is a sample");
        let shifted = hand_pose.isometry() * nalgebra::Translation3::from(-shift);
        for t in &mut ik_targets {
            t.position += shift;
        }
        let ik =
            self.hand
                .inverse_with_palm(&ik_targets, &self.workspace[k].0, opts, &self.palm)?;
        let pose_iso = shifted * ik.palm_correction;
        let corrected = Pose {
            position: Point3::from(pose_iso.translation.vector),
            orientation: pose_iso.rotation,
        };
        // Fingers not in the grasp: the posture that leaves the hand clearest.
        let used: Vec<usize> = ik_targets.iter().map(|t| t.finger).collect();
        let free: Vec<usize> = (0..self.hand.fingers.len())
            .filter(|f| !used.contains(f))
            .collect();
        let mut best: Option<(Vec<f64>, (usize, f64))> = None;
        let postures = if final_effort { 4 } else { 1 };
        for posture in 0..postures {
            let mut q = ik.joints.clone();
            for &f in &free {
                for &j in &self.hand.fingers[f].joints {
                    if used
                        .iter()
                        .any(|&u| self.hand.fingers[u].joints.contains(&j))
                    {
                        continue; // shared with a finger in the grasp
                    }
                    let (lo, hi) = self.hand.tree.joints[j].limits();
                    q[j] = match posture {
                        0 => self.open[j],
                        1 => lo,
                        2 => hi,
                        _ => 0.5 * (lo + hi),
                    };
                }
            }
            let posed = self.collision.posed(&self.hand, &q, &pose_iso)?;
            let clearance = plane.map_or(f64::INFINITY, |pl| posed.plane_clearance(pl));
            let inside = posed.points_inside(points, collision::DEFAULT_TOLERANCE, limit);
            // Fewer points inside first, then more clearance (capped: beyond 1 cm it is clear).
            let key = (inside, -clearance.min(0.01));
            if best
                .as_ref()
                .is_none_or(|(_, b)| key.0 < b.0 || (key.0 == b.0 && key.1 < b.1))
            {
                best = Some((q, key));
            }
            if free.is_empty() {
                break;
            }
        }
        let (q, (inside, _)) = best.expect("at least one posture");
        let posed = self.collision.posed(&self.hand, &q, &pose_iso)?;
        let plane_clearance = plane.map(|pl| posed.plane_clearance(pl));
        // World ← hand frame ← root.
        let root_iso = pose_iso * self.hand.hand_frame_in_root(&q)?.inverse();
        let root_pose = Pose {
            position: Point3::from(root_iso.translation.vector),
            orientation: root_iso.rotation,
        };
        let worst_residual = ik.residuals.iter().cloned().fold(0.0, f64::max);
        let (mut pre_points, mut app_points, mut app_clearance) = (0, 0, None);
        if final_effort {
            let approach = pose_iso.rotation * Vector3::z();
            for (k, back) in [(0, pregrasp_distance), (1, 0.5 * pregrasp_distance)] {
                let at = nalgebra::Translation3::from(-approach * back) * pose_iso;
                let posed = self.collision.posed(&self.hand, &q, &at)?;
                let n = posed.points_inside(points, collision::DEFAULT_TOLERANCE, usize::MAX);
                if k == 0 {
                    pre_points = n;
                } else {
                    app_points = n;
                }
                if let Some(pl) = plane {
                    let c = posed.plane_clearance(pl);
                    app_clearance = Some(app_clearance.map_or(c, |a: f64| a.min(c)));
                }
            }
        }
        Ok(JointConfiguration {
            joints: self
                .hand
                .tree
                .joints
                .iter()
                .zip(&q)
                .map(|(j, v)| (j.name.clone(), *v))
                .collect(),
            reachable: ik.reachable,
            residuals: ik.residuals,
            hand_pose: corrected,
            root_pose,
            plane_clearance,
            points_in_collision: inside,
            pregrasp_points_in_collision: pre_points,
            approach_points_in_collision: app_points,
            approach_plane_clearance: app_clearance,
            worst_residual,
        })
    }
}
