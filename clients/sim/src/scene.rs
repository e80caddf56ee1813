//! The simulated tabletop: a table, YCB objects as free bodies of convex pieces, and a hand
//! model mounted on a mocap base (a 6-DoF base that follows commanded poses exactly, the way a
//! stiff arm would), with MuJoCo options set for grasping.

use crate::SimError;
use crate::hand::SimHand;
use crate::object::SimObject;
use mujoco_rs::prelude::*;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::fmt::Write as _;
use std::path::Path;

/// Table top half extents (x, y), m; the top is the plane z = 0.
pub const TABLE_HALF: [f64; 2] = [0.4, 0.4];
/// Simulation step, s (the hand models' own).
pub const TIMESTEP: f64 = 0.002;
/// Sliding, torsional and rolling friction of the object geoms (hand geoms keep their own;
/// MuJoCo takes the larger of a pair).
pub const OBJECT_FRICTION: [f64; 3] = [0.9, 0.01, 0.0001];
/// Table friction.
pub const TABLE_FRICTION: [f64; 3] = [0.6, 0.005, 0.0001];
/// Where the hand waits while the camera looks (out of every view).
pub const PARKED: [f64; 3] = [0.0, 0.0, 3.0];

/// Time constant of the weld that holds the base to its target, s (stiff: twice the step is
/// MuJoCo's floor).
pub const BASE_SOLREF: f64 = 0.005;

/// Prefix of every name from the hand model.
pub const HAND_PREFIX: &str = "hand/";

/// A built scene: the compiled model and the ids a trial needs.
pub struct Scene {
    pub model: MjModel,
    /// Body ids of the objects, in the order given.
    pub object_bodies: Vec<usize>,
    /// qpos address of each object's free joint.
    pub object_qpos: Vec<usize>,
    pub table_geom: usize,
    /// Mocap index of the base's target.
    pub mount_mocap: usize,
    /// qpos / qvel address of the base's free joint.
    pub base_qpos: usize,
    pub base_dof: usize,
    /// Body ids of the hand (the mounted subtree).
    pub hand_bodies: Vec<bool>,
    /// (qpos address, joint name without prefix) of every hand joint.
    pub hand_joints: Vec<(usize, String)>,
    /// Actuator ids of the hand's closing actuators with their open and closed commands.
    pub closing: Vec<(usize, f64, f64)>,
    /// Whether the squeeze keeps the plan's proportions within the force limits
    /// ([`SimHand::balanced_grip`]).
    pub balanced_grip: bool,
}

