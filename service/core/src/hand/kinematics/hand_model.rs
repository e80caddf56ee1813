//! A kinematic tree read as a hand: its palm, its fingers as joint chains and its thumb.
//!
//! # Rules (each overridable through [`HandOverrides`])
//! - **Palm**: walking down from the root, the first body with two or more child subtrees that
//!   contain a movable joint ("the root of the branching"). Joints above it (a wrist) belong to
//!   the arm, not to a finger.
//! - **Fingers**: one per leaf body below the palm whose path from the palm carries at least one
//!   joint; the finger's joints are the joints of the bodies on that path, palm excluded, and the
//!   leaf is its fingertip. Two chains tied by a loop closure (MJCF `<equality connect|weld>`,
//!   e.g. the coupler bar of the Robotiq 2F-85's four-bar linkage) are one finger: the chain whose
//!   tip lies farther from the palm at the mid configuration is kept. Chains with the same joints
//!   (two leaves on one phalanx) are one finger, with the farther leaf as its tip.
//! - **Contact point** of a finger part: the regional centre of the part (method.md §1), taken as
//!   the centre of the bounding box of the tip body's collision geometry, else of its parent's
//!   (a visual-only pad on a collision pad), else the tip body's origin.
//! - **Thumb**: the finger most opposed to the others in the modelled open pose (the reference
//!   configuration clamped into the limits, MuJoCo's qpos0). With C_i the contact point of
//!   finger i there (palm frame) and c the mean of all C_i, the thumb minimises
//!   Σ_{j≠i} cos∠(C_i − c, C_j − c): its offset from the hand's centre points away from every
//!   other finger's. Ties go to the earlier finger. (Workspace means are not used here: a
//!   Barrett finger's 180° spread averages its tip back onto the palm.)
//! - **Hand frame** (the frame of [`crate::hand::HandDescription`]), fixed to the palm body: origin
//!   at the centroid of the finger bases (first joint anchors: where the fingers leave the palm's
//!   inner surface); +x, the closing direction, from the thumb's mean contact point to the mean of
//!   the other fingers' (means over seeded workspace samples); +z, the approach, from the origin
//!   toward the mean of all fingers' mean contact points, made orthogonal to x; +y = z × x.
//! - **Finger names**: the tip body names with their common prefix and suffix removed, cut at
//!   separators (`wam/bhand/thumb/dist_link` → `thumb`, `ff_tip` → `ff`), or the full names
//!   where that leaves an empty, duplicate or `palm` name.

use super::kinematic_tree::KinematicTree;
use super::{GeomShape, mjcf, urdf};
use crate::error::FieldError;
use nalgebra::{Isometry3, Point3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

/// Names that override the detection rules of this module.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HandOverrides {
    /// Body to use as the palm.
    pub palm: Option<String>,
    /// Fingertip bodies, one per finger, in the order the fingers should get.
    pub fingertips: Option<Vec<String>>,
    /// The fingertip body (or derived finger name) of the thumb.
    pub thumb: Option<String>,
    /// Hand name for the description (default: the model's name).
    pub name: Option<String>,
}

/// One finger: a joint chain from the palm to a fingertip body.
#[derive(Debug, Clone, PartialEq)]
pub struct KinematicFinger {
    pub name: String,
    /// Bodies from the palm (exclusive) to the tip (inclusive).
    pub bodies: Vec<usize>,
    /// Tree joint indices along the chain, palm side first.
    pub joints: Vec<usize>,
    /// The fingertip body.
    pub tip: usize,
    /// Contact point (regional centre of the fingertip) in the tip body's frame.
    pub tip_point: Point3<f64>,
    /// An upper bound on the distance from the first joint's anchor to the contact point over
    /// all configurations, m: the sum of the distances between successive joint anchors and from
    /// the last anchor to the contact point (each invariant under the hinge it starts at), plus
    /// the stroke of every slide. Targets farther than this are unreachable without searching.
    pub reach: f64,
}

/// A hand with known kinematics: the tree, its palm, fingers and thumb.
#[derive(Debug, Clone, PartialEq)]
pub struct KinematicHand {
    pub name: String,
    pub tree: KinematicTree,
    /// The palm body.
    pub palm: usize,
    pub fingers: Vec<KinematicFinger>,
    /// Index into `fingers` of the thumb.
    pub thumb: usize,
    /// The hand frame of [`crate::hand::HandDescription`] (origin at the palm's inner surface,
    /// +z approach, +x closing) as a pose in the palm body's frame; see [`Self::hand_frame`].
    pub(crate) hand_frame: Isometry3<f64>,
}

