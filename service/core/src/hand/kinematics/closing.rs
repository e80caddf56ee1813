//! How a hand closes: the grasp synergy that the final-configuration search drives and that a
//! robot (or graspd-sim) executes (issue 15). Derived from the kinematics alone, so it works for
//! any imported hand.
//!
//! # Rules
//! - **Flexion joints** close a finger. A joint of the finger's chain is one when, from the
//!   modelled open pose (the home configuration: hand models are drawn open), its range goes
//!   [`MIN_FLEXION`] rad (a slide [`MIN_STROKE`] m) further to one side than to the other
//!   (by at least twice), and moving toward that far limit takes the finger's contact point
//!   toward the hand's grasp centre G — the mean of every finger's workspace-mean contact point,
//!   in front of the palm — with cos ≥ [`MIN_CLOSING_COS`]. The velocity is read at the home
//!   pose, or, where the joint's axis runs through the contact point there (a twist), with the
//!   finger's joints a third of the way to their far limits. Open value: the home value;
//!   closed value: the far limit.
//! - **Setting joints** are the others (finger spread, thumb rotation, linkage followers): they
//!   hold the pre-shape's posture while the fingers close.
//! - A finger closes on the straight line in joint space from open to closed, s = 0 … 1.
//!   Fingers whose joints the model ties together (loop closures, joint couplings: a linkage
//!   gripper) form a **group**: they close with one s, projected onto the constraints.
//! - **Pre-shape** of a grasp (fingers h1 against h2): the setting joints, chosen among the
//!   open pose and seeded workspace samples, for which the closing paths of the opposing contact
//!   points meet in front of the palm, head on, with the h2 fingers a finger width apart. Its
//!   grasp frame (x from the h1 contacts to the h2 contacts, z from the palm to their midpoint)
//!   and its opening along x at each s are what the search aligns with the object.

use super::hand_model::{KinematicHand, WORKSPACE_SEED};
use super::kinematic_tree::JointKind;
use crate::error::FieldError;
use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// Least extra range on the far side of a flexion joint, rad.
pub const MIN_FLEXION: f64 = 0.3;
/// Least extra stroke of a flexion slide, m.
pub const MIN_STROKE: f64 = 0.005;
/// Least cosine between a flexion joint's contact-point velocity and the way to G.
pub const MIN_CLOSING_COS: f64 = 0.2;
/// Samples of the closing path s = 0 … 1 kept per pre-shape.
pub const PATH_SAMPLES: usize = 11;
/// Workspace samples whose setting joints are tried as pre-shapes.
const PRESHAPE_CANDIDATES: usize = 192;
/// Beside the best pre-shape, up to this many wider ones are kept ([`HandSynergy::pre_shapes`]).
pub const WIDER_PRESHAPES: usize = 3;
/// Each wider pre-shape opens at least this much further than the one before it, m.
pub const WIDER_STEP: f64 = 0.02;

/// A joint that closes a finger.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlexionJoint {
    pub joint: usize,
    /// Value with the finger open (the home pose) and closed (the far limit).
    pub open: f64,
    pub closed: f64,
    /// Whether it is the finger's palm-side flexion joint, which leads the close.
    pub leads: bool,
}

impl FlexionJoint {
    /// The joint's value at closing parameter `s` (0 open … 1 closed): the palm-side joint
    /// moves with s, the others with s², so a finger first turns at its knuckle, its tip
    /// travelling across toward the opposing fingers, and curls at the end of the close. With
    /// every joint moving with s the tips hooked over the top of a low or boxy object: the
    /// pre-shaped fingers' middle links met the top first, and the Shadow hand's contacts on
    /// the potted meat can lay within 1–1.5 cm of its rim (docs/final-configuration.md,
    /// "The closing path").
    pub fn at(&self, s: f64) -> f64 {
        let share = if self.leads { s } else { s * s.abs() };
        self.open + share * (self.closed - self.open)
    }

