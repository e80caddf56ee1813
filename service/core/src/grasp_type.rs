//! The six grasp types and the five hand parts of the method (method.md §1, dissertation Fig 4.3,
//! Eq 5.1).

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Grasp type s = 1..6, derived from Feix's GRASP taxonomy (Eq 5.1, Fig 4.3).
///
/// The declaration order is the dissertation's order and the order of every per-type array in the
/// API (probabilities, scores, model outputs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GraspType {
    LargeWrap,
    SmallWrap,
    Power,
    Pinch,
    Precision,
    Tripod,
}

impl GraspType {
    /// All six types in the dissertation's order s = 1..6.
    pub const ALL: [GraspType; 6] = [
        GraspType::LargeWrap,
        GraspType::SmallWrap,
        GraspType::Power,
        GraspType::Pinch,
        GraspType::Precision,
        GraspType::Tripod,
    ];

    /// The snake_case name used in the API and in hand data files.
    pub fn name(self) -> &'static str {
        match self {
            GraspType::LargeWrap => "large_wrap",
            GraspType::SmallWrap => "small_wrap",
            GraspType::Power => "power",
            GraspType::Pinch => "pinch",
            GraspType::Precision => "precision",
            GraspType::Tripod => "tripod",
        }
    }

    /// Zero-based index (s − 1).
    pub fn index(self) -> usize {
        self as usize
    }

    pub fn from_index(i: usize) -> Option<Self> {
        Self::ALL.get(i).copied()
    }

    /// The opposing hand parts (h1, h2) of the pregrasping opposition O^s_{h1-h2} (Eq 5.1).
    pub fn opposition_parts(self) -> (HandPart, HandPart) {
        match self {
            GraspType::LargeWrap | GraspType::Power => {
                (HandPart::ThumbSurface, HandPart::FingerSurface)
            }
            GraspType::SmallWrap => (HandPart::Palm, HandPart::FingerSurface),
            GraspType::Pinch | GraspType::Precision | GraspType::Tripod => {
                (HandPart::ThumbTip, HandPart::FingerTip)
            }
        }
    }

    /// Whether the hand closes its fingers around the object with the palm close to it (wraps and
    /// power) rather than holding it at the fingertips (pinch, precision, tripod).
    pub fn is_power(self) -> bool {
        matches!(
            self,
            GraspType::LargeWrap | GraspType::SmallWrap | GraspType::Power
        )
    }

    /// Preference order used to map a type the hand cannot realise to the nearest one it can
    /// (method.md §2). The first realisable entry wins; the table follows the Feix taxonomy's
    /// neighbourhoods (power ↔ wraps, precision ↔ tripod ↔ pinch).
    pub fn nearest_types(self) -> [GraspType; 5] {
        use GraspType::*;
        match self {
            LargeWrap => [Power, SmallWrap, Precision, Tripod, Pinch],
            SmallWrap => [LargeWrap, Power, Tripod, Pinch, Precision],
            Power => [LargeWrap, SmallWrap, Precision, Tripod, Pinch],
            Pinch => [Tripod, Precision, SmallWrap, Power, LargeWrap],
            Precision => [Tripod, Pinch, Power, LargeWrap, SmallWrap],
            Tripod => [Precision, Pinch, Power, SmallWrap, LargeWrap],
        }
    }
}

impl fmt::Display for GraspType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for GraspType {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        GraspType::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown grasp type '{s}' (expected one of large_wrap, small_wrap, power, pinch, precision, tripod)"
                )
            })
    }
}

/// A hand part (Fig 5.3): thumb tip, thumb surface, finger tip, finger surface, palm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum HandPart {
    #[serde(rename = "TT")]
    ThumbTip,
    #[serde(rename = "TS")]
    ThumbSurface,
    #[serde(rename = "FT")]
    FingerTip,
    #[serde(rename = "FS")]
    FingerSurface,
    #[serde(rename = "P")]
    Palm,
}

impl HandPart {
    pub const ALL: [HandPart; 5] = [
        HandPart::ThumbTip,
        HandPart::ThumbSurface,
        HandPart::FingerTip,
        HandPart::FingerSurface,
        HandPart::Palm,
    ];

    /// The abbreviation of the dissertation (TT, TS, FT, FS, P).
    pub fn code(self) -> &'static str {
        match self {
            HandPart::ThumbTip => "TT",
            HandPart::ThumbSurface => "TS",
            HandPart::FingerTip => "FT",
            HandPart::FingerSurface => "FS",
            HandPart::Palm => "P",
        }
    }

    /// Tip parts touch with the distal pad; surface parts with the inner phalanges.
    pub fn is_tip(self) -> bool {
        matches!(self, HandPart::ThumbTip | HandPart::FingerTip)
    }

    pub fn is_thumb(self) -> bool {
        matches!(self, HandPart::ThumbTip | HandPart::ThumbSurface)
    }
}

impl fmt::Display for HandPart {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.code())
    }
}

impl FromStr for HandPart {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        HandPart::ALL
            .into_iter()
            .find(|p| p.code() == s)
            .ok_or_else(|| format!("unknown hand part '{s}' (expected TT, TS, FT, FS or P)"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opposition_table_matches_eq_5_1() {
        use HandPart::*;
        let expect = [
            (ThumbSurface, FingerSurface),
            (Palm, FingerSurface),
            (ThumbSurface, FingerSurface),
            (ThumbTip, FingerTip),
            (ThumbTip, FingerTip),
            (ThumbTip, FingerTip),
        ];
        for (t, e) in GraspType::ALL.iter().zip(expect) {
            assert_eq!(t.opposition_parts(), e, "{t}");
        }
    }

    #[test]
    fn names_round_trip() {
        for t in GraspType::ALL {
            assert_eq!(t.name().parse::<GraspType>().unwrap(), t);
            assert_eq!(GraspType::from_index(t.index()), Some(t));
        }
        assert!("grab".parse::<GraspType>().is_err());
        for p in HandPart::ALL {
            assert_eq!(p.code().parse::<HandPart>().unwrap(), p);
        }
    }

    #[test]
    fn nearest_types_never_list_self_and_cover_the_rest() {
        for t in GraspType::ALL {
            let n = t.nearest_types();
            assert!(!n.contains(&t));
            let mut all: Vec<_> = n.to_vec();
            all.push(t);
            all.sort();
            all.dedup();
            assert_eq!(all.len(), 6);
        }
    }
}
