//! The [`HandDescription`] of a [`KinematicHand`], measured on its reachable workspace.
//!
//! [`WORKSPACE_SAMPLES`] joint vectors are drawn uniformly inside the limits with the fixed seed
//! [`WORKSPACE_SEED`]; every finger's contact point (regional centre of its tip) is computed in the
//! hand frame ([`KinematicHand::hand_frame`]) for each. Then, with t the thumb and J the other
//! fingers:
//! - `max_aperture` (a_max of Eq 5.4, two contacts): the largest opening along the closing
//!   direction between the tips' surfaces, max over samples and j ∈ J of (p_j − p_t)·x less
//!   half of each tip's thickness (the smallest extent of its collision bounding box): what an
//!   object may measure to fit between them (the 2F-85: 8.5 cm, not the 9.3 cm between its pad
//!   centres, which let stage 1 propose pinches wider than the gripper opens); `min_aperture`:
//!   the smallest (p_j − p_t)·x, not below 0;
//! - `max_height` (h_max of Eq 5.4): the largest height z of the centroid of all contact points;
//! - `max_polygon_area` (a_max for ≥ 3 contacts): the largest area of the triangle of the thumb
//!   and the two outermost fingers of J (by base y); `max_finger_spread`: the largest distance
//!   between the contact points of neighbouring fingers of J; both only with two or more in J;
//! - palm length, width and thickness: the extents along x, y, z of the bounding box of the palm
//!   body's collision geometry in the hand frame (without collision geometry: the spread of the
//!   finger bases plus one finger width, and one finger width thick);
//! - `finger_width`: the mean over fingers of the middle extent of the tip's collision bounding
//!   box (the width across the pad), else 2 cm;
//! - per finger: `base` = its first joint's anchor, `length` = the farthest its contact point
//!   gets from the base; the thumb offers TT and TS, the others FT and FS;
//! - grasp types (method.md §2): one opposing finger: pinch only (the stage-1 opposition is the
//!   grasp); two: large_wrap, power, pinch, tripod, with small_wrap ≡ large_wrap and
//!   precision ≡ tripod (the Barrett mapping); three or more: all six, precision with every
//!   finger, small_wrap against the palm. Pinch takes the finger of J whose mean contact point is
//!   nearest the thumb's, tripod the two nearest.

use super::hand_model::{KinematicHand, WORKSPACE_SAMPLES, WORKSPACE_SEED, collision_bounds};
use crate::error::FieldError;
use crate::grasp_type::{GraspType, HandPart};
use crate::hand::description::{
    Finger, GraspRealisation, HandDescription, HandGeometry, PALM, TypeEquivalence,
};
use nalgebra::{Point3, Vector3};

/// Finger width used when a fingertip has no collision geometry, m.
const DEFAULT_FINGER_WIDTH: f64 = 0.02;

