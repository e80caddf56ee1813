//! How graspd-sim drives a hand model: which model file, which body to mount, which graspd hand
//! plans for it, its closing actuators and the squeeze depth it asks graspd for.
//!
//! Everything is derived from the MJCF model (issue 15), so any hand graspd can register can be
//! simulated; a hand TOML (`clients/sim/hands/*.toml`, or a file given by path) only overrides:
//! - **mounted body**: the model's top body (the first child of its world body);
//! - **closing actuators**: the actuators whose length changes between the hand open and closed
//!   as graspd's synergy closes it (`graspd_core::hand::kinematics::HandSynergy`: flexion joints
//!   from the open pose to their far limits, linkages projected), MuJoCo computing the lengths
//!   through each actuator's own transmission (joint, tendon, gear); open and closed commands
//!   are the position servos' commands at those lengths, within the control range;
//! - **squeeze depth** (how far graspd's squeeze presses each contact into the object): when
//!   every closing servo has a force limit, graspd's largest (5 cm): the servos then press at
//!   their own force limits, as a robot's gripper closes "until force"; the saturating error
//!   computed from gain and force range alone proved too small in MuJoCo, where linkages and
//!   soft contacts give way (the 2F-85 held 65 % of the Table 5.2 trials at it, 85 % at 5 cm);
//!   with unlimited servos the depth at which each servo, at its gain (scaled by
//!   `servo_gain_scale`), pushes [`GRIP_FORCE`] at the far end of the finger it moves
//!   (`d = F·r² / (kp·gear²)`, r the lever from its joint to the farthest geom it carries), the
//!   largest over the hand's closing servos that flex a synergy flexion joint, within
//!   [[`MIN_SQUEEZE_DEPTH`], [`MAX_SQUEEZE_DEPTH`]]; any other unlimited servo (a tendon, an
//!   abduction) counts at [`MIN_SQUEEZE_DEPTH`];
//! - **balanced grip**: when every closing servo has a force limit, there are two or more, and
//!   the weakest flexion servo among them pushes at least [`BALANCE_MARGIN`] × [`GRIP_FORCE`]
//!   at its limit at the far end of its finger (limit · gear / lever), the close keeps the
//!   plan's squeeze proportions within the limits (`closing::within_force_limits`, the most
//!   loaded servo at its limit): the hand has force to spare, and servos that saturate one by
//!   one no longer push in the proportions graspd balanced (Table 5.2, 20 trials, paired: the
//!   Barrett, 33 N, 143 → 149 of 160, the banana 9 → 13, no object lost, with the most loaded
//!   servo asked twice its limit; at its limit, session 13: fused views 148 → 155, all 13
//!   objects 253 → 248 — the sugar box 20 → 15 —, Table 5.2 153 → 153). A weaker hand needs
//!   all its force: the Shadow (6.5 N) went 126 → 120 at the same rule, 91 at margin 1 (its
//!   objects slipped in the lift), 114 with half its servos at their limits and 121 with every
//!   one at least at its limit; it squeezes as planned, its servos saturating where they must
//!   (session 13, six Table 5.2 objects: in proportion at its limits it knocks no object away in
//!   the close, but holds the soup can 17 → 5 and the mustard bottle 13 → 5 of 20); once the
//!   object slides, the grip reflex (`grip_reflex.rs`) adds each force-limited servo's share of
//!   the balanced grip, the most loaded at its limit;
//! - **graspd name**: the model's name (`<mujoco model=…>`) made a graspd name.

use crate::SimError;
use graspd_core::hand::kinematics::{HandSynergy, KinematicHand};
use mujoco_rs::prelude::*;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The built-in simulation hands: (name, TOML).
const BUILT_IN: [(&str, &str); 4] = [
    ("robotiq_2f85", include_str!("../hands/robotiq_2f85.toml")),
    ("barrett", include_str!("../hands/barrett.toml")),
    ("shadow", include_str!("../hands/shadow.toml")),
    ("allegro", include_str!("../hands/allegro.toml")),
];

/// The largest squeeze depth graspd accepts (`options.squeeze_depth`), m.
pub const MAX_SQUEEZE_DEPTH: f64 = 0.05;

/// The smallest squeeze depth derived for a hand with unlimited servos, m (a grasp benchmark's
/// squeeze, DexGraspBench's order).
pub const MIN_SQUEEZE_DEPTH: f64 = 0.005;

