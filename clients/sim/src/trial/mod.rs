//! One grasp trial: render → PlanGrasp → pre-grasp → approach → close → lift → hold → shake,
//! with the outcome classified.
//!
//! Protocol (all in simulated time, 2 ms steps):
//! 1. the object is dropped 1 mm above the table at a seeded random spot (±`place_range`,
//!    default [`PLACE_RANGE`]) and
//!    yaw, and settles for 0.3 s while the hand is parked out of view;
//! 2. the camera renders the scene and graspd plans on the frame (or on the object's cloud);
//! 3. the base jumps to the pre-grasp pose (`pregrasp_pose × hand_pose⁻¹ × root_pose`) with every
//!    actuator at graspd's `pregrasp_joints` (each servo's equilibrium there) and holds 0.3 s;
//! 4. approach: the base moves in a straight line to `root_pose` in [`APPROACH_S`];
//! 5. close: every actuator together in [`CLOSE_S`], from the pre-grasp through the touching
//!    `joints` (two thirds of the time) to `squeeze_joints` (kept in proportion within the
//!    force limits for a hand with force to spare, `closing::within_force_limits`), then 0.4 s
//!    settle — guarded (each
//!    actuator stops where what it moves touches the object and squeezes from there), or open
//!    loop when asked ([`crate::closing`]);
//! 6. lift: the base rises [`LIFT_M`] in [`LIFT_S`]; hold [`HOLD_S`]; from here on the hand
//!    grips harder, in the plan's proportions, while the object slides in it (the grip
//!    reflex, [`crate::grip_reflex`]; off with `--no-grip-reflex`);
//! 7. shake: [`SHAKE_S`] of a sinusoidal displacement of amplitude [`SHAKE_AMPLITUDE_M`] at
//!    [`SHAKE_HZ`] along (1, 1, 0.5)/|·| (peak acceleration ≈ 3.2 m/s²), then 0.3 s still.
//!
//! A plan graspd marks infeasible is asked again with other seeds (`replans` times, seeds
//! seed + 1000·k) and the first feasible one is executed; when none is, the one graspd rates
//! most robust (`quality.robustness`) is executed anyway (the record keeps `feasible` and the
//! reason): the simulation, not the planner's own check, decides. (The first plan, executed
//! before: Table 5.2, 20 trials per cell, paired: Allegro 130 → 134, Barrett 142 → 143, Shadow
//! 123 → 126 of 160 — the banana and the Shadow's tuna can, whose plans are mostly infeasible.)
//!
//! Success: after the shake the object is off the table (no contact with it), touches the hand,
//! and its centre of mass is at least [`LIFTED_M`] above where it was (an object hanging tilted
//! from the fingers is held; one lying on the table or on a finger resting on it is not). Failures, in the order they are checked: `no_plan` (PlanGrasp answered an error or
//! the plan has no joints), `ik_collision` (at the end of the approach the hand is more than
//! [`TABLE_PENETRATION_M`] into the table, or the approach pushed the object more than
//! [`PUSH_M`]), `missed_contact` (after closing fewer than two hand bodies touch
//! the object), `slipped_lift` (not lifted, or lost during the lift or the hold), `dropped_shake`.

use crate::camera::{self, Intrinsics, RgbdImage};
use crate::debug;
use crate::hand::SimHand;
pub use crate::record::{Outcome, TrialRecord};
use crate::scene::{Scene, from_mj};
use crate::service::{PlanAsk, PlanResult, Service};
use graspd_api::convert::{grasp_type_from_proto, pose_from_proto};
use mujoco_rs::prelude::MjtObjBase;
use nalgebra::{Isometry3, Point3, Vector3};
use rand::{RngExt, SeedableRng};

pub mod world;

pub use crate::closing::{CLOSE_S, CLOSE_SETTLE_S};
pub use world::{SETTLE_S, Trial};

