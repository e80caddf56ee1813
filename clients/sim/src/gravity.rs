//! The second test of a held object beside lift-hold-shake (issue 15), as DexGraspBench tests
//! grasps: gravity turned to each of the six axis directions. From the state after the hold,
//! for each of ±x, ±y, ±z in turn (each from that same state), the object's own weight is
//! cancelled and m·g applied along the direction, rising over [`RAMP_S`] and then held for
//! [`DIRECTION_S`]; the direction is held when the object ends within [`MAX_SHIFT_M`] and
//! [`MAX_TURN_DEG`] of where it hung, still touching the hand. The hand's base stays where the
//! lift left it. The state after the hold is restored afterwards, so the shake that follows
//! sees the grasp the hold left.

use crate::trial::world::Trial;
use nalgebra::Vector3;

/// Time the load takes to turn to a direction, s.
pub const RAMP_S: f64 = 0.2;
/// Time the load stays along a direction, s.
pub const DIRECTION_S: f64 = 1.0;
/// Largest displacement of the object that counts as held, m.
pub const MAX_SHIFT_M: f64 = 0.02;
/// Largest rotation of the object that counts as held, degrees.
pub const MAX_TURN_DEG: f64 = 15.0;

/// The six directions, in the order tested.
pub const DIRECTIONS: [[f64; 3]; 6] = [
    [1.0, 0.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, -1.0],
];

/// Runs the six directions from the trial's current state (the object held after the hold)
/// and restores that state; returns per direction whether the object stayed.
pub fn six_directions(trial: &mut Trial) -> [bool; 6] {
    let saved = trial.data.clone();
    let saved_reflex = trial.reflex.clone();
    let body = trial.scene.object_bodies[0];
    let mass = trial.scene.model.body_mass()[body];
    let g = Vector3::from(trial.scene.model.ffi().opt.gravity);
    let start_p = trial.object_position();
    let start_q = trial.object_orientation();
    let mut held = [false; 6];
    for (k, d) in DIRECTIONS.iter().enumerate() {
        let load = Vector3::from(*d) * g.norm() * mass;
        trial.run(RAMP_S + DIRECTION_S, |t, f| {
            let share = (f * (RAMP_S + DIRECTION_S) / RAMP_S).min(1.0);
            // Cancel the weight and apply the load, both in proportion while it turns.
            let force = (load - g * mass) * share;
            t.data.xfrc_applied_mut()[body][..3].copy_from_slice(force.as_slice());
        });
        let shift = (trial.object_position() - start_p).norm();
        let turn = start_q.angle_to(&trial.object_orientation()).to_degrees();
        held[k] = shift <= MAX_SHIFT_M && turn <= MAX_TURN_DEG && trial.hand_bodies_touching() > 0;
        saved.copy_to(&mut trial.data).expect("the same model");
        trial.reflex = saved_reflex.clone();
    }
    held
}