    /// +1 when the joint's value grows as the finger closes, −1 when it shrinks.
    pub fn closing_sign(&self) -> f64 {
        (self.closed - self.open).signum()
    }
}

/// One finger's synergy.
#[derive(Debug, Clone, PartialEq)]
pub struct FingerSynergy {
    /// Index into [`KinematicHand::fingers`].
    pub finger: usize,
    /// Flexion joints, palm side first.
    pub flexion: Vec<FlexionJoint>,
    /// The finger's other joints.
    pub setting: Vec<usize>,
    /// Whether the model's constraints tie this finger to others (see [`HandSynergy::groups`]).
    pub constrained: bool,
}

/// The posture a grasp starts from and how its contacts close (see the module rules).
#[derive(Debug, Clone, PartialEq)]
pub struct PreShape {
    /// Fingers on the h1 side (the thumb; empty for a palm opposition) and the h2 side.
    pub h1: Vec<usize>,
    pub h2: Vec<usize>,
    /// Every joint: setting joints at the pre-shape, flexion joints open.
    pub base: Vec<f64>,
    /// The grasp frame in the hand frame: origin at the midpoint of the h1 and h2 contact points
    /// half-way closed, x from h1 to h2, z away from the palm (palm opposition: z from the palm
    /// to the fingers, x the hand's x made perpendicular).
    pub frame: Isometry3<f64>,
    /// h1–h2 distance of the contact points along the h1 → h2 line at s = k / (PATH_SAMPLES − 1).
    pub opening: [f64; PATH_SAMPLES],
    /// How far the opposing contact paths stay apart at their closest, m (0: they meet).
    pub miss: f64,
}

impl PreShape {
    /// The widest opening along the closing path, m.
    pub fn widest(&self) -> f64 {
        self.opening.iter().copied().fold(0.0, f64::max)
    }

    /// The least s at which the opening is at most `width` (1 when it never is).
    pub fn s_for_opening(&self, width: f64) -> f64 {
        let o = &self.opening;
        if width >= o[0] {
            return 0.0;
        }
        for k in 1..PATH_SAMPLES {
            if o[k] <= width {
                let (a, b) = (o[k - 1], o[k]);
                let f = if (a - b).abs() > 1e-12 {
                    (a - width) / (a - b)
                } else {
                    1.0
                };
                return ((k - 1) as f64 + f) / (PATH_SAMPLES - 1) as f64;
            }
        }
        1.0
    }
}

/// The synergy of a whole hand.
#[derive(Debug, Clone, PartialEq)]
pub struct HandSynergy {
    /// One per finger of the hand, in its order.
    pub fingers: Vec<FingerSynergy>,
    /// Fingers that close together (each finger is in exactly one group).
    pub groups: Vec<Vec<usize>>,
    /// The grasp centre G in the hand frame.
    pub grasp_centre: Point3<f64>,
}

impl HandSynergy {
    /// Derives the synergy (module rules).
    pub fn derive(hand: &KinematicHand) -> Result<Self, FieldError> {
        let home = hand.tree.home_configuration();
        let samples = hand.sample_configurations(256, WORKSPACE_SEED ^ 0xc105);
        let mut means = vec![Vector3::zeros(); hand.fingers.len()];
        for q in &samples {
            for (m, t) in means.iter_mut().zip(hand.fingertips(q)?) {
                *m += t.coords / samples.len().max(1) as f64;
            }
        }
        let g = Point3::from(means.iter().sum::<Vector3<f64>>() / means.len().max(1) as f64);
        let mut fingers = Vec::with_capacity(hand.fingers.len());
        for (fi, f) in hand.fingers.iter().enumerate() {
            let mut flexion = Vec::new();
            let mut setting = Vec::new();
            for &j in &f.joints {
                let joint = &hand.tree.joints[j];
                let (lo, hi) = joint.limits();
                let (below, above) = (home[j] - lo, hi - home[j]);
                let (far, near, toward) = if above >= below {
                    (above, below, hi)
                } else {
                    (below, above, lo)
                };
                let min = match joint.kind {
                    JointKind::Hinge => MIN_FLEXION,
                    JointKind::Slide => MIN_STROKE,
                };
                let closes = far - near >= min
                    && far >= 2.0 * near
                    && closing_cosine(hand, fi, j, toward, &home, &g)? >= MIN_CLOSING_COS;
                if closes {
                    flexion.push(FlexionJoint {
                        joint: j,
                        open: home[j],
                        closed: toward,
                        leads: flexion.is_empty(),
                    });
                } else {
                    setting.push(j);
                }
            }
            fingers.push(FingerSynergy {
                finger: fi,
                flexion,
                setting,
                constrained: false,
            });
        }
        let groups = coupled_groups(hand, &fingers)?;
        let constrained = !hand.tree.loop_closures.is_empty() || !hand.tree.couplings.is_empty();
        for f in &mut fingers {
            f.constrained = constrained;
        }
        Ok(Self {
            fingers,
            groups,
            grasp_centre: g,
        })
    }