impl KinematicHand {
    /// Derives and validates the hand description (rules in the module documentation).
    pub fn describe(&self) -> Result<HandDescription, FieldError> {
        let to_hand = self.hand_frame.inverse();
        let configs = self.sample_configurations(WORKSPACE_SAMPLES, WORKSPACE_SEED ^ 0x5eed);
        let samples: Vec<Vec<Point3<f64>>> = self
            .tip_samples_in_palm(&configs)?
            .into_iter()
            .map(|s| s.into_iter().map(|p| to_hand * p).collect())
            .collect();
        let n = self.fingers.len();
        let t = self.thumb;
        let bases: Vec<Point3<f64>> = self
            .finger_bases_in_palm()
            .into_iter()
            .map(|b| to_hand * b)
            .collect();
        let mut others: Vec<usize> = (0..n).filter(|&j| j != t).collect();
        others.sort_by(|&a, &b| bases[a].y.total_cmp(&bases[b].y).then(a.cmp(&b)));

        // Each tip's thickness: the smallest extent of its collision bounds (or its parent's).
        let thickness: Vec<f64> = self
            .fingers
            .iter()
            .map(|f| {
                collision_bounds(&self.tree, f.tip)
                    .or_else(|| collision_bounds(&self.tree, self.tree.bodies[f.tip].parent?))
                    .map_or(0.0, |(lo, hi)| {
                        let e = hi - lo;
                        e.x.min(e.y).min(e.z)
                    })
            })
            .collect();
        let mut max_aperture = f64::NEG_INFINITY;
        let mut min_aperture = f64::INFINITY;
        let mut max_height = f64::NEG_INFINITY;
        let mut max_area: f64 = 0.0;
        let mut max_spread: f64 = 0.0;
        let mut lengths = vec![0.0f64; n];
        let mut centroids = vec![Vector3::zeros(); n];
        for s in &samples {
            for &j in &others {
                let a = s[j].x - s[t].x;
                max_aperture = max_aperture.max(a - 0.5 * (thickness[j] + thickness[t]));
                min_aperture = min_aperture.min(a);
            }
            let c = s.iter().map(|p| p.coords).sum::<Vector3<f64>>() / n as f64;
            max_height = max_height.max(c.z);
            for i in 0..n {
                lengths[i] = lengths[i].max((s[i] - bases[i]).norm());
                centroids[i] += s[i].coords / samples.len() as f64;
            }
            if others.len() >= 2 {
                let (a, b) = (s[others[0]], s[others[others.len() - 1]]);
                max_area = max_area.max(0.5 * (a - s[t]).cross(&(b - s[t])).norm());
                for w in others.windows(2) {
                    max_spread = max_spread.max((s[w[0]] - s[w[1]]).norm());
                }
            }
        }

        let finger_width = {
            let widths: Vec<f64> = self
                .fingers
                .iter()
                .filter_map(|f| {
                    let (lo, hi) = collision_bounds(&self.tree, f.tip).or_else(|| {
                        let p = self.tree.bodies[f.tip].parent?;
                        collision_bounds(&self.tree, p)
                    })?;
                    let mut e = [hi.x - lo.x, hi.y - lo.y, hi.z - lo.z];
                    e.sort_by(f64::total_cmp);
                    Some(e[1])
                })
                .collect();
            if widths.is_empty() {
                DEFAULT_FINGER_WIDTH
            } else {
                widths.iter().sum::<f64>() / widths.len() as f64
            }
        };
        let (palm_length, palm_width, palm_thickness) =
            match collision_bounds(&self.tree, self.palm) {
                Some((lo, hi)) => {
                    let mut a = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
                    let mut b = -a;
                    for i in 0..8 {
                        let corner = Point3::new(
                            if i & 1 == 0 { lo.x } else { hi.x },
                            if i & 2 == 0 { lo.y } else { hi.y },
                            if i & 4 == 0 { lo.z } else { hi.z },
                        );
                        let h = to_hand * corner;
                        a = a.inf(&h);
                        b = b.sup(&h);
                    }
                    (b.x - a.x, b.y - a.y, b.z - a.z)
                }
                None => {
                    let spread = |k: usize| {
                        let v: Vec<f64> = bases.iter().map(|b| b[k]).collect();
                        v.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                            - v.iter().cloned().fold(f64::INFINITY, f64::min)
                    };
                    (
                        spread(0) + finger_width,
                        spread(1) + finger_width,
                        finger_width,
                    )
                }
            };

        let fingers: Vec<Finger> = (0..n)
            .map(|i| Finger {
                name: self.fingers[i].name.clone(),
                thumb: i == t,
                parts: if i == t {
                    vec![HandPart::ThumbTip, HandPart::ThumbSurface]
                } else {
                    vec![HandPart::FingerTip, HandPart::FingerSurface]
                },
                length: lengths[i],
                base: [bases[i].x, bases[i].y, bases[i].z],
            })
            .collect();
        let name = |i: usize| self.fingers[i].name.clone();
        let mut nearest = others.clone();
        nearest.sort_by(|&a, &b| {
            (centroids[a] - centroids[t])
                .norm()
                .total_cmp(&(centroids[b] - centroids[t]).norm())
                .then(a.cmp(&b))
        });
        let thumb = vec![name(t)];
        let all: Vec<String> = others.iter().map(|&j| name(j)).collect();
        let real =
            |grasp_type, h1: Vec<String>, h2: Vec<String>| GraspRealisation { grasp_type, h1, h2 };
        let pinch = real(GraspType::Pinch, thumb.clone(), vec![name(nearest[0])]);
        let (grasp_types, equivalent_types) = match others.len() {
            1 => (vec![pinch], Vec::new()),
            2 => (
                vec![
                    real(GraspType::LargeWrap, thumb.clone(), all.clone()),
                    real(GraspType::Power, thumb.clone(), all.clone()),
                    pinch,
                    real(GraspType::Tripod, thumb.clone(), all.clone()),
                ],
                vec![
                    TypeEquivalence {
                        grasp_type: GraspType::SmallWrap,
                        same_as: GraspType::LargeWrap,
                    },
                    TypeEquivalence {
                        grasp_type: GraspType::Precision,
                        same_as: GraspType::Tripod,
                    },
                ],
            ),
            _ => (
                vec![
                    real(GraspType::LargeWrap, thumb.clone(), all.clone()),
                    real(GraspType::SmallWrap, vec![PALM.to_string()], all.clone()),
                    real(GraspType::Power, thumb.clone(), all.clone()),
                    pinch,
                    real(GraspType::Precision, thumb.clone(), all.clone()),
                    real(
                        GraspType::Tripod,
                        thumb.clone(),
                        vec![name(nearest[0]), name(nearest[1])],
                    ),
                ],
                Vec::new(),
            ),
        };
        let description = HandDescription {
            name: self.name.clone(),
            description: format!(
                "imported from model '{}': palm '{}', thumb '{}', {} fingers; geometry measured on \
                 {WORKSPACE_SAMPLES} seeded joint samples",
                self.tree.name, self.tree.bodies[self.palm].name, self.fingers[t].name, n
            ),
            geometry: HandGeometry {
                palm_width,
                palm_length,
                palm_thickness,
                max_aperture,
                min_aperture: min_aperture.max(0.0),
                max_height,
                finger_width,
                max_polygon_area: (others.len() >= 2).then_some(max_area),
                max_finger_spread: (others.len() >= 2).then_some(max_spread),
            },
            fingers,
            grasp_types,
            equivalent_types,
        };
        description.validate()?;
        Ok(description)
    }
}