/// Default half-width of the square the object is placed in, m (issue 15: ±10 cm).
pub const PLACE_RANGE: f64 = 0.10;
pub const PRESHAPE_S: f64 = 0.3;
pub const APPROACH_S: f64 = 0.6;
pub const LIFT_M: f64 = 0.10;
pub const LIFT_S: f64 = 1.0;
pub const HOLD_S: f64 = 2.0;
pub const SHAKE_S: f64 = 1.5;
pub const SHAKE_HZ: f64 = 2.0;
pub const SHAKE_AMPLITUDE_M: f64 = 0.02;
/// Rise of the object's centre of mass that counts as lifted, m (the base rises 0.10).
pub const LIFTED_M: f64 = 0.03;
/// Object displacement before closing that counts as a collision, m.
pub const PUSH_M: f64 = 0.03;
/// Hand penetration into the table at the end of the approach that counts as a collision, m.
pub const TABLE_PENETRATION_M: f64 = 0.005;

/// Options of a trial.
#[derive(Debug, Clone, Copy)]
pub struct TrialOptions {
    pub intrinsics: Intrinsics,
    pub camera: Isometry3<f64>,
    /// Plan on the object's points instead of the RGB-D frame.
    pub cloud_input: bool,
    /// Extra PlanGrasp calls (other seeds) when a plan comes back infeasible.
    pub replans: usize,
    /// Render a snapshot with the hand after the hold, from this view.
    pub snapshot: Option<(Intrinsics, Isometry3<f64>)>,
    /// Close guarded (the default) instead of open loop ([`crate::closing`]).
    pub guarded_close: bool,
    /// Execute the plan ranked this far down graspd's `candidates` (0: the best), as a robot
    /// stack falling back would.
    pub candidate: usize,
    /// Force this grasp type instead of graspd's detection.
    pub grasp_type: Option<graspd_proto::v1::GraspType>,
    /// graspd's planner mode (None: its default).
    pub mode: Option<graspd_proto::v1::PlannerMode>,
    /// Half-width of the square the object is placed in, m.
    pub place_range: f64,
    /// Views of the scene sent with each PlanGrasp (RGB-D input): the camera, and `views − 1`
    /// more turned about the table's vertical (`camera::views_around`), fused by graspd.
    pub views: usize,
    /// Run the six-direction gravity test after the hold ([`crate::gravity`]).
    pub gravity_test: bool,
    /// Grip harder when the object slides in the hand after the close
    /// ([`crate::grip_reflex`]); off: the grip of the close throughout, as a grasp benchmark's
    /// fixed squeeze.
    pub grip_reflex: bool,
}

/// The seeded object placement within ±`range` m: (x, y, yaw).
pub fn placement(seed: u64, range: f64) -> [f64; 3] {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x9e37_79b9_7f4a_7c15);
    let range = range.max(1e-6);
    [
        rng.random_range(-range..range),
        rng.random_range(-range..range),
        rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
    ]
}

/// Runs one whole trial of `hand` on object 0 of `scene`.
pub fn run_trial(
    scene: &Scene,
    hand: &SimHand,
    object: &str,
    service: &Service,
    seed: u64,
    opts: &TrialOptions,
) -> TrialRecord {
    let place = placement(seed, opts.place_range);
    let mut rec = TrialRecord::empty(hand, object, seed, place);
    let t_sim = std::time::Instant::now();
    let mut trial = Trial::new(scene, place);
    let start = trial.object_position();
    let t_render = std::time::Instant::now();
    let image = trial.render(opts.intrinsics, opts.camera);
    let extra: Vec<RgbdImage> = if opts.cloud_input {
        Vec::new()
    } else {
        camera::views_around(&opts.camera, opts.views)
            .iter()
            .skip(1)
            .map(|v| trial.render(opts.intrinsics, *v))
            .collect()
    };
    let cloud = opts.cloud_input.then(|| {
        let obj = scene.object_bodies[0];
        image.points_of(|g| scene.model.geom_bodyid()[g] as usize == obj)
    });
    rec.render_ms = t_render.elapsed().as_secs_f64() * 1e3;
    let mut sim_s = t_sim.elapsed().as_secs_f64() - rec.render_ms / 1e3;
    // A robot stack re-plans when the planner says a plan is infeasible: up to `replans` more
    // seeds, the first feasible plan wins, else the plan graspd rates most robust.
    let ask = PlanAsk {
        candidates: if opts.candidate > 0 {
            opts.candidate as u32 + 1
        } else {
            0
        },
        grasp_type: opts.grasp_type,
        mode: opts.mode,
        object: None,
    };
    let robustness = |r: &PlanResult| r.response.quality.as_ref().map_or(0.0, |q| q.robustness);
    let mut plan = service.plan(hand, &image, &extra, cloud.as_deref(), seed, &ask);
    let mut attempts = 1;
    let mut extra_ms = 0.0;
    while attempts <= opts.replans && matches!(&plan, Ok(p) if !p.response.feasible) {
        let again = service.plan(
            hand,
            &image,
            &extra,
            cloud.as_deref(),
            seed + 1000 * attempts as u64,
            &ask,
        );
        attempts += 1;
        if let Ok(p) = &again {
            extra_ms += p.latency * 1e3;
            let better = match &plan {
                Ok(first) => p.response.feasible || robustness(p) > robustness(first),
                Err(_) => true,
            };
            if better {
                plan = again;
            }
        }
    }
    rec.plan_attempts = attempts;
    rec.replan_ms = extra_ms;
    if opts.candidate > 0
        && let Ok(p) = &mut plan
    {
        take_candidate(&mut p.response, opts.candidate);
    }
    let t_sim = std::time::Instant::now();
    let outcome = match plan {
        Err(s) => {
            rec.detail = format!("{}: {}", s.code(), s.message());
            Outcome::NoPlan
        }
        Ok(plan) => execute(&mut trial, &plan, start, opts, &mut rec),
    };
    rec.outcome = outcome;
    sim_s += t_sim.elapsed().as_secs_f64();
    rec.sim_ms = sim_s * 1e3;
    rec
}