/// The scene's MJCF: `hand_model` is the hand's MJCF file, `objects` the objects with their
/// initial poses.
pub fn scene_xml(
    hand: &SimHand,
    hand_model: &Path,
    objects: &[(&SimObject, Isometry3<f64>)],
) -> Result<String, SimError> {
    let hand_file = hand_model
        .canonicalize()
        .map_err(|e| SimError::Input(format!("hands: model {}: {e}", hand_model.display())))?;
    let mut x = String::new();
    let f = |v: f64| format!("{v:.6}");
    let _ = writeln!(x, "<mujoco model=\"graspd-sim\">");
    // The menagerie hands' own options (elliptic cones, impratio 10) for every hand: attaching
    // keeps the parent's values.
    let _ = writeln!(
        x,
        "  <option timestep=\"{TIMESTEP}\" cone=\"elliptic\" impratio=\"10\" \
         integrator=\"implicitfast\"/>"
    );
    let _ = writeln!(x, "  <asset>");
    let _ = writeln!(
        x,
        "    <model name=\"hand\" file=\"{}\"/>",
        xml_escape(&hand_file.to_string_lossy())
    );
    for (k, (obj, _)) in objects.iter().enumerate() {
        for (i, piece) in obj.pieces.iter().enumerate() {
            let mut v = String::new();
            for p in piece {
                let _ = write!(v, "{} {} {} ", f(p.x), f(p.y), f(p.z));
            }
            let _ = writeln!(
                x,
                "    <mesh name=\"o{k}_p{i}\" vertex=\"{}\"/>",
                v.trim_end()
            );
        }
    }
    let _ = writeln!(x, "  </asset>");
    let _ = writeln!(x, "  <worldbody>");
    let _ = writeln!(
        x,
        "    <light name=\"top\" pos=\"0 0 2\" dir=\"0 0 -1\" directional=\"true\"/>"
    );
    let tf = TABLE_FRICTION;
    let _ = writeln!(
        x,
        "    <geom name=\"table\" type=\"box\" size=\"{} {} 0.02\" pos=\"0 0 -0.02\" \
         rgba=\"0.62 0.6 0.58 1\" friction=\"{} {} {}\"/>",
        TABLE_HALF[0], TABLE_HALF[1], tf[0], tf[1], tf[2]
    );
    let of = OBJECT_FRICTION;
    for (k, (obj, pose)) in objects.iter().enumerate() {
        let (p, q) = (pose.translation.vector, pose.rotation);
        let _ = writeln!(
            x,
            "    <body name=\"object{k}\" pos=\"{} {} {}\" quat=\"{} {} {} {}\">",
            f(p.x),
            f(p.y),
            f(p.z),
            f(q.w),
            f(q.i),
            f(q.j),
            f(q.k)
        );
        let _ = writeln!(x, "      <freejoint name=\"object{k}\"/>");
        let [r, g, b] = obj.rgb;
        let density = obj.density();
        for i in 0..obj.pieces.len() {
            let _ = writeln!(
                x,
                "      <geom type=\"mesh\" mesh=\"o{k}_p{i}\" density=\"{density:.3}\" \
                 rgba=\"{r:.3} {g:.3} {b:.3} 1\" condim=\"4\" friction=\"{} {} {}\"/>",
                of[0], of[1], of[2]
            );
        }
        let _ = writeln!(x, "    </body>");
    }
    // The base: a free body welded to the mocap target. Moving the target drags the base with
    // real velocities, which contact friction needs (a mocap parent would teleport the hand and
    // the fingers would slide off whatever they hold).
    let _ = writeln!(
        x,
        "    <body name=\"mount\" mocap=\"true\" pos=\"{} {} {}\"/>",
        PARKED[0], PARKED[1], PARKED[2]
    );
    let _ = writeln!(
        x,
        "    <body name=\"base\" pos=\"{} {} {}\">",
        PARKED[0], PARKED[1], PARKED[2]
    );
    let _ = writeln!(x, "      <freejoint name=\"base\"/>");
    let _ = writeln!(
        x,
        "      <attach model=\"hand\" body=\"{}\" prefix=\"{HAND_PREFIX}\"/>",
        xml_escape(&hand.root_body)
    );
    let _ = writeln!(x, "    </body>");
    let _ = writeln!(x, "  </worldbody>");
    let _ = writeln!(x, "  <equality>");
    let _ = writeln!(
        x,
        "    <weld name=\"base\" body1=\"mount\" body2=\"base\" relpose=\"0 0 0 1 0 0 0\" \
         solref=\"{BASE_SOLREF} 1\" solimp=\"0.95 0.99 0.001\"/>"
    );
    let _ = writeln!(x, "  </equality>");
    let _ = writeln!(x, "</mujoco>");
    Ok(x)
}

pub(crate) fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
}

