//! What goes into the planner besides the cloud and the hand: the mode, the options and the
//! hints (the domain side of a PlanGrasp request).

use crate::cloud::Plane;
use crate::grasp_type::GraspType;
use crate::planning::parallel_grasp::ParallelGrasp;
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

/// Dual-stage (the method), the "without opposition" ablation of Table 5.1, or ch. 3's
/// learned quality for a two-jaw gripper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlannerMode {
    #[default]
    DualStage,
    /// Skip stage 1 and search the m contacts directly over the whole cloud.
    WithoutOpposition,
    /// A learned quality network searched by Bayesian optimisation over grasps straight down
    /// (`learned_planner`).
    LearnedQuality,
}

impl PlannerMode {
    pub const ALL: [PlannerMode; 3] = [
        PlannerMode::DualStage,
        PlannerMode::WithoutOpposition,
        PlannerMode::LearnedQuality,
    ];

    /// The snake_case name used in the API.
    pub fn name(self) -> &'static str {
        match self {
            PlannerMode::DualStage => "dual_stage",
            PlannerMode::WithoutOpposition => "without_opposition",
            PlannerMode::LearnedQuality => "learned_quality",
        }
    }
}

impl std::str::FromStr for PlannerMode {
    type Err = String;
    /// The mode by its API name (a command line's `--mode`).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        PlannerMode::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown planner mode '{s}' (expected one of dual_stage, without_opposition, learned_quality)"
                )
            })
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
    /// Realise this parallel-jaw grasp g = {x, y, z, θ} (ch. 3) with the hand's kinematics,
    /// straight down onto the table, instead of searching: a two-jaw gripper's pinch on the
    /// two points its jaws meet ([`ParallelGrasp::opposition`]). Needs the hand's model and a
    /// support plane or `up`.
    pub parallel_grasp: Option<ParallelGrasp>,
}
