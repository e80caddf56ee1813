//! The one hand description type of graspd (method.md §2, dissertation ch. 5.5.2).
//!
//! A hand is data: its fingers, which hand parts (TT, TS, FT, FS, P) each offers, its geometry and
//! which grasp types it realises with which fingers. The same type is read from the built-in data
//! files, from inline descriptions in requests (JSON or proto) and by the clients.
//!
//! # Hand frame
//! Origin at the centre of the palm's inner surface; **+z** is the approach direction (out of the
//! palm, toward the object); **+x** is the closing direction, from the h1 side (thumb or palm
//! opposition) to the h2 side (the opposing fingers); **+y = z × x** runs across the fingers.
//! Lengths are metres.

use crate::error::FieldError;
use crate::grasp_type::{GraspType, HandPart};
use serde::{Deserialize, Serialize};

/// Geometry that the planner needs: palm box, finger thickness, and the limits a_max, h_max of the
/// reachability measure (Eq 5.4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandGeometry {
    /// Palm extent across the fingers (along y), m.
    pub palm_width: f64,
    /// Palm extent along the closing direction (along x), m.
    pub palm_length: f64,
    /// Palm thickness behind its inner surface (along −z), m.
    pub palm_thickness: f64,
    /// a_max for two contacts: the largest opening between the opposing parts, m (Eq 5.4).
    pub max_aperture: f64,
    /// Smallest opening the opposing parts can close to, m.
    #[serde(default)]
    pub min_aperture: f64,
    /// h_max: the largest height from the grasp centroid to the palm that the fingers reach, m
    /// (Eq 5.4).
    pub max_height: f64,
    /// Finger thickness (collision capsule diameter), m. Also the least distance between two
    /// contacts of neighbouring fingers.
    pub finger_width: f64,
    /// a_max for three or more contacts: the largest grasp-polygon area, m². Default
    /// ½ · max_aperture · finger span (a triangle from the thumb to the outer fingertips).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_polygon_area: Option<f64>,
    /// Largest distance between the contacts of two neighbouring fingers when they splay, m.
    /// Default: 2.5 × the mean spacing of the finger bases, at least 2 × finger_width.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_finger_spread: Option<f64>,
}

/// One finger: a chain from its base on the palm to its tip.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Finger {
    pub name: String,
    /// The thumb (or the finger that opposes the others). Its parts are TT/TS.
    #[serde(default)]
    pub thumb: bool,
    /// Hand parts this finger offers (TT, TS for a thumb; FT, FS for the others).
    pub parts: Vec<HandPart>,
    /// Length from base to tip, m.
    pub length: f64,
    /// Base position in the hand frame, m.
    pub base: [f64; 3],
}

/// How the hand realises one grasp type: which fingers form the two opposing sides.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GraspRealisation {
    #[serde(rename = "type")]
    pub grasp_type: GraspType,
    /// Fingers on the h1 side (thumb side), or `["palm"]` for the palm opposition of small_wrap.
    pub h1: Vec<String>,
    /// Fingers on the h2 side.
    pub h2: Vec<String>,
}

/// A type the hand treats as another (Barrett: small_wrap ≡ large_wrap, precision ≡ tripod).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TypeEquivalence {
    #[serde(rename = "type")]
    pub grasp_type: GraspType,
    pub same_as: GraspType,
}

/// A hand description (method.md §2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandDescription {
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub geometry: HandGeometry,
    pub fingers: Vec<Finger>,
    pub grasp_types: Vec<GraspRealisation>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub equivalent_types: Vec<TypeEquivalence>,
}

/// The literal used for the palm in `h1`.
pub const PALM: &str = "palm";

/// A grasp type resolved against a hand: the fingers and parts of each side, with contact count.
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedGrasp {
    pub grasp_type: GraspType,
    /// The type the caller or the detector asked for, when it was mapped to another.
    pub requested: GraspType,
    pub h1_part: HandPart,
    pub h2_part: HandPart,
    /// Finger indices on the h1 side; empty when h1 is the palm.
    pub h1_fingers: Vec<usize>,
    pub h2_fingers: Vec<usize>,
}

impl ResolvedGrasp {
    /// m, the number of final contacts (the palm counts as one).
    pub fn contact_count(&self) -> usize {
        self.h1_count() + self.h2_fingers.len()
    }

    pub fn h1_count(&self) -> usize {
        if self.h1_part == HandPart::Palm {
            1
        } else {
            self.h1_fingers.len()
        }
    }
}

fn positive(field: String, v: f64, max: f64) -> Result<(), FieldError> {
    if !v.is_finite() || v <= 0.0 || v > max {
        return Err(FieldError::new(
            field,
            format!("must be a finite length in (0, {max}] m, got {v}"),
        ));
    }
    Ok(())
}