/// Puts the plan ranked `k`-th in `candidates` in the response's place (no joints when graspd
/// returned fewer: the trial then ends `no_plan`).
pub fn take_candidate(r: &mut graspd_proto::v1::PlanGraspResponse, k: usize) {
    match r.candidates.get(k).cloned() {
        Some(c) => {
            r.contacts = c.contacts;
            r.hand_pose = c.hand_pose;
            r.pregrasp_pose = c.pregrasp_pose;
            r.root_pose = c.root_pose;
            r.approach = c.approach;
            r.joints = c.joints;
            r.pregrasp_joints = c.pregrasp_joints;
            r.squeeze_joints = c.squeeze_joints;
            r.quality = c.quality;
            r.feasible = c.feasible;
            r.infeasible_reason = c.infeasible_reason;
        }
        None => r.joints.clear(),
    }
}

/// What the approach leaves for the rest of a trial.
pub struct Approached {
    /// The base pose of the grasp (the plan's root_pose).
    pub root: Isometry3<f64>,
    /// Per actuator: its command at the planned (touching) joints.
    pub grasp: Vec<f64>,
    /// Per actuator: its command at the squeeze, where the closing ends.
    pub closed: Vec<f64>,
    /// The object's centre of mass before anything touched it.
    pub start_com: Point3<f64>,
}

/// How the hand gets to the grasp.
#[derive(Debug, Clone, Copy)]
pub enum Motion<'p> {
    /// The standard protocol: a jump to the pre-grasp pose, then the straight approach.
    Straight,
    /// Along a reach (PlanReach's hand-frame poses at their times, ending at the grasp), from
    /// its first pose, the hand pre-shaped there; the approach onto the grasp takes its last
    /// `approach_s` seconds.
    Path {
        path: &'p [(f64, Isometry3<f64>)],
        approach_s: f64,
    },
}

