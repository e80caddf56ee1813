//! The evaluation of a contact set against Eq 5.2 — hand frame, palm height, R, G, S, the hand's
//! limits and the collision check — and what both stages share for it ([`SearchContext`]: the
//! object, the hand, the guidance p_att, n_att). Stage-specific feasibility lives in
//! `opposition.rs` (stage 1) and `dual_stage.rs` (stage 2).

use super::annealing::Scored;
use super::collision::{self, FingerContact, PLANE_TOLERANCE, PosedHand};
use super::grasp_plan::Pose;
use super::hand_pose::{self, HandFrame, finger_frame, palm_frame};
use super::object_shape::ObjectShape;
use super::quality::{self, ContactPoint};
use super::request::PlannerOptions;
use super::robustness::{Robustness, resisted_force, robustness, robustness_above};
use crate::cloud::{CloudIndex, LazyNormals, Plane};
use crate::grasp_type::HandPart;
use crate::hand::{HandDescription, ResolvedGrasp};
use nalgebra::{Point3, Vector3};

/// Merit offsets: infeasible configurations rank below every feasible one (|Q| ≤ 2), those that
/// break a geometric limit below those that only miss S ≥ ε or collide.
pub const MERIT_UNSTABLE: f64 = -5.0;
pub const MERIT_COLLIDING: f64 = -6.0;
pub const MERIT_GEOMETRY: f64 = -10.0;

/// The planner's view of one request.
pub struct SearchContext<'a> {
    pub points: &'a [Point3<f64>],
    /// Normals and k-NN lists, computed on first use.
    pub normals: &'a LazyNormals<'a>,
    pub index: &'a CloudIndex,
    pub shape: &'a ObjectShape,
    pub hand: &'a HandDescription,
    pub grasp: &'a ResolvedGrasp,
    pub p_att: Point3<f64>,
    pub n_att: Vector3<f64>,
    /// Approach directions in order of preference (−n_att first).
    pub approach_prefs: Vec<Vector3<f64>>,
    pub plane: Option<Plane>,
    pub options: &'a PlannerOptions,
    /// cos(atan μ): the friction-cone half-angle test.
    pub cos_friction: f64,
    /// Whether the search rejects configurations whose posed parametric hand collides (the
    /// options' `check_collisions`; off for the stage 1 of a hand with kinematics, whose
    /// final-configuration search places the real hand).
    pub collision_checks: bool,
}

impl<'a> SearchContext<'a> {
    /// The same request planned for another grasp type (`grasp`, with its approach
    /// preferences).
    pub fn for_grasp<'b>(
        &'b self,
        grasp: &'b ResolvedGrasp,
        approach_prefs: Vec<Vector3<f64>>,
    ) -> SearchContext<'b>
    where
        'a: 'b,
    {
        SearchContext {
            points: self.points,
            normals: self.normals,
            index: self.index,
            shape: self.shape,
            hand: self.hand,
            grasp,
            p_att: self.p_att,
            n_att: self.n_att,
            approach_prefs,
            plane: self.plane,
            options: self.options,
            cos_friction: self.cos_friction,
            collision_checks: self.collision_checks,
        }
    }
}

/// A contact set assessed against the hand and Eq 5.2 (S and collision aside).
#[derive(Debug, Clone)]
pub struct Assessment {
    /// Sum of normalised limit violations; 0 when every geometric constraint holds.
    pub violation: f64,
    pub reason: Option<String>,
    pub frame: Option<HandFrame>,
    /// Grasp centre (centroid of the contacts).
    pub center: Point3<f64>,
    /// a (opening or polygon area) and h of Eq 5.4.
    pub a: f64,
    pub h: f64,
    pub r: f64,
    pub g: f64,
    pub q: f64,
}

impl Assessment {
    pub fn violated(&mut self, amount: f64, reason: impl FnOnce() -> String) {
        if amount > 0.0 {
            if self.reason.is_none() {
                self.reason = Some(reason());
            }
            self.violation += amount;
        }
    }
}

/// Radius of a fingertip's contact patch for the robustness figure's torsion, m.
pub const PATCH_RADIUS: f64 = 0.01;