/// Seed of the workspace sampling (thumb detection, hand description): fixed, so that the same
/// model always gives the same hand.
pub const WORKSPACE_SEED: u64 = 0x6a17_d5c3;
/// Configurations sampled for the thumb rule and the hand description.
pub const WORKSPACE_SAMPLES: usize = 2000;

impl KinematicHand {
    /// Reads an MJCF file with the default detection rules.
    pub fn from_mjcf_file(path: impl AsRef<Path>) -> Result<Self, FieldError> {
        Self::from_tree(
            mjcf::read_mjcf_file(path.as_ref())?,
            &HandOverrides::default(),
        )
    }

    /// Reads an MJCF document; includes and meshes resolve against `model_dir`.
    pub fn from_mjcf_str(text: &str, model_dir: impl AsRef<Path>) -> Result<Self, FieldError> {
        Self::from_tree(
            mjcf::parse_mjcf(text, model_dir.as_ref(), "<mjcf>")?,
            &HandOverrides::default(),
        )
    }

    /// Reads a URDF file with the default detection rules.
    pub fn from_urdf_file(path: impl AsRef<Path>) -> Result<Self, FieldError> {
        Self::from_tree(
            urdf::read_urdf_file(path.as_ref())?,
            &HandOverrides::default(),
        )
    }

    /// Reads a URDF document; meshes resolve against `mesh_dir`.
    pub fn from_urdf_str(text: &str, mesh_dir: impl AsRef<Path>) -> Result<Self, FieldError> {
        Self::from_tree(
            urdf::parse_urdf(text, mesh_dir.as_ref(), "<urdf>")?,
            &HandOverrides::default(),
        )
    }

    /// Reads a tree as a hand by the rules of this module, with `overrides` applied.
    pub fn from_tree(tree: KinematicTree, overrides: &HandOverrides) -> Result<Self, FieldError> {
        let palm = match &overrides.palm {
            Some(n) => tree.body_index(n).ok_or_else(|| {
                FieldError::new("hand.palm", format!("no body named '{n}' in the model"))
            })?,
            None => detect_palm(&tree)?,
        };
        let tips: Vec<usize> = match &overrides.fingertips {
            Some(names) => names
                .iter()
                .map(|n| {
                    let b = tree.body_index(n).ok_or_else(|| {
                        FieldError::new(
                            "hand.fingertips",
                            format!("no body named '{n}' in the model"),
                        )
                    })?;
                    if tree.path(palm, b).is_none_or(|p| p.is_empty()) {
                        return Err(FieldError::new(
                            "hand.fingertips",
                            format!("'{n}' is not below the palm '{}'", tree.bodies[palm].name),
                        ));
                    }
                    Ok(b)
                })
                .collect::<Result<_, _>>()?,
            None => detect_tips(&tree, palm)?,
        };
        let mut fingers = Vec::with_capacity(tips.len());
        for &tip in &tips {
            let bodies = tree.path(palm, tip).expect("tip below palm");
            let joints: Vec<usize> = bodies
                .iter()
                .flat_map(|&b| tree.bodies[b].joints.iter().copied())
                .collect();
            if joints.is_empty() {
                return Err(FieldError::new(
                    "hand.fingertips",
                    format!(
                        "no joint between the palm '{}' and '{}': not a finger",
                        tree.bodies[palm].name, tree.bodies[tip].name
                    ),
                ));
            }
            let tip_point = regional_centre(&tree, tip);
            let reach = reach_bound(&tree, &joints, tip, &tip_point);
            fingers.push(KinematicFinger {
                name: tree.bodies[tip].name.clone(),
                bodies,
                joints,
                tip,
                tip_point,
                reach,
            });
        }
        if fingers.len() < 2 {
            return Err(FieldError::new(
                "hand.fingers",
                format!(
                    "the model has {} finger(s) below the palm '{}'; a hand needs at least two \
                     jointed chains from the palm to a fingertip",
                    fingers.len(),
                    tree.bodies[palm].name
                ),
            ));
        }
        let short = short_names(&fingers.iter().map(|f| f.name.clone()).collect::<Vec<_>>());
        for (f, n) in fingers.iter_mut().zip(short) {
            f.name = n;
        }
        let name = overrides
            .name
            .clone()
            .unwrap_or_else(|| sanitize(&tree.name));
        let mut hand = KinematicHand {
            name,
            tree,
            palm,
            fingers,
            thumb: 0,
            hand_frame: Isometry3::identity(),
        };
        hand.thumb = match &overrides.thumb {
            Some(n) => hand
                .fingers
                .iter()
                .position(|f| &f.name == n || hand.tree.bodies[f.tip].name == *n)
                .ok_or_else(|| {
                    FieldError::new("hand.thumb", format!("'{n}' is not one of the fingers"))
                })?,
            None => hand.detect_thumb()?,
        };
        hand.hand_frame = hand.derive_hand_frame()?;
        Ok(hand)
    }