impl Scene {
    /// Compiles the scene (see [`scene_xml`]).
    pub fn build(
        hand: &SimHand,
        objects: &[(&SimObject, Isometry3<f64>)],
    ) -> Result<Self, SimError> {
        let xml = scene_xml(hand, &hand.model.clone(), objects)?;
        if let Some(dir) = std::env::var_os("GRASPD_SIM_DEBUG_DIR") {
            let _ = std::fs::write(Path::new(&dir).join("scene.xml"), &xml);
        }
        let mut model = MjModel::from_xml_string(&xml)
            .map_err(|e| SimError::Sim(format!("compiling the scene: {e}")))?;
        scale_servo_gains(&mut model, hand.servo_gain_scale);
        let id = |t: MjtObjBase, name: &str| {
            model
                .name_to_id(t, name)
                .ok_or_else(|| SimError::Sim(format!("scene has no {t:?} `{name}`")))
        };
        let mut object_bodies = Vec::new();
        let mut object_qpos = Vec::new();
        for k in 0..objects.len() {
            object_bodies.push(id(MjtObjBase::mjOBJ_BODY, &format!("object{k}"))?);
            let j = id(MjtObjBase::mjOBJ_JOINT, &format!("object{k}"))?;
            object_qpos.push(model.jnt_qposadr()[j] as usize);
        }
        let table_geom = id(MjtObjBase::mjOBJ_GEOM, "table")?;
        let mount = id(MjtObjBase::mjOBJ_BODY, "mount")?;
        let mount_mocap = model.body_mocapid()[mount] as usize;
        let base = id(MjtObjBase::mjOBJ_BODY, "base")?;
        let base_joint = id(MjtObjBase::mjOBJ_JOINT, "base")?;
        let base_qpos = model.jnt_qposadr()[base_joint] as usize;
        let base_dof = model.jnt_dofadr()[base_joint] as usize;
        let nbody = model.ffi().nbody as usize;
        let parents = model.body_parentid();
        let mut hand_bodies = vec![false; nbody];
        hand_bodies[base] = true;
        // Bodies are numbered parents first.
        for b in 1..nbody {
            let p = parents[b] as usize;
            hand_bodies[b] = hand_bodies[b] || hand_bodies[p];
        }
        let mut hand_joints = Vec::new();
        for j in 0..model.ffi().njnt as usize {
            if j != base_joint && hand_bodies[model.jnt_bodyid()[j] as usize] {
                let name = model
                    .id_to_name(MjtObjBase::mjOBJ_JOINT, j)
                    .unwrap_or_default();
                let name = name.strip_prefix(HAND_PREFIX).unwrap_or(name).to_string();
                hand_joints.push((model.jnt_qposadr()[j] as usize, name));
            }
        }
        let mut closing = Vec::new();
        for a in &hand.actuators {
            let aid = id(
                MjtObjBase::mjOBJ_ACTUATOR,
                &format!("{HAND_PREFIX}{}", a.name),
            )?;
            closing.push((aid, a.open, a.closed));
        }

        Ok(Scene {
            model,
            object_bodies,
            object_qpos,
            table_geom,
            mount_mocap,
            base_qpos,
            base_dof,
            hand_bodies,
            hand_joints,
            closing,
            balanced_grip: hand.balanced_grip,
        })
    }

    /// Whether geom `g` belongs to the hand.
    pub fn is_hand_geom(&self, g: usize) -> bool {
        self.hand_bodies[self.model.geom_bodyid()[g] as usize]
    }
}

/// Pose as MuJoCo's (pos, quat w-x-y-z).
pub fn to_mj(p: &Isometry3<f64>) -> ([f64; 3], [f64; 4]) {
    let t = p.translation.vector;
    let q = p.rotation;
    ([t.x, t.y, t.z], [q.w, q.i, q.j, q.k])
}

/// Pose from a position and a w-x-y-z quaternion.
pub fn from_mj(pos: &[f64; 3], quat: &[f64; 4]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(pos[0], pos[1], pos[2]),
        UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            quat[0], quat[1], quat[2], quat[3],
        )),
    )
}

/// An object standing on the table at (x, y) turned by `yaw` about z.
pub fn on_table(x: f64, y: f64, yaw: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(Vector3::new(x, y, 0.001)),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw),
    )
}

/// Multiplies the position gain of every hand actuator and its stiffness bias by `scale`
/// ([`SimHand::servo_gain_scale`]): force = s·kp·(ctrl − length), the same equilibrium.
pub(crate) fn scale_servo_gains(model: &mut MjModel, scale: f64) {
    if scale == 1.0 {
        return;
    }
    let hand: Vec<bool> = (0..model.ffi().nu as usize)
        .map(|a| {
            model
                .id_to_name(MjtObjBase::mjOBJ_ACTUATOR, a)
                .is_some_and(|n| n.starts_with(HAND_PREFIX))
        })
        .collect();
    // SAFETY: plain numbers of a compiled model no data was made from yet.
    let gain = unsafe { model.actuator_gainprm_mut() };
    for (a, _) in hand.iter().enumerate().filter(|(_, h)| **h) {
        gain[a][0] *= scale;
    }
    let bias = model.actuator_biasprm_mut();
    for (a, _) in hand.iter().enumerate().filter(|(_, h)| **h) {
        bias[a][1] *= scale;
    }
}
