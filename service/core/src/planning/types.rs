//! What goes into the planner and what comes out (the domain side of PlanGrasp).

use crate::cloud::Plane;
use crate::grasp_type::{GraspType, HandPart};
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Dual-stage (the method) or the "without opposition" ablation of Table 5.1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlannerMode {
    #[default]
    DualStage,
    /// Skip stage 1 and search the m contacts directly over the whole cloud.
    WithoutOpposition,
}

impl PlannerMode {
    /// The snake_case name used in the API.
    pub fn name(self) -> &'static str {
        match self {
            PlannerMode::DualStage => "dual_stage",
            PlannerMode::WithoutOpposition => "without_opposition",
        }
    }
}

/// Planner parameters. Defaults are the dissertation's where it gives them (ε, μ, weights) and
/// documented choices where it does not (method.md §3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlannerOptions {
    /// RNG seed: the same request and seed give the same plan.
    pub seed: u64,
    pub mode: PlannerMode,
    /// ε, lower bound on S (Eq 5.2).
    pub epsilon: f64,
    /// Friction coefficient μ.
    pub friction: f64,
    /// Torsion coefficient γ of the soft-finger grasp matrix (spread-normalised units).
    pub torsion_gamma: f64,
    /// (ω_R, ω_G) at stage 1 and at stage 2 (Eq 5.2).
    pub stage1_weights: [f64; 2],
    pub stage2_weights: [f64; 2],
    /// Iterations per stage = clamp(iteration_fraction · |Φ|, min_iterations, max_iterations).
    /// The text uses 10 % of the candidates with no cap.
    pub iteration_fraction: f64,
    pub min_iterations: usize,
    pub max_iterations: usize,
    /// Stop a stage after this many iterations without a better feasible configuration.
    pub patience: usize,
    /// Bounded widenings of the neighbourhoods when a stage finds nothing feasible.
    pub restarts: usize,
    /// Stage-1 neighbourhood radius λ₁ (m); default 0.6·a_max, bounded by the object's extent.
    pub lambda1: Option<f64>,
    /// Stage-2 neighbourhood radius λ₂ around each contact's target (m); default max(1.5 cm,
    /// finger width).
    pub lambda2: Option<f64>,
    /// Stage-1 candidates: Φ(p_att) thinned to at most this many spatially even points, so the
    /// opposition space has the method's size whatever the cloud's density (the dissertation's
    /// clouds had 120 points).
    pub opposition_candidates: usize,
    /// Stage-2 candidates per contact: Φ(target, λ₂) thinned likewise.
    pub contact_candidates: usize,
    /// k of the k-NN PCA normals.
    pub normals_k: usize,
    /// Back-off of the pre-grasp pose along the approach, m.
    pub pregrasp_distance: f64,
    /// Friction-cone edges of the Ferrari–Canny figure.
    pub friction_cone_edges: usize,
    /// Reject candidates whose posed hand collides with the support plane or the cloud.
    pub check_collisions: bool,
    /// Find and remove a support plane in the cloud when none is given.
    pub detect_support_plane: bool,
    /// Largest distance of the grasp centre from the object's estimated centre, perpendicular to
    /// the approach, as a fraction of the object's radius (S ignores where the mass is).
    pub max_center_offset: f64,
    /// Complete a single view's unseen side by symmetry (`cloud::completion`) when the
    /// viewpoint and the up direction are known.
    pub complete_unseen: bool,
    /// Plans returned in `candidates`: the best this many distinct ones, ranked.
    pub candidates: usize,
    /// Hand with kinematics: how far the squeeze presses each contact into the object along its
    /// normal, m.
    pub squeeze_depth: f64,
    /// Hand with kinematics: most candidate configurations judged (placed, closed, squeezed);
    /// while none is feasible the search goes on, up to three times as many.
    pub final_candidates: usize,
}

impl Default for PlannerOptions {
    fn default() -> Self {
        Self {
            seed: 0,
            mode: PlannerMode::DualStage,
            epsilon: 0.7,
            friction: 0.6,
            torsion_gamma: 1.0,
            stage1_weights: [0.3, 0.7],
            stage2_weights: [0.7, 0.3],
            iteration_fraction: 0.1,
            min_iterations: 100,
            max_iterations: 1200,
            patience: 250,
            restarts: 2,
            lambda1: None,
            lambda2: None,
            opposition_candidates: 128,
            contact_candidates: 16,
            normals_k: 16,
            pregrasp_distance: 0.08,
            friction_cone_edges: 8,
            check_collisions: true,
            detect_support_plane: true,
            max_center_offset: 0.6,
            complete_unseen: true,
            candidates: 1,
            squeeze_depth: 0.01,
            final_candidates: 16,
        }
    }
}

/// What the caller knows beyond the cloud.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlanHints {
    /// Use this grasp type (must be realisable by the hand, directly or by equivalence).
    pub grasp_type: Option<GraspType>,
    /// Approach here (snapped to the nearest cloud point).
    pub attention_point: Option<Point3<f64>>,
    /// The grasp-type model's attention point (Eq 4.3), when no `attention_point` was given:
    /// p_att as well, but a suggestion — a hand with kinematics also tries the oppositions about
    /// the surface point over the estimated centre of mass (`dual_stage::opposition_stage_about`).
    pub detected_attention: Option<Point3<f64>>,
    /// The plane the object stands on.
    pub support_plane: Option<Plane>,
    /// Sensor position in the cloud's frame: normals face it and it sets the approach side.
    pub viewpoint: Option<Point3<f64>>,
    /// For a cloud fused from several views: where each part of it was seen from, as (end
    /// index, camera position) in order. Each point's normal then faces the camera that saw it
    /// and nothing is completed (the far side was measured); `viewpoint` still sets the
    /// approach side.
    pub seen_from: Vec<(usize, Point3<f64>)>,
    /// Which way is up, when no support plane is known.
    pub up: Option<Vector3<f64>>,
    /// P(s|O) for s = 1..6 from the grasp-type model over the ROI (Eq 4.3): the planner takes
    /// s* as the most probable type the hand realises. Ignored when `grasp_type` is set.
    pub detected_types: Option<[f64; 6]>,
}

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
}
