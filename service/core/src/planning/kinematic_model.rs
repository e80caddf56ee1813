//! A hand with known kinematics prepared for planning (issue 6, issue 15): the tree read as a
//! hand, the convex collision pieces of every body of the model, how the hand closes (its
//! synergy) and the pre-shape of each grasp the hand realises. Built once per hand (catalog
//! entry) and shared by every plan; the final configuration g = (C_g, Joint_g, Pose_g) is then
//! found with this model in the loop (`final_configuration`).

use crate::error::FieldError;
use crate::hand::HandDescription;
use crate::hand::kinematics::{
    HandCollision, HandSynergy, KinematicHand, PreShape, ProjectionMemo,
};

/// A hand's kinematics prepared for planning.
#[derive(Debug, Clone)]
pub struct KinematicModel {
    pub hand: KinematicHand,
    pub collision: HandCollision,
    /// How the hand closes (flexion and setting joints, linked fingers).
    pub synergy: HandSynergy,
    /// The pre-shape of each way the hand realises a grasp type (kinematic finger indices).
    pub pre_shapes: Vec<PreShapeEntry>,
    /// The linkage projections its plans' closing sweeps solved (kept for the plans after).
    pub projections: ProjectionMemo,
}

/// The pre-shapes of one grasp realisation: fingers h1 (empty: the palm) against h2, the best
/// first, then wider ones ([`crate::hand::kinematics::HandSynergy::pre_shapes`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PreShapeEntry {
    pub h1: Vec<usize>,
    pub h2: Vec<usize>,
    pub shapes: Vec<PreShape>,
}

impl KinematicModel {
    /// Prepares a hand: collision pieces, synergy, and a pre-shape per realisation of its
    /// derived description (a realisation the hand cannot pre-shape is left out; its plans come
    /// back infeasible, saying so).
    pub fn new(hand: KinematicHand) -> Result<Self, FieldError> {
        let collision = hand.collision_model()?;
        let synergy = HandSynergy::derive(&hand)?;
        let description = hand.describe()?;
        let mut pre_shapes: Vec<PreShapeEntry> = Vec::new();
        for r in &description.grasp_types {
            let idx = |names: &[String]| -> Vec<usize> {
                names.iter().filter_map(|n| hand.finger_index(n)).collect()
            };
            let (h1, h2) = (idx(&r.h1), idx(&r.h2));
            if h2.is_empty() || pre_shapes.iter().any(|p| p.h1 == h1 && p.h2 == h2) {
                continue;
            }
            if let Ok(shapes) =
                synergy.pre_shapes(&hand, &h1, &h2, description.geometry.finger_width)
            {
                pre_shapes.push(PreShapeEntry { h1, h2, shapes });
            }
        }
        Ok(Self {
            hand,
            collision,
            synergy,
            pre_shapes,
            projections: ProjectionMemo::default(),
        })
    }

    /// The pre-shapes for fingers `h1` (empty: the palm) against `h2` (kinematic indices), the
    /// best first, then wider ones.
    pub fn pre_shapes(&self, h1: &[usize], h2: &[usize]) -> Option<&[PreShape]> {
        self.pre_shapes
            .iter()
            .find(|p| p.h1 == h1 && p.h2 == h2)
            .map(|p| p.shapes.as_slice())
    }

    /// The validated hand description derived from the kinematics.
    pub fn describe(&self) -> Result<HandDescription, FieldError> {
        self.hand.describe()
    }
}