/// Steps 3–4 of the protocol: records the plan, pre-shapes and moves the hand to the grasp
/// (`motion`); `Err` with the failure class when the plan has no joints or the approach
/// collides. Hand contacts with other objects on the way are recorded
/// (`rec.touched_others`).
pub fn pre_grasp_and_approach(
    trial: &mut Trial,
    plan: &PlanResult,
    start: Point3<f64>,
    motion: Motion<'_>,
    rec: &mut TrialRecord,
) -> Result<Approached, Outcome> {
    let r = &plan.response;
    trial.data.forward();
    let start_com = trial.object_com();
    rec.plan_ms = Some(plan.latency * 1e3);
    rec.server_ms = r.timings.as_ref().map(|t| t.total * 1e3);
    rec.grasp_type = Some(
        grasp_type_from_proto(r.grasp_type, "grasp_type")
            .ok()
            .flatten()
            .map_or("unspecified", |g| g.name())
            .to_string(),
    );
    rec.type_source = Some(r.type_source.clone());
    rec.feasible = Some(r.feasible);
    rec.infeasible_reason = r.infeasible_reason.clone();
    rec.approach = r.approach.map(|a| [a.x, a.y, a.z]);
    rec.robustness = r.quality.map(|q| q.robustness);
    rec.planned_contacts = r.contacts.iter().map(|c| c.finger.clone()).collect();
    rec.planned_inferred = r.contacts.iter().map(|c| c.inferred).collect();
    rec.planned_positions = r
        .contacts
        .iter()
        .filter_map(|c| c.position.map(|p| [p.x, p.y, p.z]))
        .collect();
    rec.gravity_resistance = r.quality.map(|q| q.gravity_resistance);
    rec.gii = r.quality.map(|q| q.gii);
    let pose =
        |p: &Option<graspd_proto::v1::Pose>| pose_from_proto(p, "").ok().map(|p| p.isometry());
    let (Some(root), Some(hand_pose), Some(pre)) = (
        pose(&r.root_pose),
        pose(&r.hand_pose),
        pose(&r.pregrasp_pose),
    ) else {
        rec.detail = "the plan has no root_pose (the hand has no kinematics)".into();
        return Err(Outcome::NoPlan);
    };
    let named = |j: &[graspd_proto::v1::JointAngle]| -> Vec<(String, f64)> {
        j.iter().map(|j| (j.name.clone(), j.angle)).collect()
    };
    let joints = named(&r.joints);
    let (pre_joints, squeeze_joints) = (named(&r.pregrasp_joints), named(&r.squeeze_joints));
    // Executed as planned: every actuator at its command for the pre-grasp joints, then through
    // the touching joints to the squeeze.
    if pre_joints.is_empty() || squeeze_joints.is_empty() {
        rec.detail = "the plan has no pre-grasp or squeeze joints".into();
        return Err(Outcome::NoPlan);
    }
    let opened = trial.planned_commands(&pre_joints);
    let grasp = trial.planned_commands(&joints);
    let closed = trial.planned_commands(&squeeze_joints);
    let pre_root = pre * hand_pose.inverse() * root;
    // The plan as graspd means it: the hand posed at the grasp (and, for the debug pictures, the
    // squeeze), no physics. How deep it lies in the true object measures the plan's geometry:
    // what a single view and its completion got wrong.
    let saved = trial.data.qpos().to_vec();
    let debug = std::env::var_os("GRASPD_SIM_DEBUG_DIR").is_some();
    for (name, q) in [("planned", &joints), ("squeeze", &squeeze_joints)] {
        if name == "squeeze" && !debug {
            break;
        }
        trial.place_base(&root);
        trial.set_hand_joints(q);
        trial.data.forward();
        if name == "planned" {
            rec.planned_depth_mm = Some(trial.deepest_object_penetration() * 1e3);
        }
        debug::penetration(trial, name);
        debug::snapshot(trial, name);
    }
    trial.data.qpos_mut().copy_from_slice(&saved);
    trial.data.forward();
    trial.set_hand_joints(if pre_joints.is_empty() {
        &joints
    } else {
        &pre_joints
    });
    trial.data.ctrl_mut().copy_from_slice(&opened);
    // The base pose that puts the hand frame at `hand`.
    let base_for = |hand: &Isometry3<f64>| hand * hand_pose.inverse() * root;
    // Other objects touched: on the reach (true) or on the approach.
    let mut others: Vec<(usize, bool)> = Vec::new();
    let mut deepest: f64 = 0.0;
    let mut watch = |t: &Trial, in_reach: bool| {
        for (b, depth) in t.hand_contacts_with_others() {
            deepest = deepest.max(depth);
            if !others.contains(&(b, in_reach)) {
                others.push((b, in_reach));
            }
        }
    };
    match motion {
        Motion::Straight => {
            trial.place_base(&pre_root);
            trial.data.forward();
            trial.run(PRESHAPE_S, |_, _| {});
            debug::snapshot(trial, "pregrasp");
            // Approach along the straight line.
            trial.run(APPROACH_S, |t, f| {
                let p = pre_root.lerp_slerp(&root, f);
                t.set_base(&p);
                watch(t, false);
            });
        }
        Motion::Path { path, approach_s } => {
            let Some((&(t0, first), &(t1, _))) = path.first().zip(path.last()) else {
                rec.detail = "the reach has no samples".into();
                return Err(Outcome::NoPlan);
            };
            trial.place_base(&base_for(&first));
            trial.data.forward();
            trial.run(PRESHAPE_S, |t, _| watch(t, true));
            debug::snapshot(trial, "pregrasp");
            let duration = (t1 - t0).max(1e-3);
            let mut k = 0;
            trial.run(duration, |t, f| {
                // The pose at this time, between the samples around it.
                let now = t0 + f * duration;
                while k + 2 < path.len() && path[k + 1].0 <= now {
                    k += 1;
                }
                let (a, b) = (path[k], path[(k + 1).min(path.len() - 1)]);
                let s = if b.0 > a.0 {
                    ((now - a.0) / (b.0 - a.0)).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                t.set_base(&base_for(&a.1.lerp_slerp(&b.1, s)));
                watch(t, now < t1 - approach_s);
            });
            // Settle onto the grasp pose itself.
            trial.run(0.1, |t, _| {
                t.set_base(&root);
                watch(t, false);
            });
        }
    }
    let m = &trial.scene.model;
    let names = |in_reach: Option<bool>| {
        let mut n: Vec<String> = others
            .iter()
            .filter(|(_, r)| in_reach.is_none_or(|want| *r == want))
            .map(|&(b, _)| {
                m.id_to_name(MjtObjBase::mjOBJ_BODY, b)
                    .unwrap_or_default()
                    .to_string()
            })
            .collect();
        n.sort();
        n.dedup();
        n
    };
    rec.touched_others = names(None);
    rec.touched_in_reach = names(Some(true));
    rec.others_penetration_mm = (!others.is_empty()).then_some(deepest * 1e3);
    debug::snapshot(trial, "approached");
    let through = trial.deepest_table_penetration();
    if through > TABLE_PENETRATION_M {
        rec.detail = format!("the hand went {:.0} mm into the table", through * 1e3);
        return Err(Outcome::IkCollision);
    }
    let pushed = (trial.object_position() - start).norm();
    rec.moved_approach_mm = Some(pushed * 1e3);
    if pushed > PUSH_M {
        rec.detail = format!("the approach pushed the object {:.0} mm", pushed * 1e3);
        return Err(Outcome::IkCollision);
    }
    Ok(Approached {
        root,
        grasp,
        closed,
        start_com,
    })
}

/// Steps 3–7 of the protocol on a plan.
pub(crate) fn execute(
    trial: &mut Trial,
    plan: &PlanResult,
    start: Point3<f64>,
    opts: &TrialOptions,
    rec: &mut TrialRecord,
) -> Outcome {
    match pre_grasp_and_approach(trial, plan, start, Motion::Straight, rec) {
        Ok(a) => grasp_and_lift(trial, a, opts, rec),
        Err(o) => o,
    }
}

/// Steps 5–7 of the protocol, from the approached hand: close, lift, hold, shake.
pub fn grasp_and_lift(
    trial: &mut Trial,
    approached: Approached,
    opts: &TrialOptions,
    rec: &mut TrialRecord,
) -> Outcome {
    let Approached {
        root,
        grasp,
        closed,
        start_com,
    } = approached;
    // Close (crate::closing): guarded unless the options ask for the open loop.
    let (before_p, before_q) = (trial.object_position(), trial.object_orientation());
    let commands = if trial.scene.balanced_grip {
        crate::closing::within_force_limits(&trial.scene.model, &grasp, &closed)
    } else {
        closed.clone()
    };
    let at_touch = crate::closing::close(trial, &grasp, &commands, opts.guarded_close);
    if opts.grip_reflex {
        trial.reflex = crate::grip_reflex::GripReflex::arm(trial, &grasp, &closed)
            .map(|r| Box::new(r) as Box<dyn world::BeforeStep>);
    }
    debug::snapshot(trial, "closed");
    debug::forces(trial, "closed", &grasp, &commands);
    let touching = trial.hand_bodies_touching();
    rec.contact_bodies = Some(touching);
    rec.moved_close_mm = Some((trial.object_position() - before_p).norm() * 1e3);
    rec.moved_touch_mm = Some((at_touch - before_p).norm() * 1e3);
    rec.turned_close_deg = Some(before_q.angle_to(&trial.object_orientation()).to_degrees());
    rec.touching_bodies = trial.hand_body_names_touching();
    if touching < 2 {
        rec.detail = format!("{touching} hand bodies touch the object after closing");
        return Outcome::MissedContact;
    }
    // Lift and hold.
    trial.run(LIFT_S, |t, f| {
        let up = nalgebra::Translation3::new(0.0, 0.0, LIFT_M * smooth(f));
        t.set_base(&(up * root));
    });
    debug::snapshot(trial, "lifted");
    // The commands held now (the grip reflex may have raised them): a finger whose length
    // reached its command presses nothing.
    let held_commands = trial.data.ctrl().to_vec();
    debug::forces(trial, "lifted", &grasp, &held_commands);
    let height = |t: &Trial| t.object_com().z - start_com.z;
    rec.lift_height = Some(height(trial));
    let lifted = nalgebra::Translation3::new(0.0, 0.0, LIFT_M) * root;
    trial.run(HOLD_S, |_, _| {});
    if let Some((intr, view)) = opts.snapshot {
        rec.snapshot = Some(trial.render(intr, view));
    }
    let held = |t: &Trial| {
        height(t) >= LIFTED_M && !t.object_touches_table() && t.hand_bodies_touching() >= 1
    };
    if !held(trial) {
        rec.final_height = Some(height(trial));
        rec.detail = format!(
            "object {:.0} mm above its start after the lift, {:.0} mm after the hold",
            rec.lift_height.unwrap_or(0.0) * 1e3,
            height(trial) * 1e3
        );
        return Outcome::SlippedLift;
    }
    if opts.gravity_test {
        rec.gravity_held = Some(crate::gravity::six_directions(trial));
    }
    // Shake.
    let dir = Vector3::new(1.0, 1.0, 0.5).normalize();
    trial.run(SHAKE_S, |t, f| {
        let s = SHAKE_AMPLITUDE_M * (2.0 * std::f64::consts::PI * SHAKE_HZ * SHAKE_S * f).sin();
        let d = nalgebra::Translation3::from(dir * s);
        t.set_base(&(d * lifted));
    });
    trial.set_base(&lifted);
    trial.run(0.3, |_, _| {});
    rec.final_height = Some(height(trial));
    if !held(trial) {
        rec.detail = format!(
            "object {:.0} mm above its start after the shake",
            height(trial) * 1e3
        );
        return Outcome::DroppedShake;
    }
    Outcome::Success
}

/// Smoothstep 0 → 1 (zero velocity at both ends).
fn smooth(f: f64) -> f64 {
    f * f * (3.0 - 2.0 * f)
}

/// The mocap pose of the base in the world.
pub fn base_pose(trial: &Trial) -> Isometry3<f64> {
    let m = trial.scene.mount_mocap;
    from_mj(&trial.data.mocap_pos()[m], &trial.data.mocap_quat()[m])
}

#[cfg(test)]
mod tests {
    use super::take_candidate;
    use graspd_proto::v1 as pb;

    fn joint(name: &str, angle: f64) -> pb::JointAngle {
        pb::JointAngle {
            name: name.into(),
            angle,
        }
    }

    /// The fall-back plan takes the response's place whole (joints, squeeze, feasibility); one
    /// graspd did not return leaves no joints, so the trial ends `no_plan` instead of running
    /// the best plan under another name.
    #[test]
    fn a_fall_back_candidate_replaces_the_plan_whole() {
        let second = pb::GraspCandidate {
            joints: vec![joint("j", 0.3)],
            squeeze_joints: vec![joint("j", 0.4)],
            feasible: false,
            infeasible_reason: Some("second".into()),
            ..Default::default()
        };
        let mut r = pb::PlanGraspResponse {
            joints: vec![joint("j", 0.1)],
            feasible: true,
            candidates: vec![pb::GraspCandidate::default(), second],
            ..Default::default()
        };
        take_candidate(&mut r, 1);
        assert_eq!(r.joints, vec![joint("j", 0.3)]);
        assert_eq!(r.squeeze_joints, vec![joint("j", 0.4)]);
        assert!(!r.feasible);
        assert_eq!(r.infeasible_reason.as_deref(), Some("second"));
        take_candidate(&mut r, 2);
        assert!(r.joints.is_empty());
    }
}
