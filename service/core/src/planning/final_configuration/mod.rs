//! The final configuration g = (C_g, Joint_g, Pose_g) of a hand with known kinematics, found
//! with the hand's own model in the loop (issue 15). Stage 1 (the pregrasping opposition) is the
//! front end; after it, for each candidate:
//!
//! 1. **Place** ([`placement`]): the pre-shape's grasp frame on the opposition, turned about it to
//!    each approach to try, the pre-shaped hand moved in along the approach from the pre-grasp
//!    distance until it would touch the object (the visible points and their completion)
//!    or the table — so proposals are clear of both by construction. Fingertip pre-shapes try
//!    several openings (and, for an object wider than the best pre-shape ever opens, touched on
//!    one side only, a wider pre-shape); while a candidate has no feasible one (and the search
//!    still lacks feasible plans) the best opening is tried again with the hand turned about the approach
//!    ([`YAWS_DEG`]): beside a curved or skewed object (a banana, a box seen at a corner) a
//!    fingertip of the row otherwise lands on the object's top and holds the hand up.
//! 2. **Close** ([`closing_sweep`]): the taking-part fingers close along the synergy until their
//!    links touch; fingers that take no part keep the posture (open, or curled) that let the
//!    hand go deepest. The contacts are where the links touch; the grasp joints are the
//!    touching joints.
//! 3. **Squeeze** ([`squeeze`]): each touching finger closed further so that its contacts move up to
//!    `squeeze_depth` into the object along their normals, none outward and no joint opening
//!    (a small linear program per finger; linked groups by one path step), scaled back until
//!    no contact slides across the surface further than the depth — the position servos'
//!    error becomes the grip force; the pre-grasp joints are the pre-shape.
//! 4. **Judge**: feasible when both sides touch, S ≥ ε (Eq 5.3, GII about the contacts; three
//!    or more contacts with [`FIRM_ROBUSTNESS`] may stand in for it; two contacts on a line
//!    inside both friction cones), the
//!    grasp and the squeeze are clear of the table (a squeeze that presses onto it is accepted
//!    when the search has nothing feasible otherwise: `pressed_on_table`) and linked fingers
//!    push the object at most [`MAX_PUSH`]; ranked by the force at the estimated centre of
//!    mass the contacts resist in their weakest direction ([`super::robustness`]), then by Q
//!    of Eq 5.2. A candidate its
//!    contacts alone rule out (one side touched, a pair outside its friction cones or driven
//!    each on its own) gets its squeeze and opening ([`grip`]) only if it is output.
//!
//! Candidates ([`order`]): up to four stage-1 oppositions (from the attention point and the
//! surface point over the centre of mass, `dual_stage::opposition_stage_about`) and the best
//! moved to the height of the estimated centre of mass (these two also with the thumb on the
//! other side) × the approach preferences (−n_att, the rule's approach, −up, −z; each made
//! perpendicular to the opposition) × turns of 0, ±30° and ±60° about the opposition line (a
//! palm opposition: rolls about it), in that order of preference; at most
//! `options.final_candidates` are
//! judged, up to [`WIDENING`] times as many while none is feasible. Deterministic: no clock
//! decides anything.

pub mod closing_sweep;
mod contacts;
mod grip;
mod judge;
mod object_view;
mod order;
pub mod placement;
mod pregrasp;
mod squeeze;

use super::collision::PLANE_TOLERANCE;
use super::evaluation::SearchContext;
use super::grasp_plan::StageStats;
use super::kinematic_model::KinematicModel;
use super::quality::ContactPoint;
use super::robustness::Robustness;
use crate::error::FieldError;
use crate::hand::kinematics::PreShape;
use closing_sweep::SweepContact;
use contacts::unlinked_fingers;
use grip::Pending;
use judge::judge;
use nalgebra::{Isometry3, Vector3};
pub use object_view::{COLLISION_CELL, ObjectView};
use order::candidate_order;