    /// The group of finger `f`.
    pub fn group_of(&self, f: usize) -> &[usize] {
        self.groups
            .iter()
            .find(|g| g.contains(&f))
            .map(Vec::as_slice)
            .unwrap_or(&[])
    }

    /// Sets the flexion joints of each `(finger, s)` in `q` (s = 0 open … 1 closed) and projects
    /// onto the model's constraints when one of them is constrained.
    pub fn close(
        &self,
        hand: &KinematicHand,
        q: &mut [f64],
        fingers: &[(usize, f64)],
    ) -> Result<(), FieldError> {
        let mut project = false;
        let mut held = Vec::new();
        for &(f, s) in fingers {
            let fs = &self.fingers[f];
            for fj in &fs.flexion {
                q[fj.joint] = fj.at(s.clamp(0.0, 1.5));
                held.push(fj.joint);
            }
            project |= fs.constrained;
        }
        hand.tree.clamp(q);
        if project {
            // The driven joints stay where they were put; the linkage follows them.
            hand.tree.project_constraints_holding(q, &held)?;
        }
        Ok(())
    }

    /// The pre-shapes for grasping with `h1` (empty: the palm) against `h2` (module rules):
    /// the best first, then up to [`WIDER_PRESHAPES`] that open further, each the best of those
    /// opening at least [`WIDER_STEP`] wider than the one before. The best stays near the open
    /// pose and may open narrower than the object: the Shadow's thumb against its four fingers
    /// opens 64 mm at most there, against a 89 mm box whose fingertips then land on its top.
    pub fn pre_shapes(
        &self,
        hand: &KinematicHand,
        h1: &[usize],
        h2: &[usize],
        finger_width: f64,
    ) -> Result<Vec<PreShape>, FieldError> {
        let mut home = hand.tree.home_configuration();
        hand.tree.project_constraints(&mut home)?;
        let taking_part: Vec<usize> = h1.iter().chain(h2).copied().collect();
        // A linkage's setting joints follow its constraints: only the open pose is tried.
        let linked = taking_part.iter().any(|&f| self.fingers[f].constrained);
        let mut starts = vec![home.clone()];
        if !linked {
            starts.extend(hand.sample_configurations(PRESHAPE_CANDIDATES, WORKSPACE_SEED ^ 0x9e5));
        }
        let mut scored: Vec<(f64, PreShape)> = Vec::new();
        for start in &starts {
            let mut base = home.clone();
            let mut moved = 0.0;
            for &f in &taking_part {
                for &j in &self.fingers[f].setting {
                    base[j] = start[j];
                    let (lo, hi) = hand.tree.joints[j].limits();
                    moved += (start[j] - home[j]).abs() / (hi - lo).max(1e-6);
                }
            }
            let Some((score, shape)) = self.score_pre_shape(hand, base, h1, h2, finger_width)?
            else {
                continue;
            };
            // Stay near the open pose unless another posture opposes clearly better (1 cm per
            // full range moved).
            scored.push((score + 0.01 * moved, shape));
        }
        let best_of = |least: f64| {
            scored
                .iter()
                .filter(|(_, s)| s.widest() >= least)
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, s)| s.clone())
        };
        let mut out: Vec<PreShape> = best_of(f64::NEG_INFINITY).into_iter().collect();
        if out.is_empty() {
            return Err(FieldError::new(
                "hand.fingers",
                "no pre-shape brings the opposing fingers' contact points together",
            ));
        }
        while out.len() <= WIDER_PRESHAPES {
            let least = out.last().map_or(0.0, PreShape::widest) + WIDER_STEP;
            let Some(wider) = best_of(least) else {
                break;
            };
            out.push(wider);
        }
        Ok(out)
    }

    /// Scores a pre-shape (lower is better) and builds it; None when the fingers never oppose.
    fn score_pre_shape(
        &self,
        hand: &KinematicHand,
        base: Vec<f64>,
        h1: &[usize],
        h2: &[usize],
        finger_width: f64,
    ) -> Result<Option<(f64, PreShape)>, FieldError> {
        let taking_part: Vec<usize> = h1.iter().chain(h2).copied().collect();
        let mut c1 = [Point3::origin(); PATH_SAMPLES];
        let mut c2 = [Point3::origin(); PATH_SAMPLES];
        let mut crowding = 0.0f64;
        for k in 0..PATH_SAMPLES {
            let s = k as f64 / (PATH_SAMPLES - 1) as f64;
            let mut q = base.clone();
            let fs: Vec<(usize, f64)> = taking_part.iter().map(|&f| (f, s)).collect();
            self.close(hand, &mut q, &fs)?;
            let tips = hand.fingertips(&q)?;
            let mean = |idx: &[usize]| {
                Point3::from(
                    idx.iter().map(|&f| tips[f].coords).sum::<Vector3<f64>>() / idx.len() as f64,
                )
            };
            c1[k] = if h1.is_empty() {
                Point3::origin()
            } else {
                mean(h1)
            };
            c2[k] = mean(h2);
            for (i, &a) in h2.iter().enumerate() {
                for &b in &h2[i + 1..] {
                    let d = (tips[a] - tips[b]).norm();
                    crowding = crowding.max(finger_width - d);
                }
            }
        }
        let dist: Vec<f64> = (0..PATH_SAMPLES).map(|k| (c2[k] - c1[k]).norm()).collect();
        let (kmin, miss) = dist
            .iter()
            .copied()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("samples");
        // They must close on each other: the opening shrinks over the first half.
        let half = PATH_SAMPLES / 2;
        if dist[half] >= dist[0] - 1e-4 && kmin == 0 {
            return Ok(None);
        }
        let k_mid = half.min(kmin.max(1));
        let Some(line) = (c2[k_mid] - c1[k_mid])
            .try_normalize(1e-6)
            .or_else(|| (c2[0] - c1[0]).try_normalize(1e-6))
        else {
            return Ok(None);
        };
        let mid = Point3::from((c1[k_mid].coords + c2[k_mid].coords) / 2.0);
        let meet = Point3::from((c1[kmin].coords + c2[kmin].coords) / 2.0);
        let (x, z) = if h1.is_empty() {
            // Palm opposition: the line runs from the palm out to the fingers, so it is the
            // frame's z; x is the hand's, made perpendicular.
            let Some(x) = (Vector3::x() - line * line.x).try_normalize(1e-6) else {
                return Ok(None);
            };
            (x, line)
        } else {
            let out = mid.coords - line * mid.coords.dot(&line);
            let Some(z) = out.try_normalize(1e-6) else {
                return Ok(None);
            };
            (line, z)
        };
        let y = z.cross(&x);
        let rot =
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_basis_unchecked(&[x, y, z]));
        let frame = Isometry3::from_parts(Translation3::from(mid.coords), rot);
        let mut opening = [0.0; PATH_SAMPLES];
        for k in 0..PATH_SAMPLES {
            opening[k] = (c2[k] - c1[k]).dot(&line).max(0.0);
        }
        // Head on: the opening should close along the line, not by sliding past each other.
        let approach = (dist[0] - miss).max(0.0);
        let sideways = ((c2[0] - c1[0]) - line * (c2[0] - c1[0]).dot(&line)).norm();
        // Meeting behind the palm plane (z ≤ 1 cm in the hand frame) is no grasp.
        let behind = (0.01 - meet.z).max(0.0);
        let score =
            miss + 0.25 * sideways + 2.0 * crowding.max(0.0) + 5.0 * behind - 0.1 * approach;
        Ok(Some((
            score,
            PreShape {
                h1: h1.to_vec(),
                h2: h2.to_vec(),
                base,
                frame,
                opening,
                miss,
            },
        )))
    }
}

