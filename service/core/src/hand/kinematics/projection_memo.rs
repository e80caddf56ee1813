//! Linkage projections already solved for one hand
//! ([`KinematicTree::project_constraints_fk`]), kept for the plans that follow.
//!
//! The closing sweep of a hand whose fingers are tied by loop closures or joint couplings (of
//! the shared hands, the 2F-85's linkage) projects the joints back onto the constraints at
//! every step. Every candidate of a plan, and every plan of that hand, closes
//! from the same pre-shapes along the same path steps until its first touch, so most of these
//! projections repeat exactly: 63 % within one 2F-85 plan and 75 % over the 40 plans of the
//! `kinematic_plan` bench. The projection depends on its inputs alone (the joints it starts from
//! and those it holds), so a kept answer is the one it would compute again, bit for bit: plans
//! do not depend on what the memo holds.

use super::forward_kinematics::ForwardKinematics;
use super::kinematic_tree::KinematicTree;
use crate::error::FieldError;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Projections a memo keeps before it starts again (the 2F-85's 40 bench plans reach 7,400
/// distinct ones, about 185 new per plan; an entry is its joints and the poses of its bodies,
/// about 1.5 KB for the 2F-85).
pub const MEMO_CAPACITY: usize = 4096;

/// A projection's inputs: the bits of the joints it starts from, then the held joints.
type Key = Vec<u64>;

/// The projected joints and their forward kinematics.
type Projected = Arc<(Vec<f64>, ForwardKinematics)>;

/// Projections of one hand's tree, shared by the plans (and the threads) that use the hand.
#[derive(Default)]
pub struct ProjectionMemo {
    entries: Mutex<HashMap<Key, Projected>>,
}

impl std::fmt::Debug for ProjectionMemo {
    /// How many projections are kept, not the poses themselves (a model's debug print would
    /// otherwise run to megabytes).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProjectionMemo")
            .field("kept", &self.len())
            .finish()
    }
}

impl Clone for ProjectionMemo {
    /// A clone starts empty: what a memo keeps belongs to the tree it was filled from.
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl ProjectionMemo {
    /// [`KinematicTree::project_constraints_fk`] of `tree` (the one this memo belongs to) from
    /// `q` holding `held`: `q` becomes the projected joints, and their forward kinematics are
    /// returned. Only answers are kept, never errors.
    pub fn project(
        &self,
        tree: &KinematicTree,
        q: &mut [f64],
        held: &[usize],
    ) -> Result<Projected, FieldError> {
        let key: Key = q
            .iter()
            .map(|x| x.to_bits())
            .chain(held.iter().map(|&j| j as u64))
            .collect();
        let kept = self.lock().get(&key).cloned();
        if let Some(p) = kept {
            q.copy_from_slice(&p.0);
            return Ok(p);
        }
        let (_, fk) = tree.project_constraints_fk(q, held)?;
        let p: Projected = Arc::new((q.to_vec(), fk));
        let mut entries = self.lock();
        if entries.len() >= MEMO_CAPACITY {
            entries.clear();
        }
        entries.insert(key, p.clone());
        Ok(p)
    }

    /// The number of projections kept.
    pub fn len(&self) -> usize {
        self.lock().len()
    }

    /// Whether nothing is kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<Key, Projected>> {
        // A panic while the lock was held left at worst a missing entry: the map stays valid.
        self.entries.lock().unwrap_or_else(|e| e.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hand::kinematics::KinematicHand;

    /// The 2F-85's linkage projected through the memo, from a driven joint set and a start the
    /// sweep would use: the same joints and the same forward kinematics as the projection
    /// itself, the first time and when kept; a different start is a different entry.
    #[test]
    fn a_kept_projection_is_the_projection_bit_for_bit() {
        let path = graspd_testkit::testdata_dir().join("hands/robotiq_2f85/2f85.xml");
        let hand = KinematicHand::from_mjcf_file(path).expect("the shared 2F-85 loads");
        let tree = &hand.tree;
        assert!(!tree.loop_closures.is_empty() || !tree.couplings.is_empty());
        let memo = ProjectionMemo::default();
        let driven = 0;
        let mut start = vec![0.0; tree.joints.len()];
        start[driven] = 0.3;
        let mut direct = start.clone();
        let (_, fk) = tree.project_constraints_fk(&mut direct, &[driven]).unwrap();
        for round in 0..2 {
            let mut q = start.clone();
            let p = memo.project(tree, &mut q, &[driven]).unwrap();
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&q), bits(&direct), "round {round}");
            assert_eq!(bits(&p.0), bits(&direct), "round {round}");
            assert_eq!(p.1, fk, "round {round}");
            assert_eq!(memo.len(), 1);
        }
        assert_ne!(direct, start, "the linkage moved the other joints");
        let mut other = start.clone();
        other[driven] = 0.4;
        memo.project(tree, &mut other, &[driven]).unwrap();
        assert_eq!(memo.len(), 2);
        assert!(memo.clone().is_empty());
    }
}
