//! What a trial records: how it ended ([`Outcome`], the failure classes of [`crate::trial`]) and
//! everything measured on the way ([`TrialRecord`], one entry of a bench's `results.json`).

use crate::camera::RgbdImage;
use crate::hand::SimHand;
use serde::Serialize;

/// How a trial ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    Success,
    NoPlan,
    IkCollision,
    MissedContact,
    SlippedLift,
    DroppedShake,
}

impl Outcome {
    pub const ALL: [Outcome; 6] = [
        Outcome::Success,
        Outcome::NoPlan,
        Outcome::IkCollision,
        Outcome::MissedContact,
        Outcome::SlippedLift,
        Outcome::DroppedShake,
    ];
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Success => "success",
            Outcome::NoPlan => "no_plan",
            Outcome::IkCollision => "ik_collision",
            Outcome::MissedContact => "missed_contact",
            Outcome::SlippedLift => "slipped_lift",
            Outcome::DroppedShake => "dropped_shake",
        }
    }
}

/// What one trial did.
#[derive(Debug, Clone, Serialize)]
pub struct TrialRecord {
    pub hand: String,
    pub object: String,
    pub seed: u64,
    pub outcome: Outcome,
    /// Detail of a failure.
    pub detail: String,
    pub grasp_type: Option<String>,
    pub type_source: Option<String>,
    pub feasible: Option<bool>,
    pub infeasible_reason: Option<String>,
    /// PlanGrasp round trip of the executed plan, ms.
    pub plan_ms: Option<f64>,
    /// PlanGrasp calls made (1 + re-plans) and the time of the re-plans, ms.
    pub plan_attempts: usize,
    pub replan_ms: f64,
    /// graspd's own total, ms.
    pub server_ms: Option<f64>,
    pub render_ms: f64,
    pub sim_ms: f64,
    /// Object height above its start after the lift and at the end, m.
    pub lift_height: Option<f64>,
    pub final_height: Option<f64>,
    /// Hand bodies touching the object after closing.
    pub contact_bodies: Option<usize>,
    /// The executed plan's approach direction, robustness figure and contacts (finger names).
    pub approach: Option<[f64; 3]>,
    pub robustness: Option<f64>,
    pub planned_contacts: Vec<String>,
    /// Which of them lie on the completed, unseen side of the object (`inferred`).
    #[serde(default)]
    pub planned_inferred: Vec<bool>,
    /// The executed plan's contact positions (world), its resisted weight and S (Eq 5.3).
    pub planned_positions: Vec<[f64; 3]>,
    pub gravity_resistance: Option<f64>,
    pub gii: Option<f64>,
    /// How far the object moved during the approach, during the close up to the touching
    /// commands and during the whole close (squeeze included), mm, and how much it turned
    /// during the close, degrees; the hand bodies touching it after closing.
    pub moved_approach_mm: Option<f64>,
    pub moved_touch_mm: Option<f64>,
    pub moved_close_mm: Option<f64>,
    pub turned_close_deg: Option<f64>,
    pub touching_bodies: Vec<String>,
    /// How deep the deepest hand body lies in the true object with the hand posed at the plan's
    /// grasp (no physics), mm: what the single view and its completion got wrong.
    pub planned_depth_mm: Option<f64>,
    /// The six-direction gravity test ([`crate::gravity`], order ±x, ±y, ±z): whether each
    /// direction held; None when the object was not held after the hold or the test was off.
    pub gravity_held: Option<[bool; 6]>,
    /// Object placement (x, y, yaw).
    pub placement: [f64; 3],
    /// Other objects (in clutter) that a hand body touched before the close, and the deepest
    /// it went into one, mm; those touched on the reach itself, before its pre-grasp point
    /// (the rest on the approach onto the grasp).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub touched_others: Vec<String>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub touched_in_reach: Vec<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub others_penetration_mm: Option<f64>,
    /// The snapshot after the hold (when asked for and the object got that far).
    #[serde(skip)]
    pub snapshot: Option<RgbdImage>,
}

impl TrialRecord {
    /// A record before anything happened (outcome `no_plan` until set).
    pub fn empty(hand: &SimHand, object: &str, seed: u64, place: [f64; 3]) -> Self {
        TrialRecord {
            hand: hand.name.clone(),
            object: object.to_string(),
            seed,
            outcome: Outcome::NoPlan,
            detail: String::new(),
            grasp_type: None,
            type_source: None,
            feasible: None,
            infeasible_reason: None,
            plan_ms: None,
            plan_attempts: 0,
            replan_ms: 0.0,
            server_ms: None,
            render_ms: 0.0,
            sim_ms: 0.0,
            lift_height: None,
            final_height: None,
            contact_bodies: None,
            approach: None,
            robustness: None,
            planned_contacts: Vec::new(),
            planned_inferred: Vec::new(),
            planned_positions: Vec::new(),
            gravity_resistance: None,
            gii: None,
            moved_approach_mm: None,
            moved_touch_mm: None,
            moved_close_mm: None,
            turned_close_deg: None,
            touching_bodies: Vec::new(),
            planned_depth_mm: None,
            gravity_held: None,
            placement: place,
            touched_others: Vec::new(),
            touched_in_reach: Vec::new(),
            others_penetration_mm: None,
            snapshot: None,
        }
    }
}