/// Cosine between the contact-point velocity of moving joint `j` of finger `fi` toward `toward`
/// and the way from the contact point to `g` (hand frame), read at `home` or, for a twist there,
/// with the finger's joints a third of the way to their far limits.
fn closing_cosine(
    hand: &KinematicHand,
    fi: usize,
    j: usize,
    toward: f64,
    home: &[f64],
    g: &Point3<f64>,
) -> Result<f64, FieldError> {
    let velocity = |q: &[f64]| -> Result<(Point3<f64>, Vector3<f64>), FieldError> {
        let step = 0.02 * (toward - q[j]).signum();
        let p0 = hand.fingertips(q)?[fi];
        let mut q2 = q.to_vec();
        q2[j] += step;
        let p1 = hand.fingertips(&q2)?[fi];
        Ok((p0, (p1 - p0) / 0.02))
    };
    let (mut p, mut v) = velocity(home)?;
    if v.norm() < 1e-3 {
        let mut bent = home.to_vec();
        for &k in &hand.fingers[fi].joints {
            let (lo, hi) = hand.tree.joints[k].limits();
            let far = if hi - home[k] >= home[k] - lo { hi } else { lo };
            bent[k] = home[k] + (far - home[k]) / 3.0;
        }
        (p, v) = velocity(&bent)?;
    }
    let to_g = g - p;
    if v.norm() < 1e-6 || to_g.norm() < 1e-6 {
        return Ok(0.0);
    }
    Ok(v.dot(&to_g) / (v.norm() * to_g.norm()))
}

