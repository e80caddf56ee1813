//! The built-in hand catalog, loaded from the data files in `service/hands/` that ship inside the
//! binary (method.md §2: a parallel gripper, a 3-finger Barrett-like and a 5-finger Shadow-like
//! hand).

use super::description::HandDescription;
use crate::error::FieldError;
use std::collections::BTreeMap;

/// The data files of the built-in hands, embedded at compile time.
const BUILTIN_FILES: [(&str, &str); 3] = [
    (
        "parallel_gripper.toml",
        include_str!("../../../hands/parallel_gripper.toml"),
    ),
    ("barrett.toml", include_str!("../../../hands/barrett.toml")),
    ("shadow.toml", include_str!("../../../hands/shadow.toml")),
];

/// Parses and validates a hand description written in TOML (the format of the data files).
pub fn parse_hand_toml(text: &str) -> Result<HandDescription, FieldError> {
    let hand: HandDescription =
        toml::from_str(text).map_err(|e| FieldError::new("hand", e.to_string()))?;
    hand.validate()?;
    Ok(hand)
}

/// Hands by name.
#[derive(Debug, Clone, Default)]
pub struct HandCatalog {
    hands: BTreeMap<String, HandDescription>,
}

impl HandCatalog {
    /// The built-in hands. Panics only if a shipped data file is invalid, which the unit tests
    /// rule out.
    pub fn builtin() -> Self {
        let mut c = Self::default();
        for (file, text) in BUILTIN_FILES {
            let hand = parse_hand_toml(text)
                .unwrap_or_else(|e| panic!("built-in hand file {file} is invalid: {e}"));
            c.hands.insert(hand.name.clone(), hand);
        }
        c
    }

    pub fn get(&self, name: &str) -> Option<&HandDescription> {
        self.hands.get(name)
    }

    pub fn list(&self) -> impl Iterator<Item = &HandDescription> {
        self.hands.values()
    }

    pub fn names(&self) -> Vec<String> {
        self.hands.keys().cloned().collect()
    }

    /// Adds a validated hand; replaces one of the same name.
    pub fn insert(&mut self, hand: HandDescription) -> Result<(), FieldError> {
        hand.validate()?;
        self.hands.insert(hand.name.clone(), hand);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp_type::GraspType::*;

    #[test]
    fn builtin_hands_load_with_the_dissertation_contact_counts() {
        let c = HandCatalog::builtin();
        assert_eq!(c.names(), ["barrett", "parallel_gripper", "shadow"]);
        let count = |h: &str, t| c.get(h).unwrap().resolve_forced(t).unwrap().contact_count();
        assert_eq!(count("parallel_gripper", Pinch), 2);
        assert_eq!(count("barrett", LargeWrap), 3);
        assert_eq!(count("barrett", Tripod), 3);
        assert_eq!(count("shadow", Precision), 5);
        assert_eq!(count("shadow", Tripod), 3);
        assert_eq!(count("shadow", Pinch), 2);
        assert_eq!(count("shadow", SmallWrap), 5);
    }

    #[test]
    fn equivalences_and_nearest_types() {
        let c = HandCatalog::builtin();
        let b = c.get("barrett").unwrap();
        let r = b.resolve_forced(SmallWrap).unwrap();
        assert_eq!((r.grasp_type, r.requested), (LargeWrap, SmallWrap));
        assert_eq!(b.resolve_forced(Precision).unwrap().grasp_type, Tripod);
        let p = c.get("parallel_gripper").unwrap();
        assert!(p.resolve_forced(Tripod).is_none());
        for t in crate::GraspType::ALL {
            assert_eq!(p.resolve_detected(t).grasp_type, Pinch);
        }
        assert_eq!(c.get("shadow").unwrap().realisable_types().len(), 6);
    }

    #[test]
    fn invalid_descriptions_name_the_field() {
        let text = include_str!("../../../hands/barrett.toml");
        let bad = text.replace("max_aperture = 0.16", "max_aperture = -1.0");
        assert_eq!(
            parse_hand_toml(&bad).unwrap_err().field,
            "hand.geometry.max_aperture"
        );
        let bad = text.replace(
            "h2 = [\"f1\", \"f2\"]\n\n[[grasp_types]]\ntype = \"power\"",
            "h2 = [\"f9\"]\n\n[[grasp_types]]\ntype = \"power\"",
        );
        let e = parse_hand_toml(&bad).unwrap_err();
        assert_eq!(e.field, "hand.grasp_types[0].h2");
        assert!(e.message.contains("f9"));
        let bad = text.replace("parts = [\"TT\", \"TS\"]", "parts = [\"FT\"]");
        assert_eq!(
            parse_hand_toml(&bad).unwrap_err().field,
            "hand.fingers[0].parts"
        );
    }
}