/// Largest push of a linked finger into the object while its group closes, m.
pub const MAX_PUSH: f64 = 0.015;
/// Openings beyond the opposition's width that fingertip pre-shapes try, m (then fully open).
pub const PRESHAPE_MARGINS: [f64; 3] = [0.03, 0.06, 0.1];
/// While no candidate is feasible the search judges up to this many times
/// `options.final_candidates`.
const WIDENING: usize = 3;
/// A feasible grasp this robust (resisted force at the centre of mass per unit grip force per
/// contact, weakest direction) is firm: a kinematic hand tries further grasp types only while
/// none is. Measured on the Table 5.2 run (20 trials per cell): the quarter of executed plans
/// below 0.4–0.6 held 2–42 % of the time, the quarter above 0.7–1.7 held 90–100 %. Widening
/// the candidate search while no candidate reached it changed no hand's rate beyond ±2 % and
/// doubled the Shadow's median planning time, so only infeasibility widens that.
pub const FIRM_ROBUSTNESS: f64 = 0.8;
/// Turns of the hand about the approach (from the opposition's line) tried, with the best
/// opening, while a candidate is not feasible, degrees. Measured (Table 5.2, 20 trials per cell,
/// paired): plans feasible 558 → 590 of 640, held Robotiq 151 → 152, Barrett 133 → 133, Shadow
/// 109 → 111, Allegro 116 → 123 of 160; the planner bench's feasible Shadow 23 → 30 and Robotiq
/// 29 → 34 of 40, at 1.5–2.5 times their median planning time.
const YAWS_DEG: [f64; 4] = [20.0, -20.0, 40.0, -40.0];
/// A contact whose neighbourhood's unit normals have a mean shorter than this lies by an edge
/// (a box's or a can's rim; its neighbourhood: [`closing_sweep::COHERENCE_RADIUS`]): its mean
/// normal is neither face's, and a fingertip there rolls onto the edge when the hand squeezes,
/// so the robustness does not count it.
pub const EDGE_COHERENCE: f64 = 0.9;
/// Times the hand is raised when the closed fingers reach into the table.
const MAX_RAISES: usize = 2;
/// How far each finger's contacts may stand off the object in the pre-grasp opening, m,
/// tightest first.
pub const PREGRASP_TRAVELS: [f64; 4] = [0.025, 0.04, 0.06, 0.09];

/// One judged candidate.
#[derive(Debug, Clone)]
pub struct FinalConfiguration {
    /// The stage-1 opposition it was built on (point indices).
    pub opposition: (usize, usize),
    /// Unit approach direction in the world (the hand moves along it from the pre-grasp).
    pub approach: Vector3<f64>,
    /// The hand frame at the grasp, in the world.
    pub hand_pose: Isometry3<f64>,
    /// The model's root frame at the grasp.
    pub root_pose: Isometry3<f64>,
    /// Joints of the pre-grasp (the pre-shape), the grasp (touching) and the squeeze.
    pub pregrasp: Vec<f64>,
    pub grasp: Vec<f64>,
    pub squeeze: Vec<f64>,
    pub contacts: Vec<SweepContact>,
    /// Per contact, whether the squeeze drives it off the object (`squeeze::Squeeze`); empty
    /// until the squeeze is computed.
    sliding: Vec<bool>,
    /// S of Eq 5.3 over the contacts.
    pub gii: f64,
    pub robustness: Robustness,
    /// Least clearance of the hand to the table at the grasp, m.
    pub plane_clearance: Option<f64>,
    /// Least clearance of the hand to the table with the squeeze joints, m: negative where the
    /// squeeze presses a link onto the table ([`Self::pressed_on_table`]).
    pub squeeze_clearance: Option<f64>,
    pub push: f64,
    pub feasible: bool,
    /// Whether contacts lie on both sides of the opposition (h1's and h2's).
    pub two_sided: bool,
    pub reason: Option<String>,
    /// Ranking key within feasibility (larger is better).
    pub score: f64,
    /// Whether the robustness programs stopped early (the candidate could not enter the best
    /// `want`): `robustness` then holds an upper bound of the weakest axis.
    cut: bool,
    /// Whether S < ε is all that keeps the candidate from being feasible.
    short_of_epsilon_only: bool,
    /// Whether the squeeze pressing the hand into the table is all that keeps the candidate
    /// from being feasible ([`Self::pressed_on_table`]).
    on_table_only: bool,
    /// What it lacks until it is output, when its contacts alone rule it out.
    pending: Option<Pending>,
}