impl HandDescription {
    /// Checks every field; the error names the offending field as `hand.<path>`.
    pub fn validate(&self) -> Result<(), FieldError> {
        if self.name.trim().is_empty() || self.name.len() > 64 {
            return Err(FieldError::new("hand.name", "must be 1 to 64 characters"));
        }
        if !self
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.')
        {
            return Err(FieldError::new(
                "hand.name",
                "may contain only ASCII letters, digits, '_', '-' and '.'",
            ));
        }
        let g = &self.geometry;
        positive("hand.geometry.palm_width".into(), g.palm_width, 1.0)?;
        positive("hand.geometry.palm_length".into(), g.palm_length, 1.0)?;
        positive("hand.geometry.palm_thickness".into(), g.palm_thickness, 1.0)?;
        positive("hand.geometry.max_aperture".into(), g.max_aperture, 1.0)?;
        positive("hand.geometry.max_height".into(), g.max_height, 1.0)?;
        positive("hand.geometry.finger_width".into(), g.finger_width, 0.2)?;
        if !g.min_aperture.is_finite() || g.min_aperture < 0.0 || g.min_aperture >= g.max_aperture {
            return Err(FieldError::new(
                "hand.geometry.min_aperture",
                format!(
                    "must be ≥ 0 and below max_aperture ({}), got {}",
                    g.max_aperture, g.min_aperture
                ),
            ));
        }
        if let Some(a) = g.max_polygon_area {
            positive("hand.geometry.max_polygon_area".into(), a, 1.0)?;
        }
        if let Some(s) = g.max_finger_spread {
            positive("hand.geometry.max_finger_spread".into(), s, 1.0)?;
        }
        if self.fingers.is_empty() || self.fingers.len() > 16 {
            return Err(FieldError::new(
                "hand.fingers",
                format!("must list 1 to 16 fingers, got {}", self.fingers.len()),
            ));
        }
        for (i, f) in self.fingers.iter().enumerate() {
            let at = |s: &str| format!("hand.fingers[{i}].{s}");
            if f.name.trim().is_empty() || f.name == PALM {
                return Err(FieldError::new(
                    at("name"),
                    "must be non-empty and not 'palm'",
                ));
            }
            if self.fingers[..i].iter().any(|o| o.name == f.name) {
                return Err(FieldError::new(
                    at("name"),
                    format!("duplicate finger name '{}'", f.name),
                ));
            }
            positive(at("length"), f.length, 0.5)?;
            if f.base.iter().any(|v| !v.is_finite() || v.abs() > 1.0) {
                return Err(FieldError::new(
                    at("base"),
                    "must be three finite coordinates within ±1 m",
                ));
            }
            if f.parts.is_empty() {
                return Err(FieldError::new(at("parts"), "must offer at least one part"));
            }
            for p in &f.parts {
                if *p == HandPart::Palm {
                    return Err(FieldError::new(at("parts"), "a finger cannot offer P"));
                }
                if p.is_thumb() != f.thumb {
                    return Err(FieldError::new(
                        at("parts"),
                        format!(
                            "{} is a {} part but the finger is {}marked thumb",
                            p.code(),
                            if p.is_thumb() { "thumb" } else { "finger" },
                            if f.thumb { "" } else { "not " }
                        ),
                    ));
                }
            }
        }
        if self.grasp_types.is_empty() {
            return Err(FieldError::new(
                "hand.grasp_types",
                "must realise at least one grasp type",
            ));
        }
        for (i, r) in self.grasp_types.iter().enumerate() {
            let at = |s: &str| format!("hand.grasp_types[{i}].{s}");
            if self.grasp_types[..i]
                .iter()
                .any(|o| o.grasp_type == r.grasp_type)
            {
                return Err(FieldError::new(
                    at("type"),
                    format!("{} is listed twice", r.grasp_type),
                ));
            }
            self.resolve_realisation(r)
                .map_err(|(f, m)| FieldError::new(at(f), m))?;
        }
        for (i, e) in self.equivalent_types.iter().enumerate() {
            if self.realisation(e.same_as).is_none() {
                return Err(FieldError::new(
                    format!("hand.equivalent_types[{i}].same_as"),
                    format!("{} is not among the hand's grasp_types", e.same_as),
                ));
            }
            if self.realisation(e.grasp_type).is_some() {
                return Err(FieldError::new(
                    format!("hand.equivalent_types[{i}].type"),
                    format!(
                        "{} is realised directly; it cannot also be an equivalent",
                        e.grasp_type
                    ),
                ));
            }
        }
        Ok(())
    }

    fn finger_index(&self, name: &str) -> Option<usize> {
        self.fingers.iter().position(|f| f.name == name)
    }

