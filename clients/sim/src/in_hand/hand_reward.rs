//! r_hand (dissertation Eq 7.5) on the simulated hand: how far the hand's posture, projected on
//! the first two posture synergies (§7.3, as graspd serves them for this hand), lies from the
//! precision grasps' centre.

use super::env::InHandScene;
use crate::SimError;
use graspd_core::GraspType;
use graspd_core::hand::{PostureSynergies, hand_based_reward};

/// The synergies of the hand and where each of their joints sits among the scene's.
pub struct HandReward {
    synergies: PostureSynergies,
    /// For each synergy joint, its index in the scene's hand joints.
    order: Vec<usize>,
}

impl HandReward {
    /// Fails when a synergy joint is not in the scene or the hand has no precision postures.
    pub fn new(synergies: PostureSynergies, scene: &InHandScene) -> Result<Self, SimError> {
        let order = synergies
            .joints
            .iter()
            .map(|name| {
                scene
                    .hand_joints
                    .iter()
                    .position(|(n, _, _)| n == name)
                    .ok_or_else(|| {
                        SimError::Input(format!(
                            "synergies: joint `{name}` is not a joint of the simulated hand"
                        ))
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        if !synergies
            .centres
            .iter()
            .any(|c| c.grasp_type == GraspType::Precision)
        {
            return Err(SimError::Input(
                "synergies: the hand has no precision postures, so r_hand (Eq 7.5) has no centre"
                    .into(),
            ));
        }
        Ok(HandReward { synergies, order })
    }

    /// d_hand of Eq 7.5 for the scene's joint angles `q`.
    pub fn distance(&self, q: &[f64]) -> f64 {
        let posture: Vec<f64> = self.order.iter().map(|&i| q[i]).collect();
        self.synergies
            .hand_distance(&posture, GraspType::Precision)
            .unwrap_or(f64::INFINITY)
    }

    /// r_hand of Eq 7.5 for the scene's joint angles `q`.
    pub fn reward(&self, q: &[f64]) -> f64 {
        hand_based_reward(self.distance(q))
    }
}