impl FinalConfiguration {
    /// The order candidates are ranked in (larger is better): feasible first; among the
    /// infeasible, those that hold the object from both sides before those that touch one
    /// (a client executing the best infeasible plan then at least grips); then the score.
    fn rank(&self) -> (bool, bool, f64) {
        (self.feasible, self.two_sided, self.score)
    }

    /// The contacts the robustness counts: those on a face, not astride an edge
    /// ([`EDGE_COHERENCE`]), that the squeeze does not drive off the object (`sliding`).
    fn contact_points(&self) -> Vec<ContactPoint> {
        self.contacts
            .iter()
            .enumerate()
            .filter(|(i, c)| {
                c.coherence >= EDGE_COHERENCE && !self.sliding.get(*i).copied().unwrap_or(false)
            })
            .map(|(_, c)| ContactPoint {
                position: c.position,
                normal: c.normal,
            })
            .collect()
    }

    /// The candidate with the six-axis robustness added to its score (module step 4); the
    /// programs (the search's largest cost) stop once it cannot beat the best `want` so far of
    /// its kind (`cut`), and do not run for a one-sided candidate or an infeasible one when
    /// enough are feasible.
    fn rated(mut self, ctx: &SearchContext, beat: Beat) -> Self {
        let floor = match (self.feasible, beat.infeasible) {
            (true, _) => beat.feasible,
            (false, Some(b)) if self.two_sided => b,
            _ => return self,
        };
        let cps = self.contact_points();
        tracing::trace!(
            centre = ?ctx.shape.center.coords.as_slice(),
            contacts = ?cps.iter().map(|c| (c.position.coords.as_slice().to_vec(), c.normal.as_slice().to_vec())).collect::<Vec<_>>(),
            coherence = ?self.contacts.iter().map(|c| c.coherence).collect::<Vec<_>>(),
            "contacts rated"
        );
        self.robustness = match ctx.robustness_above(&cps, floor - self.score) {
            Ok(r) => r,
            Err(r) => {
                self.cut = true;
                r
            }
        };
        self.score += self.robustness.weakest;
        // Force closure (module step 4): three or more contacts that cannot resist some
        // direction at the centre of mass do not hold the object, whatever S says. (A
        // two-contact pinch resists a turn about its contact line only by torsion, which the
        // point-contact model underrates for a gripper's pad: the 2F-85's pinches it called
        // open held 6 of 6 in simulation.)
        if self.feasible && self.contacts.len() >= 3 && self.robustness.weakest < MIN_ROBUSTNESS {
            self.feasible = false;
            self.reason = Some(format!(
                "the contacts resist {:.2} of one contact's grip at the centre of mass in their \
                 weakest direction (< {MIN_ROBUSTNESS}: not force closure)",
                self.robustness.weakest
            ));
        }
        // S (Eq 5.3) measures how evenly the contacts resist wrenches, not whether they hold:
        // three or more contacts that resist a firm force at the centre of mass in every
        // direction hold the object whatever S says (three on faces: an edge contact's normal
        // is a guess, `EDGE_COHERENCE`).
        if !self.feasible
            && self.short_of_epsilon_only
            && !self.cut
            && cps.len() >= 3
            && self.robustness.weakest >= FIRM_ROBUSTNESS
        {
            self.feasible = true;
            self.reason = None;
        }
        tracing::debug!(
            robustness = self.robustness.weakest,
            cut = self.cut,
            score = self.score,
            "candidate rated"
        );
        self
    }

    /// With its whole robustness figure (the search rates candidates by the six axes alone, so
    /// those rated lack only the force straight down; the others, or those cut, get it all).
    fn with_robustness(mut self, ctx: &SearchContext) -> Self {
        if self.contacts.len() < 2 {
            return self;
        }
        let cps = self.contact_points();
        if self.cut || self.robustness == Robustness::default() {
            self.robustness = ctx.robustness(&cps, true);
            self.cut = false;
        } else if let Some(g) = ctx.gravity_resistance(&cps) {
            self.robustness.gravity = g;
        }
        self
    }

