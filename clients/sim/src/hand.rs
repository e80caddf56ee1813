//! How graspd-sim drives a hand model: which model file, which body to mount, which graspd hand
//! plans for it, and each closing actuator's open and closed command (`clients/sim/hands/*.toml`).

use crate::SimError;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The built-in simulation hands: (name, TOML).
const BUILT_IN: [(&str, &str); 3] = [
    ("robotiq_2f85", include_str!("../hands/robotiq_2f85.toml")),
    ("barrett", include_str!("../hands/barrett.toml")),
    ("shadow", include_str!("../hands/shadow.toml")),
];

/// One closing actuator and its command range.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClosingActuator {
    pub name: String,
    /// Command with the finger fully open.
    pub open: f64,
    /// Command with the finger fully closed.
    pub closed: f64,
}

/// A simulated hand (one TOML file).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimHand {
    /// Name of the hand in graspd (registered from `model` when the server lacks it).
    pub graspd_hand: String,
    /// Name for tables.
    pub label: String,
    /// MJCF file, relative to the hands folder.
    pub model: PathBuf,
    /// The body of the model that is mounted on the 6-DoF base (the model's top body: its pose
    /// relative to the base is the model's own, so the base frame is the model's world frame,
    /// which is graspd's `root_pose`).
    pub root_body: String,
    /// Fraction of each closing actuator's open → closed span commanded past the planned joints.
    pub squeeze: f64,
    /// Fraction of each closing actuator's span the pre-shape opens from the planned joints
    /// (1: fully open).
    pub preshape: f64,
    pub actuators: Vec<ClosingActuator>,
    /// Bodies that carry a simulated BioTac (the finger pads), for the tactile closed loop; the
    /// session's fingers are named after them.
    #[serde(default)]
    pub tactile_bodies: Vec<String>,
    /// Sliding friction of those pads (their geoms' own), for sizing the grip force.
    #[serde(default)]
    pub pad_friction: Option<f64>,
    /// Short name (`robotiq_2f85`, `barrett`, `shadow`, or the TOML's stem).
    #[serde(skip)]
    pub name: String,
}

impl SimHand {
    /// A built-in hand by name, or a TOML file by path.
    pub fn load(name_or_path: &str) -> Result<Self, SimError> {
        let (name, text) = match BUILT_IN.iter().find(|(n, _)| *n == name_or_path) {
            Some((n, t)) => (n.to_string(), t.to_string()),
            None => {
                let p = Path::new(name_or_path);
                let text = std::fs::read_to_string(p).map_err(|e| {
                    SimError::Input(format!(
                        "hands: `{name_or_path}` is neither a built-in hand ({}) nor a readable \
                         file: {e}",
                        Self::built_in_names().join(", ")
                    ))
                })?;
                let stem = p.file_stem().and_then(|s| s.to_str()).unwrap_or("hand");
                (stem.to_string(), text)
            }
        };
        let mut hand: SimHand = toml::from_str(&text)
            .map_err(|e| SimError::Input(format!("hands: {name_or_path}: {e}")))?;
        hand.name = name;
        if !(0.0..=1.0).contains(&hand.squeeze) || !(0.0..=1.0).contains(&hand.preshape) {
            return Err(SimError::Input(format!(
                "hands: {name_or_path}: squeeze and preshape must be within [0, 1]"
            )));
        }
        Ok(hand)
    }

    pub fn built_in_names() -> Vec<&'static str> {
        BUILT_IN.iter().map(|(n, _)| *n).collect()
    }

    /// The model file under `hands_dir`.
    pub fn model_path(&self, hands_dir: &Path) -> PathBuf {
        hands_dir.join(&self.model)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_in_hands_parse_and_close_in_one_direction() {
        for name in SimHand::built_in_names() {
            let h = SimHand::load(name).unwrap();
            assert_eq!(h.name, name);
            assert!(!h.actuators.is_empty(), "{name}");
            for a in &h.actuators {
                assert!(a.open != a.closed, "{name}/{}", a.name);
            }
        }
        assert!(SimHand::load("no_such_hand").is_err());
    }
}