/// The push an unlimited closing servo is asked for at the far end of its finger, N: twice the
/// weight of a 1 kg object held between two opposed fingers at friction 1 — what a hand meant
/// for household objects should squeeze with, whatever its servos' gains.
pub const GRIP_FORCE: f64 = 10.0;

/// A hand grips balanced within its force limits (`closing::within_force_limits`) when its
/// weakest force-limited flexion servo pushes at least this many [`GRIP_FORCE`]s at its limit
/// at the far end of its finger.
pub const BALANCE_MARGIN: f64 = 2.0;

/// One closing actuator and its command range.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ClosingActuator {
    pub name: String,
    /// Command with the finger fully open.
    pub open: f64,
    /// Command with the finger fully closed.
    pub closed: f64,
}

/// A hand TOML: every field but the model is an override of the derivation.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct HandToml {
    model: PathBuf,
    graspd_hand: Option<String>,
    label: Option<String>,
    root_body: Option<String>,
    squeeze_depth: Option<f64>,
    #[serde(default)]
    actuators: Vec<ClosingActuator>,
    #[serde(default)]
    tactile_bodies: Vec<String>,
    pad_friction: Option<f64>,
    servo_gain_scale: Option<f64>,
    balanced_grip: Option<bool>,
}

/// A simulated hand.
#[derive(Debug, Clone)]
pub struct SimHand {
    /// Short name (`robotiq_2f85`, `barrett`, …, or the file's stem).
    pub name: String,
    /// Name of the hand in graspd (registered from `model` when the server lacks it).
    pub graspd_hand: String,
    /// Name for tables.
    pub label: String,
    /// MJCF file (relative paths are taken in the hands folder).
    pub model: PathBuf,
    /// The body of the model mounted on the 6-DoF base (the model's top body: the base frame is
    /// then the model's world frame, graspd's `root_pose`).
    pub root_body: String,
    /// The closing actuators with their open and closed commands.
    pub actuators: Vec<ClosingActuator>,
    /// How far graspd's squeeze presses each contact into the object, m.
    pub squeeze_depth: f64,
    /// Bodies that carry a simulated BioTac (the finger pads), for the tactile closed loop.
    pub tactile_bodies: Vec<String>,
    /// Sliding friction of those pads, for sizing the grip force.
    pub pad_friction: Option<f64>,
    /// Factor on the position gain (and the matching stiffness bias) of every actuator of the
    /// hand in the scene: the documented asset change DexGraspBench makes to the MuJoCo
    /// Menagerie hands (kp 1 → 5), whose servos are otherwise too weak to hold 100 g. 1 keeps
    /// the model as it is.
    pub servo_gain_scale: f64,
    /// Whether the close keeps the plan's squeeze proportions within the actuators' force
    /// limits (module rules; `closing::within_force_limits`) instead of letting the servos
    /// saturate one by one.
    pub balanced_grip: bool,
}

impl SimHand {
    /// A built-in hand by name, a hand TOML by path, or an MJCF model (`.xml`) by path, derived
    /// (module rules); relative model paths resolve in `hands_dir`.
    pub fn load(name_or_path: &str, hands_dir: &Path) -> Result<Self, SimError> {
        let bad = |e: String| SimError::Input(format!("hands: {name_or_path}: {e}"));
        let (name, toml) = match BUILT_IN.iter().find(|(n, _)| *n == name_or_path) {
            Some((n, t)) => (
                n.to_string(),
                toml::from_str::<HandToml>(t).map_err(|e| bad(e.to_string()))?,
            ),
            None => {
                let p = Path::new(name_or_path);
                let stem = p
                    .file_stem()
                    .and_then(|s| s.to_str())
                    .unwrap_or("hand")
                    .to_string();
                if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml")) {
                    let model = std::path::absolute(p).map_err(|e| bad(e.to_string()))?;
                    (
                        stem,
                        HandToml {
                            model,
                            graspd_hand: None,
                            label: None,
                            root_body: None,
                            squeeze_depth: None,
                            actuators: Vec::new(),
                            tactile_bodies: Vec::new(),
                            pad_friction: None,
                            servo_gain_scale: None,
                            balanced_grip: None,
                        },
                    )
                } else {
                    let text = std::fs::read_to_string(p).map_err(|e| {
                        SimError::Input(format!(
                            "hands: `{name_or_path}` is neither a built-in hand ({}) nor a readable \
                             hand TOML or MJCF file: {e}",
                            Self::built_in_names().join(", ")
                        ))
                    })?;
                    (stem, toml::from_str(&text).map_err(|e| bad(e.to_string()))?)
                }
            }
        };
        if let Some(d) = toml.squeeze_depth
            && !(0.0..=MAX_SQUEEZE_DEPTH).contains(&d)
        {
            return Err(bad(format!(
                "squeeze_depth must be within [0, {MAX_SQUEEZE_DEPTH}] m, got {d}"
            )));
        }
        let gain_scale = toml.servo_gain_scale.unwrap_or(1.0);
        if !(gain_scale.is_finite() && (0.1..=100.0).contains(&gain_scale)) {
            return Err(bad(format!(
                "servo_gain_scale must be within [0.1, 100], got {gain_scale}"
            )));
        }
        let model = hands_dir.join(&toml.model);
        let derived = derive(&model, gain_scale).map_err(|e| match e {
            SimError::Input(m) => bad(m),
            other => other,
        })?;
        Ok(SimHand {
            name,
            graspd_hand: toml.graspd_hand.unwrap_or(derived.graspd_hand),
            label: toml.label.unwrap_or(derived.label),
            model,
            root_body: toml.root_body.unwrap_or(derived.root_body),
            actuators: if toml.actuators.is_empty() {
                derived.actuators
            } else {
                toml.actuators
            },
            squeeze_depth: toml.squeeze_depth.unwrap_or(derived.squeeze_depth),
            tactile_bodies: toml.tactile_bodies,
            pad_friction: toml.pad_friction,
            servo_gain_scale: gain_scale,
            balanced_grip: toml.balanced_grip.unwrap_or(derived.balanced_grip),
        })
    }

    pub fn built_in_names() -> Vec<&'static str> {
        BUILT_IN.iter().map(|(n, _)| *n).collect()
    }
}

