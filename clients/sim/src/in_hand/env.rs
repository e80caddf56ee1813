//! The in-hand rotation task of dissertation §7.5 in MuJoCo: the Shadow hand palm up (as its
//! Menagerie model places it) with a block or an egg lying on the palm, turned by the fingers to
//! a random target orientation. State: the hand's joint angles and velocities, the object's
//! velocity and pose, the target pose (68 numbers for the Shadow's 24 joints); action: a change
//! of each actuator's joint-angle command (20 for the Shadow, whose four distal joints follow
//! their middle joints through tendons); reward r_ext (Eq 7.12). The
//! choices the text leaves open are documented in docs/in-hand.md.

use super::extrinsic_reward::{
    SUCCESS_ANGLE, dropped_reward, extrinsic_reward, orientation_difference,
};
use crate::SimError;
use crate::hand::SimHand;
use crate::scene::{HAND_PREFIX, TIMESTEP, scale_servo_gains, xml_escape};
use mujoco_rs::prelude::*;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use std::f64::consts::PI;
use std::fmt::Write as _;

/// Simulation steps per control step (2 ms each: the policy acts at 25 Hz, as in the Gym tasks
/// the dissertation used).
pub const SUBSTEPS: usize = 20;
/// Control steps per episode (§7.5.1: N_epi = 100, 4 s).
pub const EPISODE_STEPS: usize = 100;
/// Where the object starts, above the Shadow's palm (world frame, m); also the target position
/// in the state.
pub const OBJECT_START: [f64; 3] = [0.32, -0.01, 0.07];
/// An object whose centre falls below this height has left the hand (the palm's surface is at
/// about 0.017 m), m. From then on every step pays Eq 7.12's −10 until the episode's end (as in
/// the Gym tasks, a drop does not end the episode: ending it would spare the policy the rest of
/// the episode's costs and make dropping pay).
pub const DROP_Z: f64 = 0.0;
/// The largest change of an actuator's command in one control step, as a share of its range
/// (a finger crosses its range in 0.4 s at full speed).
pub const ACTION_STEP: f64 = 0.1;
/// Time the object settles on the still hand before an episode starts, s.
pub const SETTLE_S: f64 = 0.3;
/// Sliding, torsional and rolling friction of the object.
const OBJECT_FRICTION: [f64; 3] = [1.0, 0.005, 0.0001];
/// Density of the objects (the block weighs 50 g, the egg 36 g), kg/m³.
const OBJECT_DENSITY: f64 = 400.0;

/// The object of a rotation task (Fig 7.6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum InHandObject {
    /// A 5 cm cube.
    Block,
    /// An ellipsoid 6.8 × 5 × 5 cm lying on its side.
    Egg,
}

/// Which target orientations an episode draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TargetRotation {
    /// About the vertical (the palm's normal), any angle: the object stays on the palm.
    Z,
    /// Any orientation (uniform over rotations): the object has to be rolled over.
    Xyz,
}

/// A task: the object and the targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InHandTask {
    pub object: InHandObject,
    pub rotation: TargetRotation,
}

/// The compiled scene and the addresses an episode reads.
pub struct InHandScene {
    pub model: MjModel,
    pub task: InHandTask,
    /// The hand's joints (names without the scene prefix) with their qpos and dof addresses.
    pub hand_joints: Vec<(String, usize, usize)>,
    /// qpos address of the object's free joint.
    pub object_qpos: usize,
    object_dof: usize,
    target_mocap: usize,
    /// Every hand actuator's id and command range.
    actuators: Vec<(usize, [f64; 2])>,
}