impl SearchContext<'_> {
    pub fn contact(&self, i: usize) -> ContactPoint {
        ContactPoint {
            position: self.points[i],
            normal: self.normals.get(i),
        }
    }

    pub fn palm_opposition(&self) -> bool {
        self.grasp.h1_part == HandPart::Palm
    }

    /// The robustness figure ([`super::robustness`]) of `contacts` about the object's estimated
    /// centre of mass; with `gravity`, straight down along the support plane's normal too (else
    /// `gravity` is the weakest axis).
    pub fn robustness(&self, contacts: &[ContactPoint], gravity: bool) -> Robustness {
        let up = self.plane.map(|p| p.normal).filter(|_| gravity);
        robustness(
            contacts,
            &self.shape.center,
            self.shape.radius,
            self.options.friction,
            PATCH_RADIUS,
            up.as_ref(),
        )
    }

    /// The six axes of [`Self::robustness`], stopped once the weakest is known to be at most
    /// `floor` (`Err`, [`super::robustness::robustness_above`]).
    pub fn robustness_above(
        &self,
        contacts: &[ContactPoint],
        floor: f64,
    ) -> Result<Robustness, Robustness> {
        robustness_above(
            contacts,
            &self.shape.center,
            self.shape.radius,
            self.options.friction,
            PATCH_RADIUS,
            None,
            floor,
        )
    }

    /// The force straight down (along the support plane's normal) that `contacts` resist about
    /// the estimated centre of mass (`Robustness::gravity`); None without a plane.
    pub fn gravity_resistance(&self, contacts: &[ContactPoint]) -> Option<f64> {
        self.plane.map(|pl| {
            resisted_force(
                contacts,
                &self.shape.center,
                self.shape.radius,
                self.options.friction,
                PATCH_RADIUS,
                &-pl.normal,
            )
        })
    }

    /// Hand frame, palm height, R, G and Q for contacts split into the h1 and h2 sides, with the
    /// limits every stage shares: opening within [min_aperture, a_max], palm height ≤ h_max, grasp
    /// centre near the object's centre. `weights` = (ω_R, ω_G); `a` is the opening for two contacts
    /// and the grasp-polygon area for more.
    pub fn assess(&self, h1: &[usize], h2: &[usize], weights: [f64; 2]) -> Assessment {
        let mean = |idx: &[usize]| {
            Point3::from(
                idx.iter()
                    .fold(Vector3::zeros(), |a, &i| a + self.points[i].coords)
                    / idx.len() as f64,
            )
        };
        let (c1, c2) = (mean(h1), mean(h2));
        let all: Vec<usize> = h1.iter().chain(h2).copied().collect();
        let center = mean(&all);
        let d = c2 - c1;
        let geo = &self.hand.geometry;
        let mut out = Assessment {
            violation: 0.0,
            reason: None,
            frame: None,
            center,
            a: 0.0,
            h: 0.0,
            r: 0.0,
            g: -std::f64::consts::FRAC_PI_2,
            q: f64::NEG_INFINITY,
        };
        // Opening: the largest h1–h2 distance must fit the hand, the smallest must not be below
        // its closed width.
        let (mut open_max, mut open_min) = (0.0f64, f64::INFINITY);
        for &i in h1 {
            for &j in h2 {
                let dist = (self.points[j] - self.points[i]).norm();
                open_max = open_max.max(dist);
                open_min = open_min.min(dist);
            }
        }
        out.violated((open_max - geo.max_aperture) / geo.max_aperture, || {
            format!(
                "opening {:.1} mm exceeds a_max {:.1} mm",
                open_max * 1e3,
                geo.max_aperture * 1e3
            )
        });
        out.violated((geo.min_aperture - open_min) / geo.max_aperture, || {
            format!(
                "opening {:.1} mm below the hand's minimum {:.1} mm",
                open_min * 1e3,
                geo.min_aperture * 1e3
            )
        });
        let frame = if self.palm_opposition() {
            palm_frame(&d, &self.shape.axes[0])
        } else {
            finger_frame(&d, &self.approach_prefs)
        };
        let Some(frame) = frame else {
            out.violated(1.0, || "contacts coincide".into());
            return out;
        };
        let clearance = if self.palm_opposition() {
            0.0
        } else if self.grasp.h1_part.is_tip() {
            0.01
        } else {
            0.005
        };
        let h = hand_pose::palm_height(self.shape, &center, &frame, clearance);
        out.violated((h - geo.max_height) / geo.max_height, || {
            format!(
                "palm would stand {:.1} mm behind the grasp centre, beyond h_max {:.1} mm",
                h * 1e3,
                geo.max_height * 1e3
            )
        });
        let offset = center - self.shape.center;
        let off = (offset - frame.z * offset.dot(&frame.z)).norm();
        let max_off = self.options.max_center_offset * self.shape.radius;
        out.violated((off - max_off) / self.shape.radius.max(1e-6), || {
            format!(
                "grasp centre {:.1} mm off the object's centre (limit {:.1} mm)",
                off * 1e3,
                max_off * 1e3
            )
        });
        let m = all.len();
        let a = if m <= 2 {
            d.norm()
        } else {
            let pts: Vec<Point3<f64>> = all.iter().map(|&i| self.points[i]).collect();
            quality::polygon_area(&pts)
        };
        let r = quality::reachability(a, h, self.hand.a_max(m), geo.max_height);
        let g = if self.palm_opposition() {
            quality::attention_palm(&self.n_att, &d)
        } else {
            quality::attention(&self.n_att, &d)
        };
        out.frame = Some(frame);
        out.a = a;
        out.h = h;
        out.r = r;
        out.g = g;
        out.q = weights[0] * r + weights[1] * g;
        out
    }

    /// Scores an assessed configuration for the annealing, cheapest checks first (see
    /// `SearchProblem::evaluate`): the hand's limits, the objective against the acceptance
    /// threshold, S ≥ ε, and — only for a new optimum — the collision check. `k1` contacts of
    /// `c` are on the h1 side.
    pub fn score(
        &self,
        a: &Assessment,
        c: &[usize],
        k1: usize,
        threshold: f64,
        best: f64,
    ) -> Scored {
        if a.violation > 0.0 {
            return Scored {
                merit: MERIT_GEOMETRY - a.violation,
                feasible: false,
            };
        }
        if a.q <= threshold {
            return Scored {
                merit: a.q,
                feasible: false,
            };
        }
        let eps = self.options.epsilon;
        let s = self.stability(c);
        if s < eps {
            return Scored {
                merit: MERIT_UNSTABLE - (eps - s),
                feasible: false,
            };
        }
        if a.q > best && self.collision_checks && self.collides(&c[..k1], &c[k1..], a) {
            return Scored {
                merit: MERIT_COLLIDING,
                feasible: false,
            };
        }
        Scored {
            merit: a.q,
            feasible: true,
        }
    }

    /// Why an assessed configuration is infeasible (None when it is feasible).
    pub fn explain(&self, a: &Assessment, c: &[usize], k1: usize) -> Option<String> {
        if a.violation > 0.0 {
            return a.reason.clone();
        }
        let s = self.stability(c);
        if s < self.options.epsilon {
            return Some(format!("S = {s:.3} < ε = {}", self.options.epsilon));
        }
        if self.collision_checks {
            let col = self.collisions(&c[..k1], &c[k1..], a)?;
            if !col.clear() {
                return Some(col.describe());
            }
        }
        None
    }

    /// S of Eq 5.3 for the contacts (with a palm contact modelled as a soft contact too).
    pub fn stability(&self, idx: &[usize]) -> f64 {
        let c: Vec<ContactPoint> = idx.iter().map(|&i| self.contact(i)).collect();
        quality::gii(&c, self.options.torsion_gamma)
    }

    /// The contacts assigned to fingers: h2 contacts in order of their lateral coordinate go to
    /// the h2 fingers in order of their bases' y (likewise h1); a palm contact gets no finger.
    pub fn finger_contacts(
        &self,
        h1: &[usize],
        h2: &[usize],
        frame: &HandFrame,
    ) -> Vec<FingerContact> {
        let mut out = Vec::with_capacity(h1.len() + h2.len());
        let mut assign = |idx: &[usize], fingers: &[usize]| {
            let mut pts: Vec<usize> = idx.to_vec();
            pts.sort_by(|&a, &b| {
                self.points[a]
                    .coords
                    .dot(&frame.y)
                    .total_cmp(&self.points[b].coords.dot(&frame.y))
            });
            let mut fs: Vec<usize> = fingers.to_vec();
            fs.sort_by(|&a, &b| {
                self.hand.fingers[a].base[1].total_cmp(&self.hand.fingers[b].base[1])
            });
            for (p, f) in pts.iter().zip(fs) {
                out.push(FingerContact {
                    finger: f,
                    point: *p,
                    position: self.points[*p],
                    normal: self.normals.get(*p),
                });
            }
        };
        if !self.palm_opposition() {
            assign(h1, &self.grasp.h1_fingers);
        }
        assign(h2, &self.grasp.h2_fingers);
        out
    }

    /// Grasp and pre-grasp poses of an assessed contact set.
    pub fn poses(&self, a: &Assessment) -> Option<(Pose, Pose, HandFrame)> {
        let frame = a.frame?;
        let pose = hand_pose::hand_pose(&a.center, &frame, a.h);
        let pre = hand_pose::pregrasp_pose(&pose, &frame, self.options.pregrasp_distance);
        Some((pose, pre, frame))
    }

    /// The hand posed at the grasp, and pre-shaped (fingers 2 cm open) at the pre-grasp and
    /// halfway along the approach.
    fn posed(&self, h1: &[usize], h2: &[usize], a: &Assessment) -> Option<[PosedHand; 3]> {
        let (pose, pre, frame) = self.poses(a)?;
        let fingers = self.finger_contacts(h1, h2, &frame);
        let back = pre.position - pose.position;
        Some([
            PosedHand::at_grasp(self.hand, &pose, &fingers, self.palm_opposition()),
            PosedHand::preshaped(self.hand, &pose, &fingers, PRESHAPE_OPENING, back),
            PosedHand::preshaped(self.hand, &pose, &fingers, PRESHAPE_OPENING, back / 2.0),
        ])
    }

    /// Whether the posed hand collides (search-time test: plane first, early exit).
    pub fn collides(&self, h1: &[usize], h2: &[usize], a: &Assessment) -> bool {
        let Some(hands) = self.posed(h1, h2, a) else {
            return true;
        };
        if let Some(pl) = self.plane
            && hands
                .iter()
                .any(|h| h.plane_clearance(&pl) < -PLANE_TOLERANCE)
        {
            return true;
        }
        let n = collision::DEFAULT_MIN_POINTS;
        hands
            .iter()
            .any(|h| h.points_inside(self.points, self.index, collision::DEFAULT_TOLERANCE, n) >= n)
    }

    /// Collision counts of the posed hand for the report.
    pub fn collisions(
        &self,
        h1: &[usize],
        h2: &[usize],
        a: &Assessment,
    ) -> Option<CollisionCounts> {
        let hands = self.posed(h1, h2, a)?;
        let count = |h: &PosedHand| {
            h.points_inside(
                self.points,
                self.index,
                collision::DEFAULT_TOLERANCE,
                usize::MAX,
            )
        };
        let plane_clearance = self.plane.map(|pl| {
            hands
                .iter()
                .map(|h| h.plane_clearance(&pl))
                .fold(f64::INFINITY, f64::min)
        });
        Some(CollisionCounts {
            final_points: count(&hands[0]),
            pregrasp_points: count(&hands[1]),
            approach_points: count(&hands[2]),
            plane_clearance,
        })
    }
}