    /// The candidate accepted although its squeeze presses the hand into the table, when that
    /// is all it lacks and it holds by force closure (three or more contacts) — for a search
    /// that found no feasible candidate otherwise ([`search`]). The squeeze is the servos'
    /// force command, not a pose the hand reaches: the table stops such a link, as the object
    /// stops the others, and beside a low object fingertips pressed down onto the table are
    /// what hold it (MuJoCo, 20 trials per cell: the Shadow's plans judged infeasible for this
    /// alone held 29 of 32; holding the squeeze off the table instead lost the Shadow 230 → 217
    /// of 260, the gelatin box 17 → 5). A search that has a candidate clear of the table keeps
    /// it: accepting these whenever cost the Shadow four of 20 oranges (a little finger stopped
    /// under the fruit, which rolled out of the hand).
    fn pressed_on_table(mut self) -> Self {
        if self.feasible || !self.on_table_only || self.cut {
            return self;
        }
        if self.contacts.len() >= 3 && self.robustness.weakest < MIN_ROBUSTNESS {
            return self;
        }
        self.feasible = true;
        self.reason = None;
        self
    }

    /// How far the squeeze presses the hand into the table, m (None where it stays clear).
    pub fn squeeze_into_table(&self) -> Option<f64> {
        self.squeeze_clearance
            .filter(|&c| c < -PLANE_TOLERANCE)
            .map(|c| -c)
    }
}

/// The candidates of one request: which fingers take part and how the hand is pre-shaped.
struct Grasp<'m> {
    /// The realisation's pre-shapes, the best first, then wider ones.
    pres: &'m [PreShape],
    wrap: bool,
    /// Kinematic fingers taking part, h1 then h2.
    taking_part: Vec<usize>,
    free: Vec<usize>,
}

impl<'m> Grasp<'m> {
    /// The request's grasp realised by `model`; None when the hand has no pre-shape for it.
    fn of(ctx: &SearchContext, model: &'m KinematicModel) -> Option<Self> {
        let kin = |desc: &[usize]| -> Vec<usize> {
            desc.iter()
                .filter_map(|&i| model.hand.finger_index(&ctx.hand.fingers[i].name))
                .collect()
        };
        let h1 = kin(&ctx.grasp.h1_fingers);
        let h2 = kin(&ctx.grasp.h2_fingers);
        let pres = model.pre_shapes(&h1, &h2).filter(|p| !p.is_empty())?;
        let taking_part: Vec<usize> = h1.iter().chain(&h2).copied().collect();
        Some(Grasp {
            pres,
            wrap: ctx.grasp.grasp_type.is_power(),
            free: (0..model.hand.fingers.len())
                .filter(|f| !taking_part.contains(f))
                .collect(),
            taking_part,
        })
    }
}

/// The final configuration of one given candidate — `opposition` approached along `approach`,
/// the pre-shape's openings tried, no turns about the approach and no other candidate (a
/// grasp the caller chose, `PlanHints::parallel_grasp`); None when the hand has no pre-shape
/// for the grasp or cannot start.
pub fn realise(
    ctx: &SearchContext,
    model: &KinematicModel,
    opposition: (usize, usize),
    approach: &Vector3<f64>,
) -> Result<Option<FinalConfiguration>, FieldError> {
    let Some(grasp) = Grasp::of(ctx, model) else {
        return Ok(None);
    };
    let object = ObjectView::new(ctx.points, ctx.normals, ctx.plane.as_ref());
    // Any score enters, and a finite bar keeps the hand from turning about the approach.
    let beat = Beat {
        feasible: f64::MIN,
        infeasible: Some(f64::MIN),
    };
    let Some(c) = judge(ctx, model, &grasp, &object, opposition, approach, beat)? else {
        return Ok(None);
    };
    Ok(Some(
        c.completed(ctx, model, &object)?
            .with_robustness(ctx)
            .pressed_on_table(),
    ))
}