impl InHandScene {
    /// The scene's MJCF: `hand` attached as its model places it, the object above the palm and
    /// a mocap ghost of the target (no contacts).
    pub fn xml(hand: &SimHand, task: InHandTask) -> Result<String, SimError> {
        let file = hand
            .model
            .canonicalize()
            .map_err(|e| SimError::Input(format!("hands: model {}: {e}", hand.model.display())))?;
        let shape = match task.object {
            InHandObject::Block => "type=\"box\" size=\"0.025 0.025 0.025\"",
            InHandObject::Egg => "type=\"ellipsoid\" size=\"0.034 0.025 0.025\"",
        };
        let [x, y, z] = OBJECT_START;
        let [f0, f1, f2] = OBJECT_FRICTION;
        let mut s = String::new();
        let _ = writeln!(s, "<mujoco model=\"graspd-sim in-hand\">");
        let _ = writeln!(
            s,
            "  <option timestep=\"{TIMESTEP}\" cone=\"elliptic\" impratio=\"10\" \
             integrator=\"implicitfast\"/>"
        );
        let _ = writeln!(
            s,
            "  <asset><model name=\"hand\" file=\"{}\"/></asset>",
            xml_escape(&file.to_string_lossy())
        );
        let _ = writeln!(s, "  <worldbody>");
        let _ = writeln!(
            s,
            "    <light pos=\"0.3 0 1\" dir=\"0 0 -1\" directional=\"true\"/>"
        );
        let _ = writeln!(
            s,
            "    <body name=\"mount\"><attach model=\"hand\" body=\"{}\" prefix=\"{HAND_PREFIX}\"/></body>",
            xml_escape(&hand.root_body)
        );
        let _ = writeln!(
            s,
            "    <body name=\"object\" pos=\"{x} {y} {z}\"><freejoint name=\"object\"/>\
             <geom name=\"object\" {shape} density=\"{OBJECT_DENSITY}\" condim=\"4\" \
             friction=\"{f0} {f1} {f2}\" rgba=\"0.9 0.5 0.2 1\"/></body>"
        );
        let _ = writeln!(
            s,
            "    <body name=\"target\" mocap=\"true\" pos=\"{x} {} {z}\"><geom {shape} \
             contype=\"0\" conaffinity=\"0\" rgba=\"0.2 0.8 0.2 0.4\"/></body>",
            y + 0.12
        );
        let _ = writeln!(s, "  </worldbody>\n</mujoco>");
        Ok(s)
    }

    /// Compiles the scene of `task` with `hand` (its servo gains scaled as in every graspd-sim
    /// scene).
    pub fn build(hand: &SimHand, task: InHandTask) -> Result<Self, SimError> {
        let mut model = MjModel::from_xml_string(&Self::xml(hand, task)?)
            .map_err(|e| SimError::Sim(format!("compiling the in-hand scene: {e}")))?;
        scale_servo_gains(&mut model, hand.servo_gain_scale);
        let id = |t: MjtObjBase, name: &str| {
            model
                .name_to_id(t, name)
                .ok_or_else(|| SimError::Sim(format!("in-hand scene has no {t:?} `{name}`")))
        };
        let object_joint = id(MjtObjBase::mjOBJ_JOINT, "object")?;
        let target = id(MjtObjBase::mjOBJ_BODY, "target")?;
        let mut hand_joints = Vec::new();
        for j in 0..model.ffi().njnt as usize {
            if let Some(name) = model
                .id_to_name(MjtObjBase::mjOBJ_JOINT, j)
                .and_then(|n| n.strip_prefix(HAND_PREFIX))
            {
                hand_joints.push((
                    name.to_string(),
                    model.jnt_qposadr()[j] as usize,
                    model.jnt_dofadr()[j] as usize,
                ));
            }
        }
        let actuators = (0..model.ffi().nu as usize)
            .filter(|&a| {
                model
                    .id_to_name(MjtObjBase::mjOBJ_ACTUATOR, a)
                    .is_some_and(|n| n.starts_with(HAND_PREFIX))
            })
            .map(|a| (a, model.actuator_ctrlrange()[a]))
            .collect::<Vec<_>>();
        if hand_joints.is_empty() || actuators.is_empty() {
            return Err(SimError::Input(format!(
                "hands: {} has no joints or no actuators to manipulate with",
                hand.name
            )));
        }
        Ok(InHandScene {
            object_qpos: model.jnt_qposadr()[object_joint] as usize,
            object_dof: model.jnt_dofadr()[object_joint] as usize,
            target_mocap: model.body_mocapid()[target] as usize,
            model,
            task,
            hand_joints,
            actuators,
        })
    }