    pub fn finger_index(&self, name: &str) -> Option<usize> {
        self.fingers.iter().position(|f| f.name == name)
    }

    /// Seeded random joint vectors, uniform inside every joint's limits, then projected onto the
    /// model's loop closures and joint couplings ([`KinematicTree::project_constraints`]); draws
    /// that cannot be brought within 1 mm of them are replaced (at most 8 n draws in all, so a
    /// model whose constraints cannot be met yields fewer than `n`).
    pub fn sample_configurations(&self, n: usize, seed: u64) -> Vec<Vec<f64>> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut out = Vec::with_capacity(n);
        for _ in 0..8 * n.max(1) {
            if out.len() == n {
                break;
            }
            let mut q: Vec<f64> = self
                .tree
                .joints
                .iter()
                .map(|j| {
                    let (lo, hi) = j.limits();
                    if hi > lo {
                        rng.random_range(lo..=hi)
                    } else {
                        lo
                    }
                })
                .collect();
            if self
                .tree
                .project_constraints(&mut q)
                .is_ok_and(|v| v <= 1e-3)
            {
                out.push(q);
            }
        }
        out
    }

    /// Contact points of every finger in the palm body's frame, for each configuration.
    pub(crate) fn tip_samples_in_palm(
        &self,
        configs: &[Vec<f64>],
    ) -> Result<Vec<Vec<Point3<f64>>>, FieldError> {
        configs
            .iter()
            .map(|q| {
                let fk = self.tree.forward(q)?;
                let inv = fk.body_poses[self.palm].inverse();
                Ok(self
                    .fingers
                    .iter()
                    .map(|f| inv * (fk.body_poses[f.tip] * f.tip_point))
                    .collect())
            })
            .collect()
    }

    /// C_i: the mean contact point of each finger over the workspace samples, palm frame.
    fn tip_centroids(&self) -> Result<Vec<Vector3<f64>>, FieldError> {
        let configs = self.sample_configurations(WORKSPACE_SAMPLES / 4, WORKSPACE_SEED);
        let samples = self.tip_samples_in_palm(&configs)?;
        let mut centroids = vec![Vector3::zeros(); self.fingers.len()];
        for s in &samples {
            for (c, p) in centroids.iter_mut().zip(s) {
                *c += p.coords / samples.len() as f64;
            }
        }
        Ok(centroids)
    }

    /// Base of each finger: the anchor of its first joint, in the palm body's frame.
    pub(crate) fn finger_bases_in_palm(&self) -> Vec<Point3<f64>> {
        let fk = self
            .tree
            .forward(&self.tree.mid_configuration())
            .expect("mid configuration has the tree's length");
        let inv = fk.body_poses[self.palm].inverse();
        self.fingers
            .iter()
            .map(|f| inv * fk.joint_axes[f.joints[0]].0)
            .collect()
    }

    /// The hand frame in the palm body's frame:
    /// - origin b̄: the centroid of the finger bases (the palm's inner surface, where the fingers
    ///   start);
    /// - +x, the closing direction: from the thumb's mean contact point C_t to the mean of the
    ///   other fingers' C_j;
    /// - +z, the approach: from b̄ toward the mean of all C_i (where the fingers work), made
    ///   orthogonal to x (if that vanishes, the palm axis least aligned with x);
    /// - +y = z × x.
    fn derive_hand_frame(&self) -> Result<Isometry3<f64>, FieldError> {
        let c = self.tip_centroids()?;
        let n = c.len();
        let others = (0..n)
            .filter(|&j| j != self.thumb)
            .map(|j| c[j])
            .sum::<Vector3<f64>>()
            / (n - 1) as f64;
        let x = nalgebra::Unit::try_new(others - c[self.thumb], 1e-9).ok_or_else(|| {
            FieldError::new(
                "hand.fingers",
                "the thumb's workspace centre coincides with the other fingers': no closing \
                 direction",
            )
        })?;
        let bases = self.finger_bases_in_palm();
        let origin = bases.iter().map(|b| b.coords).sum::<Vector3<f64>>() / bases.len() as f64;
        let centre = c.iter().sum::<Vector3<f64>>() / n as f64;
        let v = centre - origin;
        let mut z = v - x.into_inner() * x.dot(&v);
        if z.norm() < 1e-6 {
            let axes = [Vector3::x(), Vector3::y(), Vector3::z()];
            let least = axes
                .iter()
                .min_by(|a, b| a.dot(&x).abs().total_cmp(&b.dot(&x).abs()))
                .expect("three axes");
            z = least - x.into_inner() * x.dot(least);
        }
        let z = z.normalize();
        let y = z.cross(&x);
        let rot = nalgebra::Rotation3::from_basis_unchecked(&[x.into_inner(), y, z]);
        Ok(Isometry3::from_parts(
            nalgebra::Translation3::from(origin),
            nalgebra::UnitQuaternion::from_rotation_matrix(&rot),
        ))
    }

    /// The hand frame of the derived [`crate::hand::HandDescription`] as a pose in the palm
    /// body's frame (the **hand frame** rule of the module documentation).
    pub fn hand_frame(&self) -> Isometry3<f64> {
        self.hand_frame
    }

    /// Pose of the hand frame in the model's root frame for the joint vector `q`.
    pub fn hand_frame_in_root(&self, q: &[f64]) -> Result<Isometry3<f64>, FieldError> {
        Ok(self.tree.forward(q)?.body_poses[self.palm] * self.hand_frame)
    }

    /// Contact point (regional centre of the fingertip) of every finger in the hand frame.
    pub fn fingertips(&self, q: &[f64]) -> Result<Vec<Point3<f64>>, FieldError> {
        let fk = self.tree.forward(q)?;
        let inv = (fk.body_poses[self.palm] * self.hand_frame).inverse();
        Ok(self
            .fingers
            .iter()
            .map(|f| inv * (fk.body_poses[f.tip] * f.tip_point))
            .collect())
    }

    fn detect_thumb(&self) -> Result<usize, FieldError> {
        let centroids: Vec<Vector3<f64>> = self
            .tip_samples_in_palm(&[self.tree.home_configuration()])?
            .remove(0)
            .into_iter()
            .map(|p| p.coords)
            .collect();
        let n = centroids.len();
        let centre = centroids.iter().sum::<Vector3<f64>>() / n as f64;
        let d: Vec<Vector3<f64>> = centroids.iter().map(|c| c - centre).collect();
        let score = |i: usize| -> f64 {
            (0..n)
                .filter(|&j| j != i)
                .map(|j| d[i].dot(&d[j]) / (d[i].norm() * d[j].norm()).max(1e-12))
                .sum()
        };
        Ok((0..n)
            .min_by(|&a, &b| score(a).total_cmp(&score(b)).then(a.cmp(&b)))
            .expect("at least two fingers"))
    }
}