/// Searches the final configurations on `oppositions` (best first) and returns up to `want`
/// distinct ones, feasible first, best first; empty when the hand has no pre-shape for the
/// grasp.
pub fn search(
    ctx: &SearchContext,
    model: &KinematicModel,
    oppositions: &[(usize, usize)],
    want: usize,
) -> Result<Vec<FinalConfiguration>, FieldError> {
    let Some(grasp) = Grasp::of(ctx, model) else {
        return Ok(Vec::new());
    };
    let object = ObjectView::new(ctx.points, ctx.normals, ctx.plane.as_ref());
    let order = candidate_order(ctx, oppositions);
    let mut judged: Vec<FinalConfiguration> = Vec::new();
    // Candidates in order of preference, at most `final_candidates`; while none is feasible
    // the search goes on through the rest of the order, up to WIDENING times as many (method.md
    // §3: widen the search before answering infeasible) — but not for two fingers each driven
    // on its own, which only the palm could make feasible (`unlinked_pair`): the next grasp
    // type is the better search (planner bench, Barrett median: about 60 ms widened, 45 not,
    // 19–23 before the two-finger rule; every simulated Table 5.2 trial ended the same).
    let widening = if unlinked_fingers(model, &grasp.taking_part).is_some() {
        1
    } else {
        WIDENING
    };
    for (k, (opposition, approach)) in order.iter().enumerate() {
        let feasible_so_far = judged.iter().any(|c| c.feasible);
        if k >= ctx.options.final_candidates
            && (feasible_so_far || k >= widening * ctx.options.final_candidates)
        {
            break;
        }
        let (a, b) = *opposition;
        // The scores a candidate must beat to enter the best `want` found so far: among the
        // feasible ones, and (while fewer than `want` are feasible) among the two-sided
        // infeasible ones; None when infeasible ones can no longer be returned.
        let beat_among = |feasible: bool| {
            let mut scores: Vec<f64> = judged
                .iter()
                .filter(|c| c.feasible == feasible && c.two_sided)
                .map(|c| c.score)
                .collect();
            scores.sort_by(|x, y| y.total_cmp(x));
            scores
                .get(want.max(1) - 1)
                .copied()
                .unwrap_or(f64::NEG_INFINITY)
        };
        let feasible_found = judged.iter().filter(|c| c.feasible).count();
        let beat = Beat {
            feasible: beat_among(true),
            infeasible: (feasible_found < want).then(|| beat_among(false)),
        };
        if let Some(c) = judge(ctx, model, &grasp, &object, (a, b), approach, beat)? {
            judged.push(c);
        }
        let good = judged
            .iter()
            .filter(|c| c.feasible && !c.cut && c.robustness.weakest >= GOOD_ENOUGH)
            .count();
        if good >= want {
            break;
        }
    }
    // Nothing feasible: accept those whose squeeze pressing onto the table is all they lack.
    if !judged.iter().any(|c| c.feasible) {
        judged = judged
            .into_iter()
            .map(|c| match c.on_table_only {
                true => c.with_robustness(ctx).pressed_on_table(),
                false => c,
            })
            .collect();
    }
    judged.sort_by(|x, y| {
        y.rank()
            .partial_cmp(&x.rank())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let mut out: Vec<FinalConfiguration> = Vec::new();
    for c in judged {
        let distinct = out.iter().all(|o| {
            (o.hand_pose.translation.vector - c.hand_pose.translation.vector).norm() > 0.01
                || o.hand_pose.rotation.angle_to(&c.hand_pose.rotation) > 15f64.to_radians()
        });
        if distinct {
            out.push(c.completed(ctx, model, &object)?.with_robustness(ctx));
        }
        if out.len() == want {
            break;
        }
    }
    Ok(out)
}

/// The statistics of a final-configuration search that returned `finals` in `seconds`.
pub fn stage_stats(finals: &[FinalConfiguration], seconds: f64) -> StageStats {
    StageStats {
        solution_space: finals.len() as f64,
        candidates: finals.len(),
        iterations: finals.len(),
        evaluations: finals.len(),
        feasible_found: finals.iter().any(|f| f.feasible),
        seconds,
        ..Default::default()
    }
}

/// The scores a candidate's robustness must lift it above to matter (`FinalConfiguration::rated`).
#[derive(Debug, Clone, Copy)]
struct Beat {
    feasible: f64,
    infeasible: Option<f64>,
}

/// Feasible candidates of three or more contacts resist at least this force at the centre of
/// mass in every direction, per unit grip force per contact (force closure with a margin).
pub const MIN_ROBUSTNESS: f64 = 0.05;

/// A candidate this robust (resisted force per unit grip force, weakest direction) ends the
/// search early once enough of them are found.
const GOOD_ENOUGH: f64 = 1.0;