/// How far each fingertip stands off its contact while the hand approaches, m.
pub const PRESHAPE_OPENING: f64 = 0.02;

/// Collision counts of one configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CollisionCounts {
    pub final_points: usize,
    pub pregrasp_points: usize,
    pub approach_points: usize,
    pub plane_clearance: Option<f64>,
}

impl CollisionCounts {
    /// Clear of the cloud (fewer than the noise allowance of points inside) and of the plane
    /// (1 mm tolerance).
    pub fn clear(&self) -> bool {
        let n = collision::DEFAULT_MIN_POINTS;
        self.final_points < n
            && self.pregrasp_points < n
            && self.approach_points < n
            && self.plane_clearance.is_none_or(|c| c >= -PLANE_TOLERANCE)
    }

    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if let Some(c) = self.plane_clearance.filter(|c| *c < -PLANE_TOLERANCE) {
            parts.push(format!(
                "hand reaches {:.1} mm below the support plane",
                -c * 1e3
            ));
        }
        let n = collision::DEFAULT_MIN_POINTS;
        for (what, k) in [
            ("final grasp", self.final_points),
            ("pre-grasp", self.pregrasp_points),
            ("approach", self.approach_points),
        ] {
            if k >= n {
                parts.push(format!("{k} cloud points inside the hand at the {what}"));
            }
        }
        parts.join("; ")
    }
}