/// [`KinematicFinger::reach`] of a chain.
fn reach_bound(tree: &KinematicTree, joints: &[usize], tip: usize, tip_point: &Point3<f64>) -> f64 {
    let q = tree.home_configuration();
    let fk = tree
        .forward(&q)
        .expect("home configuration has the tree's length");
    let mut points: Vec<Point3<f64>> = joints.iter().map(|&j| fk.joint_axes[j].0).collect();
    points.push(fk.point(tip, tip_point));
    let links: f64 = points.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let strokes: f64 = joints
        .iter()
        .filter(|&&j| tree.joints[j].kind == super::JointKind::Slide)
        .map(|&j| {
            let (lo, hi) = tree.joints[j].limits();
            hi - lo
        })
        .sum();
    links + strokes
}

/// Whether a body's subtree (itself included) carries a movable joint.
fn has_joint_below(tree: &KinematicTree, b: usize) -> bool {
    !tree.bodies[b].joints.is_empty()
        || tree.bodies[b]
            .children
            .iter()
            .any(|&c| has_joint_below(tree, c))
}

fn detect_palm(tree: &KinematicTree) -> Result<usize, FieldError> {
    let mut b = 0;
    loop {
        let jointed: Vec<usize> = tree.bodies[b]
            .children
            .iter()
            .copied()
            .filter(|&c| has_joint_below(tree, c))
            .collect();
        match jointed.as_slice() {
            [] => {
                return Err(FieldError::new(
                    "hand.fingers",
                    "the model has no fingers: no body has two or more jointed branches below it",
                ));
            }
            [only] => b = *only,
            _ => return Ok(b),
        }
    }
}