/// What the MJCF alone gives (module rules).
struct Derived {
    graspd_hand: String,
    label: String,
    root_body: String,
    actuators: Vec<ClosingActuator>,
    squeeze_depth: f64,
    balanced_grip: bool,
}

fn derive(model_path: &Path, gain_scale: f64) -> Result<Derived, SimError> {
    let input = |e: String| SimError::Input(format!("{}: {e}", model_path.display()));
    let hand = KinematicHand::from_mjcf_file(model_path).map_err(|e| input(e.to_string()))?;
    let synergy = HandSynergy::derive(&hand).map_err(|e| input(e.to_string()))?;
    let mj =
        MjModel::from_xml(model_path).map_err(|e| input(format!("MuJoCo cannot load it: {e}")))?;
    let root_body = mj
        .id_to_name(MjtObjBase::mjOBJ_BODY, 1)
        .ok_or_else(|| input("the model has no body".into()))?
        .to_string();
    // The hand open (the home pose) and closed by the synergy, every finger together.
    let open = {
        let mut q = hand.tree.home_configuration();
        hand.tree
            .project_constraints(&mut q)
            .map_err(|e| input(e.to_string()))?;
        q
    };
    let mut closed = open.clone();
    let all: Vec<(usize, f64)> = (0..hand.fingers.len()).map(|f| (f, 1.0)).collect();
    synergy
        .close(&hand, &mut closed, &all)
        .map_err(|e| input(e.to_string()))?;
    let lengths = |q: &[f64]| -> Vec<f64> {
        let mut data = mj.make_data();
        for (j, joint) in hand.tree.joints.iter().enumerate() {
            if let Some(id) = mj.name_to_id(MjtObjBase::mjOBJ_JOINT, &joint.name) {
                data.qpos_mut()[mj.jnt_qposadr()[id] as usize] = q[j];
            }
        }
        data.forward();
        data.actuator_length().to_vec()
    };
    let (len_open, len_closed) = (lengths(&open), lengths(&closed));
    // Per joint, the lever to the farthest geom origin it carries, in the model's reference pose
    // (qpos0).
    let lever = {
        let mut data = mj.make_data();
        data.forward();
        let parents = mj.body_parentid();
        let carries = |joint_body: usize, mut b: usize| loop {
            if b == joint_body {
                break true;
            }
            if b == 0 {
                break false;
            }
            b = parents[b] as usize;
        };
        let (anchor, geom_at) = (data.xanchor().to_vec(), data.geom_xpos().to_vec());
        let geom_body = mj.geom_bodyid();
        let jb = mj.jnt_bodyid();
        move |j: usize| -> f64 {
            let a = nalgebra::Point3::from(anchor[j]);
            (0..geom_at.len())
                .filter(|&g| carries(jb[j] as usize, geom_body[g] as usize))
                .map(|g| (nalgebra::Point3::from(geom_at[g]) - a).norm())
                .fold(0.0, f64::max)
        }
    };
    // The MuJoCo joints the synergy flexes (abduction and rotation do not press).
    let flexion: Vec<usize> = synergy
        .fingers
        .iter()
        .flat_map(|f| f.flexion.iter())
        .filter_map(|fj| mj.name_to_id(MjtObjBase::mjOBJ_JOINT, &hand.tree.joints[fj.joint].name))
        .collect();
    let (trn, trn_id, gear) = (
        mj.actuator_trntype(),
        mj.actuator_trnid(),
        mj.actuator_gear(),
    );
    let nu = mj.ffi().nu as usize;
    let gain = mj.actuator_gainprm();
    let limited = mj.actuator_forcelimited();
    let mut actuators = Vec::new();
    let mut all_limited = true;
    let mut unlimited_depth: f64 = 0.0;
    // Per force-limited flexion servo, what it pushes at its limit at the far end of its finger.
    let mut far_end_force = f64::INFINITY;
    let range = mj.actuator_forcerange();
    for a in 0..nu {
        let dl = len_closed[a] - len_open[a];
        if dl.abs() < 1e-3 {
            continue;
        }
        let g = gain[a][0];
        let command = |l: f64| servo_command(&mj, a, l);
        let name = mj
            .id_to_name(MjtObjBase::mjOBJ_ACTUATOR, a)
            .unwrap_or_default()
            .to_string();
        actuators.push(ClosingActuator {
            name,
            open: command(len_open[a]),
            closed: command(len_closed[a]),
        });
        all_limited &= limited[a];
        if limited[a] && trn[a] == MjtTrn::mjTRN_JOINT && flexion.contains(&(trn_id[a][0] as usize))
        {
            let r = lever(trn_id[a][0] as usize).max(1e-3);
            far_end_force = far_end_force.min(range[a][1].abs() * gear[a][0].abs() / r);
        }
        if !limited[a] {
            // d = F·r² / k: the contact's travel at which the servo's joint stiffness
            // k = kp·gear² pushes F at lever r.
            let k = g.abs() * gain_scale * gear[a][0] * gear[a][0];
            let d = match trn[a] {
                MjtTrn::mjTRN_JOINT if k > 1e-12 && flexion.contains(&(trn_id[a][0] as usize)) => {
                    let r = lever(trn_id[a][0] as usize);
                    GRIP_FORCE * r * r / k
                }
                _ => MIN_SQUEEZE_DEPTH,
            };
            unlimited_depth = unlimited_depth.max(d);
        }
    }
    if actuators.is_empty() {
        return Err(input(
            "no actuator moves when the hand closes: graspd-sim cannot drive it".into(),
        ));
    }
    let balanced_grip =
        all_limited && actuators.len() >= 2 && far_end_force >= BALANCE_MARGIN * GRIP_FORCE;
    Ok(Derived {
        graspd_hand: graspd_name(&hand.tree.name),
        label: hand.tree.name.clone(),
        root_body,
        actuators,
        squeeze_depth: if all_limited {
            MAX_SQUEEZE_DEPTH
        } else {
            unlimited_depth.clamp(MIN_SQUEEZE_DEPTH, MAX_SQUEEZE_DEPTH)
        },
        balanced_grip,
    })
}

/// A model name as a graspd hand name (letters, digits, `_`, `-`).
fn graspd_name(model: &str) -> String {
    let s: String = model
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect();
    let s = s.trim_matches('_').to_string();
    if s.is_empty() { "hand".into() } else { s }
}

/// The command with which actuator `a`, a position servo (force = g·ctrl + b₁·length), holds
/// `length` with no force: −b₁·length/g, within its control range (the length itself for an
/// actuator that is not a servo).
pub fn servo_command(mj: &MjModel, a: usize, length: f64) -> f64 {
    let (g, b1) = (mj.actuator_gainprm()[a][0], mj.actuator_biasprm()[a][1]);
    let c = if g.abs() > 1e-12 && b1.abs() > 1e-12 {
        -b1 * length / g
    } else {
        length
    };
    let range = mj.actuator_ctrlrange()[a];
    if range[0] < range[1] {
        c.clamp(range[0], range[1])
    } else {
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn graspd_names_are_sanitised() {
        assert_eq!(graspd_name("Shadow Hand (right)"), "shadow_hand__right");
        assert_eq!(graspd_name("allegro_right"), "allegro_right");
        assert_eq!(graspd_name("!!"), "hand");
    }
}