    fn resolve_realisation(
        &self,
        r: &GraspRealisation,
    ) -> Result<ResolvedGrasp, (&'static str, String)> {
        let (h1_part, h2_part) = r.grasp_type.opposition_parts();
        let mut h1 = Vec::new();
        if h1_part == HandPart::Palm {
            if r.h1 != [PALM] {
                return Err((
                    "h1",
                    format!("{} opposes the palm: h1 must be [\"palm\"]", r.grasp_type),
                ));
            }
        } else {
            if r.h1.is_empty() {
                return Err(("h1", "must name at least one finger".into()));
            }
            for n in &r.h1 {
                let i = self
                    .finger_index(n)
                    .ok_or_else(|| ("h1", format!("unknown finger '{n}'")))?;
                if !self.fingers[i].parts.contains(&h1_part) {
                    return Err((
                        "h1",
                        format!(
                            "finger '{n}' does not offer {} needed by {}",
                            h1_part.code(),
                            r.grasp_type
                        ),
                    ));
                }
                h1.push(i);
            }
        }
        if r.h2.is_empty() {
            return Err(("h2", "must name at least one finger".into()));
        }
        let mut h2 = Vec::new();
        for n in &r.h2 {
            let i = self
                .finger_index(n)
                .ok_or_else(|| ("h2", format!("unknown finger '{n}'")))?;
            if !self.fingers[i].parts.contains(&h2_part) {
                return Err((
                    "h2",
                    format!(
                        "finger '{n}' does not offer {} needed by {}",
                        h2_part.code(),
                        r.grasp_type
                    ),
                ));
            }
            if h1.contains(&i) || h2.contains(&i) {
                return Err(("h2", format!("finger '{n}' is used twice")));
            }
            h2.push(i);
        }
        Ok(ResolvedGrasp {
            grasp_type: r.grasp_type,
            requested: r.grasp_type,
            h1_part,
            h2_part,
            h1_fingers: h1,
            h2_fingers: h2,
        })
    }

    fn realisation(&self, t: GraspType) -> Option<&GraspRealisation> {
        self.grasp_types.iter().find(|r| r.grasp_type == t)
    }

    /// Grasp types the hand realises directly or through an equivalence.
    pub fn supports(&self, t: GraspType) -> bool {
        self.realisation(t).is_some() || self.equivalent_types.iter().any(|e| e.grasp_type == t)
    }

    /// Resolves a type the caller insists on: realised directly or through an equivalence, else
    /// `None` (the caller gets INVALID_ARGUMENT).
    pub fn resolve_forced(&self, t: GraspType) -> Option<ResolvedGrasp> {
        let target = if self.realisation(t).is_some() {
            t
        } else {
            self.equivalent_types
                .iter()
                .find(|e| e.grasp_type == t)?
                .same_as
        };
        let mut r = self.resolve_realisation(self.realisation(target)?).ok()?;
        r.requested = t;
        Some(r)
    }

    /// Resolves a detected type: as [`Self::resolve_forced`], else the nearest realisable type by
    /// the table of [`GraspType::nearest_types`] (method.md §2).
    pub fn resolve_detected(&self, t: GraspType) -> ResolvedGrasp {
        if let Some(r) = self.resolve_forced(t) {
            return r;
        }
        for n in t.nearest_types() {
            if let Some(mut r) = self.resolve_forced(n) {
                r.requested = t;
                return r;
            }
        }
        // validate() guarantees at least one realisation.
        let mut r = self
            .resolve_realisation(&self.grasp_types[0])
            .expect("validated hand");
        r.requested = t;
        r
    }

    /// Types the hand can realise (directly or by equivalence), in the order s = 1..6.
    pub fn realisable_types(&self) -> Vec<GraspType> {
        GraspType::ALL
            .into_iter()
            .filter(|t| self.supports(*t))
            .collect()
    }

    /// a_max of Eq 5.4 for a grasp with `m` contacts: the aperture for two, the polygon area for
    /// more.
    pub fn a_max(&self, m: usize) -> f64 {
        if m <= 2 {
            return self.geometry.max_aperture;
        }
        self.geometry
            .max_polygon_area
            .unwrap_or(0.5 * self.geometry.max_aperture * self.finger_span())
    }

    /// Lateral span (along y) of the non-thumb fingers' bases plus one finger width.
    pub fn finger_span(&self) -> f64 {
        let ys: Vec<f64> = self
            .fingers
            .iter()
            .filter(|f| !f.thumb)
            .map(|f| f.base[1])
            .collect();
        let (lo, hi) = ys
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &y| {
                (l.min(y), h.max(y))
            });
        if lo.is_finite() {
            (hi - lo) + self.geometry.finger_width
        } else {
            self.geometry.finger_width
        }
    }

    /// Largest distance between contacts of neighbouring fingers.
    pub fn max_finger_spread(&self) -> f64 {
        if let Some(s) = self.geometry.max_finger_spread {
            return s;
        }
        let others = (0..self.fingers.len()).filter(|&i| !self.fingers[i].thumb);
        (2.5 * self.mean_finger_spacing(others)).max(2.0 * self.geometry.finger_width)
    }

    /// Mean gap between neighbouring bases (along y) of the given fingers; 0 for fewer than two.
    pub fn mean_finger_spacing(&self, fingers: impl IntoIterator<Item = usize>) -> f64 {
        let mut ys: Vec<f64> = fingers
            .into_iter()
            .map(|f| self.fingers[f].base[1])
            .collect();
        if ys.len() < 2 {
            return 0.0;
        }
        ys.sort_by(f64::total_cmp);
        (ys[ys.len() - 1] - ys[0]) / (ys.len() - 1) as f64
    }
}