/// Distance of a body's origin from the palm at the mid configuration.
fn reach(tree: &KinematicTree, palm: usize, b: usize) -> f64 {
    let fk = tree
        .forward(&tree.mid_configuration())
        .expect("mid configuration has the tree's length");
    (fk.body_poses[b].translation.vector - fk.body_poses[palm].translation.vector).norm()
}

fn detect_tips(tree: &KinematicTree, palm: usize) -> Result<Vec<usize>, FieldError> {
    let mut chains: Vec<(usize, Vec<usize>)> = Vec::new();
    let mut stack = vec![palm];
    while let Some(b) = stack.pop() {
        let children = &tree.bodies[b].children;
        if children.is_empty() && b != palm {
            let path = tree.path(palm, b).expect("below palm");
            let joints: Vec<usize> = path
                .iter()
                .flat_map(|&x| tree.bodies[x].joints.iter().copied())
                .collect();
            if !joints.is_empty() {
                chains.push((b, path));
            }
        }
        stack.extend(children.iter().rev());
    }
    // Document order of the tips.
    chains.sort_by_key(|(b, _)| *b);
    let mut keep = vec![true; chains.len()];
    let joints_of = |path: &[usize]| -> Vec<usize> {
        path.iter()
            .flat_map(|&x| tree.bodies[x].joints.iter().copied())
            .collect()
    };
    let drop_nearer = |i: usize, j: usize, keep: &mut Vec<bool>| {
        if reach(tree, palm, chains[i].0) >= reach(tree, palm, chains[j].0) {
            keep[j] = false;
        } else {
            keep[i] = false;
        }
    };
    for i in 0..chains.len() {
        for j in i + 1..chains.len() {
            if keep[i] && keep[j] && joints_of(&chains[i].1) == joints_of(&chains[j].1) {
                drop_nearer(i, j, &mut keep);
            }
        }
    }
    for lc in &tree.loop_closures {
        let on = |b: usize| (0..chains.len()).find(|&i| keep[i] && chains[i].1.contains(&b));
        if let (Some(i), Some(j)) = (on(lc.body1), on(lc.body2))
            && i != j
        {
            drop_nearer(i, j, &mut keep);
        }
    }
    Ok(chains
        .into_iter()
        .zip(keep)
        .filter(|(_, k)| *k)
        .map(|((b, _), _)| b)
        .collect())
}

/// Bounding box (min, max) of a body's collision geometry in the body frame, if it has any.
pub(crate) fn collision_bounds(
    tree: &KinematicTree,
    body: usize,
) -> Option<(Point3<f64>, Point3<f64>)> {
    let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
    let mut hi = Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
    let mut any = false;
    for g in tree.bodies[body].geoms.iter().filter(|g| g.collision) {
        for p in geom_points(&g.shape) {
            let w = g.pose * p;
            lo = lo.inf(&w);
            hi = hi.sup(&w);
            any = true;
        }
    }
    any.then_some((lo, hi))
}