    /// Length of the state: joint angles and velocities, the object's velocity (6) and pose (7),
    /// the target pose (7).
    pub fn state_dim(&self) -> usize {
        2 * self.hand_joints.len() + 20
    }

    /// Length of the action: one relative command per actuator.
    pub fn action_dim(&self) -> usize {
        self.actuators.len()
    }
}

/// What one control step did.
#[derive(Debug, Clone)]
pub struct InHandStep {
    /// s_{t+1}.
    pub state: Vec<f32>,
    /// r_ext (Eq 7.12).
    pub r_ext: f64,
    /// The orientation's distance to the target, rad.
    pub angle: f64,
    /// Within [`SUCCESS_ANGLE`] of the target (and in the hand).
    pub success: bool,
    /// The object has left the hand (at this step or before).
    pub dropped: bool,
    /// The episode is over: [`EPISODE_STEPS`] taken.
    pub done: bool,
}

/// One environment: the scene's data, the episode's target and its random source.
pub struct InHandEnv<'a> {
    scene: &'a InHandScene,
    pub data: MjData<&'a MjModel>,
    target: UnitQuaternion<f64>,
    steps: usize,
    dropped: bool,
    rng: ChaCha8Rng,
}

impl<'a> InHandEnv<'a> {
    /// An environment whose episodes draw from `seed`; call [`Self::reset`] first.
    pub fn new(scene: &'a InHandScene, seed: u64) -> Self {
        InHandEnv {
            scene,
            data: scene.model.make_data(),
            target: UnitQuaternion::identity(),
            steps: 0,
            dropped: false,
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0x1d_4a4d_0b1e),
        }
    }

    /// A new episode: the open hand, the object dropped onto the palm at a random yaw (±5 mm
    /// about [`OBJECT_START`]) and left to settle, a random target. Returns s₀.
    pub fn reset(&mut self) -> Vec<f32> {
        let s = self.scene;
        self.data = s.model.make_data();
        let yaw = self.rng.random_range(-PI..PI);
        let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw);
        let a = s.object_qpos;
        let jitter = [
            self.rng.random_range(-0.005..0.005),
            self.rng.random_range(-0.005..0.005),
        ];
        let qpos = self.data.qpos_mut();
        qpos[a] = OBJECT_START[0] + jitter[0];
        qpos[a + 1] = OBJECT_START[1] + jitter[1];
        qpos[a + 2] = OBJECT_START[2];
        qpos[a + 3..a + 7].copy_from_slice(&[q.w, q.i, q.j, q.k]);
        self.target = match s.task.rotation {
            TargetRotation::Z => {
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), self.rng.random_range(-PI..PI))
            }
            TargetRotation::Xyz => random_orientation(&mut self.rng),
        };
        let t = self.target;
        self.data.mocap_quat_mut()[s.target_mocap] = [t.w, t.i, t.j, t.k];
        // The servos hold the open hand (every command 0: the Menagerie Shadow's flat hand).
        for &(act, [lo, hi]) in &s.actuators {
            self.data.ctrl_mut()[act] = 0.0_f64.clamp(lo, hi);
        }
        self.data.forward();
        for _ in 0..(SETTLE_S / TIMESTEP).round() as usize {
            self.data.step();
        }
        self.steps = 0;
        self.dropped = false;
        self.state()
    }

    /// One control step: each actuator's command moved by `action` (each in [−1, 1], clamped;
    /// a non-finite one holds its actuator, as 0 does, so that a diverged policy cannot put NaN
    /// into the simulation) times [`ACTION_STEP`] of its command range, kept in the range, then [`SUBSTEPS`]
    /// simulation steps. Relative to the commanded angle, not the measured one: an action of 0
    /// holds the posture (relative to the measured angle, the servos would push nothing back
    /// against gravity and the hand would sag).
    pub fn step(&mut self, action: &[f32]) -> InHandStep {
        let s = self.scene;
        for (&(act, [lo, hi]), &u) in s.actuators.iter().zip(action) {
            let u = if u.is_finite() {
                f64::from(u).clamp(-1.0, 1.0)
            } else {
                0.0
            };
            let now = self.data.ctrl()[act];
            self.data.ctrl_mut()[act] = (now + u * ACTION_STEP * (hi - lo)).clamp(lo, hi);
        }
        for _ in 0..SUBSTEPS {
            self.data.step();
        }
        self.steps += 1;
        self.dropped |= self.object_position()[2] < DROP_Z;
        let angle = orientation_difference(&self.object_orientation(), &self.target);
        let success = !self.dropped && angle < SUCCESS_ANGLE;
        InHandStep {
            state: self.state(),
            r_ext: if self.dropped {
                dropped_reward()
            } else {
                extrinsic_reward(-angle)
            },
            angle,
            success,
            dropped: self.dropped,
            done: self.steps >= EPISODE_STEPS,
        }
    }

    /// The hand's joint angles in the scene's joint order.
    pub fn joint_angles(&self) -> Vec<f64> {
        let qpos = self.data.qpos();
        self.scene
            .hand_joints
            .iter()
            .map(|(_, q, _)| qpos[*q])
            .collect()
    }

    pub fn object_position(&self) -> [f64; 3] {
        let a = self.scene.object_qpos;
        let q = self.data.qpos();
        [q[a], q[a + 1], q[a + 2]]
    }

    pub fn object_orientation(&self) -> UnitQuaternion<f64> {
        let a = self.scene.object_qpos + 3;
        let q = self.data.qpos();
        UnitQuaternion::from_quaternion(Quaternion::new(q[a], q[a + 1], q[a + 2], q[a + 3]))
    }

    pub fn target(&self) -> UnitQuaternion<f64> {
        self.target
    }

    /// The state: joint angles, joint velocities, the object's velocity (linear, angular), its
    /// position and orientation, the target position and orientation (quaternions w, x, y, z
    /// with w ≥ 0: q and −q are one orientation, and the sign flip would be a jump in the state).
    pub fn state(&self) -> Vec<f32> {
        let s = self.scene;
        let (qpos, qvel) = (self.data.qpos(), self.data.qvel());
        let mut v: Vec<f64> = Vec::with_capacity(s.state_dim());
        v.extend(s.hand_joints.iter().map(|(_, q, _)| qpos[*q]));
        v.extend(s.hand_joints.iter().map(|(_, _, d)| qvel[*d]));
        v.extend_from_slice(&qvel[s.object_dof..s.object_dof + 6]);
        v.extend_from_slice(&self.object_position());
        v.extend_from_slice(&canonical(&self.object_orientation()));
        v.extend_from_slice(&OBJECT_START);
        v.extend_from_slice(&canonical(&self.target));
        v.into_iter().map(|x| x as f32).collect()
    }
}

/// w, x, y, z with w ≥ 0.
fn canonical(q: &UnitQuaternion<f64>) -> [f64; 4] {
    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
    [s * q.w, s * q.i, s * q.j, s * q.k]
}

/// An orientation drawn uniformly over all rotations: a normalised 4-D standard normal.
fn random_orientation(rng: &mut ChaCha8Rng) -> UnitQuaternion<f64> {
    loop {
        let mut g = || rng.sample::<f64, _>(StandardNormal);
        let q = Quaternion::new(g(), g(), g(), g());
        if q.norm() > 1e-6 {
            return UnitQuaternion::from_quaternion(q);
        }
    }
}