/// Fingers tied by the model's constraints: moving one finger's flexion joints and projecting
/// onto the constraints moves the other's contact point.
fn coupled_groups(
    hand: &KinematicHand,
    fingers: &[FingerSynergy],
) -> Result<Vec<Vec<usize>>, FieldError> {
    let n = fingers.len();
    let mut group: Vec<usize> = (0..n).collect();
    if !hand.tree.loop_closures.is_empty() || !hand.tree.couplings.is_empty() {
        let mut home = hand.tree.home_configuration();
        hand.tree.project_constraints(&mut home)?;
        let tips0 = hand.fingertips(&home)?;
        for f in 0..n {
            let mut q = home.clone();
            for fj in &fingers[f].flexion {
                q[fj.joint] = fj.open + 0.3 * (fj.closed - fj.open);
            }
            hand.tree.project_constraints(&mut q)?;
            let tips = hand.fingertips(&q)?;
            for g in 0..n {
                if g != f && (tips[g] - tips0[g]).norm() > 1e-3 {
                    let (a, b) = (group[f], group[g]);
                    for v in group.iter_mut() {
                        if *v == b {
                            *v = a;
                        }
                    }
                }
            }
        }
    }
    let mut out: Vec<Vec<usize>> = Vec::new();
    for f in 0..n {
        match out.iter_mut().find(|g| group[g[0]] == group[f]) {
            Some(g) => g.push(f),
            None => out.push(vec![f]),
        }
    }
    Ok(out)
}