/// Points whose bounding box is the shape's (corners of the local box; mesh vertices).
fn geom_points(shape: &GeomShape) -> Vec<Point3<f64>> {
    let corners = |h: Vector3<f64>| -> Vec<Point3<f64>> {
        (0..8)
            .map(|i| {
                Point3::new(
                    if i & 1 == 0 { -h.x } else { h.x },
                    if i & 2 == 0 { -h.y } else { h.y },
                    if i & 4 == 0 { -h.z } else { h.z },
                )
            })
            .collect()
    };
    match shape {
        GeomShape::Sphere { radius } => corners(Vector3::repeat(*radius)),
        GeomShape::Capsule {
            radius,
            half_length,
        } => corners(Vector3::new(*radius, *radius, half_length + radius)),
        GeomShape::Cylinder {
            radius,
            half_length,
        } => corners(Vector3::new(*radius, *radius, *half_length)),
        GeomShape::Box { half_extents } => corners(*half_extents),
        GeomShape::Ellipsoid { radii } => corners(*radii),
        GeomShape::Plane => Vec::new(),
        GeomShape::Mesh { vertices, .. } => vertices.as_ref().clone(),
    }
}

/// The regional centre of a fingertip body (see the module rules).
fn regional_centre(tree: &KinematicTree, tip: usize) -> Point3<f64> {
    if let Some((lo, hi)) = collision_bounds(tree, tip) {
        return nalgebra::center(&lo, &hi);
    }
    if let Some(parent) = tree.bodies[tip].parent
        && tree.bodies[tip].joints.is_empty()
        && let Some((lo, hi)) = collision_bounds(tree, parent)
    {
        // Parent frame → tip frame (the tip is rigidly attached: no joint).
        return tree.bodies[tip].pose.inverse() * nalgebra::center(&lo, &hi);
    }
    Point3::origin()
}

/// Name separators at which common affixes are cut.
fn is_separator(c: u8) -> bool {
    matches!(c, b'_' | b'/' | b'-' | b'.' | b':')
}

/// The tip names with their common prefix and suffix removed, cut at separators
/// (`wam/bhand/index/dist_link` → `index`, `right_silicone_pad` → `right`), where that keeps
/// them non-empty, distinct and not `palm`.
fn short_names(names: &[String]) -> Vec<String> {
    let first = names[0].as_bytes();
    let mut pre = first.len();
    let mut suf = first.len();
    for n in &names[1..] {
        let b = n.as_bytes();
        pre = pre.min(first.iter().zip(b).take_while(|(x, y)| x == y).count());
        suf = suf.min(
            first
                .iter()
                .rev()
                .zip(b.iter().rev())
                .take_while(|(x, y)| x == y)
                .count(),
        );
    }
    // Prefix: up to and including its last separator; suffix: from its first separator.
    let pre = first[..pre]
        .iter()
        .rposition(|&c| is_separator(c))
        .map_or(0, |i| i + 1);
    let suf_start = first.len() - suf;
    let suf = first[suf_start..]
        .iter()
        .position(|&c| is_separator(c))
        .map_or(0, |i| suf - i);
    let short: Vec<String> = names
        .iter()
        .map(|n| {
            let end = n.len().saturating_sub(suf).max(pre);
            n.get(pre..end).unwrap_or(n).to_string()
        })
        .collect();
    let valid = short
        .iter()
        .enumerate()
        .all(|(i, s)| !s.is_empty() && s != crate::hand::PALM && !short[..i].contains(s));
    if valid { short } else { names.to_vec() }
}

/// A model name made valid as a hand name (ASCII letters, digits, `_-.`, at most 64).
fn sanitize(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .take(64)
        .collect();
    if s.trim_matches('_').is_empty() {
        "imported_hand".into()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_names_strip_common_affixes() {
        let v = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert_eq!(
            short_names(&v(&["rh_ffdistal", "rh_mfdistal", "rh_thdistal"])),
            v(&["ffdistal", "mfdistal", "thdistal"])
        );
        assert_eq!(
            short_names(&v(&[
                "wam/bhand/index/dist_link",
                "wam/bhand/thumb/dist_link"
            ])),
            v(&["index", "thumb"])
        );
        assert_eq!(
            short_names(&v(&["right_silicone_pad", "left_silicone_pad"])),
            v(&["right", "left"])
        );
        assert_eq!(short_names(&v(&["ff_tip", "th_tip"])), v(&["ff", "th"]));
        // No separator-aligned affix: the names stay as they are.
        assert_eq!(short_names(&v(&["tip", "tip2"])), v(&["tip", "tip2"]));
    }
}
