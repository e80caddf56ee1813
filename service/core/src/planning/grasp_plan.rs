//! What comes out of the planner: the plan g = (C_g, Joint_g, Pose_g) with its contacts,
//! opposition, quality, ranked candidates and statistics (the domain side of a PlanGrasp
//! response).

use super::request::PlannerMode;
use crate::cloud::Plane;
use crate::grasp_type::{GraspType, HandPart};
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Who decided the grasp type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TypeSource {
    /// The caller forced it.
    Request,
    /// The geometric rule on the object's shape and size (no image or no model).
    GeometricRule,
    /// The grasp-type network (perception).
    Model,
}

/// Where the support plane came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlaneSource {
    Request,
    Detected,
    None,
}

/// A hand pose: position and orientation of the hand frame (see `hand::description`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub position: Point3<f64>,
    pub orientation: UnitQuaternion<f64>,
}

impl Pose {
    pub fn isometry(&self) -> Isometry3<f64> {
        Isometry3::from_parts(self.position.coords.into(), self.orientation)
    }

    pub fn from_isometry(iso: &Isometry3<f64>) -> Self {
        Self {
            position: iso.translation.vector.into(),
            orientation: iso.rotation,
        }
    }
}

/// One final contact.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Contact {
    pub position: Point3<f64>,
    /// Outward surface normal at the contact.
    pub normal: Vector3<f64>,
    /// Finger name, or "palm".
    pub finger: String,
    pub part: HandPart,
    /// Index of the contact point in the request's cloud.
    pub point_index: usize,
    /// For a hand with known kinematics: distance between the surface of the touching link (a
    /// finger's or the palm's) at the planned joints and this contact, m. None for parametric
    /// hands.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ik_residual: Option<f64>,
    /// The contact lies on the completed, unseen side (`point_index` is then the visible point
    /// it completes).
    #[serde(default)]
    pub inferred: bool,
    /// For a hand with known kinematics: the body (link) of the model that touches.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub link: Option<String>,
}

/// The pregrasping opposition O^s_{h1-h2}(C_o) (Definition 1, Eq 5.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Opposition {
    pub h1: HandPart,
    pub h2: HandPart,
    pub points: [Point3<f64>; 2],
    pub normals: [Vector3<f64>; 2],
}

/// Quality of the final grasp.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quality {
    /// S, the Grasp Isotropy Index (Eq 5.3).
    pub gii: f64,
    /// R (Eq 5.4).
    pub reachability: f64,
    /// G (Eq 5.5).
    pub attention: f64,
    /// Q = ω_R·R + ω_G·G with the final stage's weights (Eq 5.2).
    pub objective: f64,
    /// Ferrari–Canny ε over linearised soft-finger cones (not part of the objective).
    pub epsilon: f64,
    /// Grasp opening a (m) or polygon area (m²) and palm height h (m) used by R.
    pub aperture_or_area: f64,
    pub palm_height: f64,
    /// The force at the estimated centre of mass the contacts resist in their weakest axis
    /// direction, in units of one contact's normal force (`planning::robustness`): what plans
    /// are ranked by.
    #[serde(default)]
    pub robustness: f64,
    /// The same straight down (gravity), when up is known.
    #[serde(default)]
    pub gravity_resistance: f64,
}

/// One ranked plan of `GraspPlan::candidates`: what a client needs to execute it or fall back.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GraspCandidate {
    pub contacts: Vec<Contact>,
    pub hand_pose: Pose,
    pub pregrasp_pose: Pose,
    pub root_pose: Option<Pose>,
    pub approach: Option<Vector3<f64>>,
    pub joints: Vec<(String, f64)>,
    pub pregrasp_joints: Vec<(String, f64)>,
    pub squeeze_joints: Vec<(String, f64)>,
    pub quality: Quality,
    pub feasible: bool,
    pub infeasible_reason: Option<String>,
}

impl GraspCandidate {
    /// The candidate that a plan itself is.
    pub fn of(plan: &GraspPlan) -> Self {
        Self {
            contacts: plan.contacts.clone(),
            hand_pose: plan.hand_pose,
            pregrasp_pose: plan.pregrasp_pose,
            root_pose: plan.root_pose,
            approach: plan.approach,
            joints: plan.joints.clone(),
            pregrasp_joints: plan.pregrasp_joints.clone(),
            squeeze_joints: plan.squeeze_joints.clone(),
            quality: plan.quality,
            feasible: plan.feasible,
            infeasible_reason: plan.infeasible_reason.clone(),
        }
    }
}

/// Search statistics of one stage.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct StageStats {
    /// |Φ_ĝ|: the number of configurations the stage could choose from.
    pub solution_space: f64,
    /// Candidate points per contact slot (the union of the neighbourhoods).
    pub candidates: usize,
    pub iterations: usize,
    /// Iteration (summed over restarts) at which the returned configuration was first found.
    pub best_iteration: usize,
    pub evaluations: usize,
    pub accepted: usize,
    pub restarts: usize,
    pub feasible_found: bool,
    pub seconds: f64,
}

/// Wall time per step of the plan, seconds.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Timings {
    pub preprocess: f64,
    pub normals: f64,
    pub grasp_type: f64,
    pub stage1: f64,
    pub stage2: f64,
    pub finalize: f64,
    pub total: f64,
}

/// Collision status of the planned hand.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct CollisionReport {
    pub checked: bool,
    /// The posed hand at the final grasp, the pre-grasp and along the approach is clear of the
    /// support plane and the cloud.
    pub clear: bool,
    pub final_points_in_collision: usize,
    pub pregrasp_points_in_collision: usize,
    pub approach_points_in_collision: usize,
    /// Least signed distance of the hand geometry to the support plane (m), when one is known.
    pub min_plane_clearance: Option<f64>,
    /// The same for the final configuration alone (for a hand with known kinematics, its own
    /// collision geometry posed at the planned joints), m.
    #[serde(default)]
    pub final_plane_clearance: Option<f64>,
}

/// The planner's answer: g = (C_g, Joint_g, Pose_g) with the information that led to it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GraspPlan {
    pub hand: String,
    pub grasp_type: GraspType,
    /// The type asked for or detected before mapping to what the hand realises.
    pub requested_type: GraspType,
    pub type_source: TypeSource,
    /// Per-type scores in the order s = 1..6 (one-hot for the geometric rule and forced types).
    pub type_scores: [f64; 6],
    pub attention_point: Point3<f64>,
    pub attention_normal: Vector3<f64>,
    pub opposition: Opposition,
    pub contacts: Vec<Contact>,
    pub hand_pose: Pose,
    pub pregrasp_pose: Pose,
    /// Joint angles by name, when the hand's kinematics are known (empty for parametric hands):
    /// every joint of the model, inside its limits.
    pub joints: Vec<(String, f64)>,
    /// Pose of the model's root frame (MJCF world body / URDF root link) at the planned joints,
    /// when the hand's kinematics are known: where to mount the model to realise `hand_pose`.
    #[serde(default)]
    pub root_pose: Option<Pose>,
    /// With kinematics: the joints of the pre-grasp (the opening the hand approaches with) and
    /// of the squeeze (each contact pressed `squeeze_depth` into the object); `joints` are the
    /// touching joints. Executed in that order: pre-grasp → grasp → squeeze.
    #[serde(default)]
    pub pregrasp_joints: Vec<(String, f64)>,
    #[serde(default)]
    pub squeeze_joints: Vec<(String, f64)>,
    /// Unit direction the hand moves in from `pregrasp_pose` to `hand_pose`.
    #[serde(default)]
    pub approach: Option<Vector3<f64>>,
    /// The best `options.candidates` distinct plans, ranked (the first is this plan).
    #[serde(default)]
    pub candidates: Vec<GraspCandidate>,
    pub quality: Quality,
    /// Whether S ≥ ε and every hard constraint held. When false, `infeasible_reason` says why and
    /// the plan is the best configuration found.
    pub feasible: bool,
    pub infeasible_reason: Option<String>,
    pub stage1: StageStats,
    pub stage2: StageStats,
    pub timings: Timings,
    pub collision: CollisionReport,
    pub support_plane: Option<Plane>,
    pub plane_source: PlaneSource,
    pub points_used: usize,
    pub mode: PlannerMode,
    pub seed: u64,
    pub warnings: Vec<String>,
    /// What perception found, when the input was an RGB-D frame.
    #[serde(default)]
    pub perception: Option<crate::perception::PerceptionReport>,
    /// The candidates in the layout of `moveit_msgs/Grasp`, when asked for
    /// ([`super::moveit_layout`]).
    #[serde(default)]
    pub moveit_grasps: Vec<super::moveit_grasp::MoveItGrasp>,
    /// The plan as a binary glTF scene, when asked for (`crate::plan_scene`).
    #[serde(skip)]
    pub scene_glb: Option<Vec<u8>>,
    /// What the learned-quality search found (`options.mode = learned_quality`, ch. 3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub learned_quality: Option<LearnedQuality>,
}

/// The learned-quality search's result (dissertation §3.2.3): the network's P(success) of the
/// executed grasp, the Gaussian process's posterior there, and what the search cost.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearnedQuality {
    /// P(y = 1 | I, g) of Eq 3.1 for the grasp the plan executes.
    pub probability: f64,
    /// The surrogate's posterior (Eq 3.5), mean and standard deviation, at the grasp the search
    /// rated best — the executed one unless graspd found that one infeasible and realised a
    /// lower-rated one.
    pub posterior_mean: f64,
    pub posterior_std: f64,
    /// Network evaluations the search made, and the candidates it could choose among.
    pub network_calls: usize,
    pub candidates: usize,
}
