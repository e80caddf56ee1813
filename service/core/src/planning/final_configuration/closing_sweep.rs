//! Closing the fingers onto the object, as the hand's servos will (GraspIt's "autograsp"): from
//! the pre-shape every taking-part finger's flexion joints advance together along the synergy
//! (s → 1). When a link meets the object (or the table) the joints that move it stop and the
//! joints beyond it go on, so a finger wraps; a finger whose links all stop, or whose joints
//! reach their closed limits, is done. Fingers tied by the model's constraints (a linkage) close
//! with one s until every one of them touches; how far the first ones would then have pushed
//! into the object is the group's `push`.
//!
//! Steps of 1/[`STEPS`] of the path, refined by [`BISECTIONS`] halvings at each first touch (of
//! the fingers that touch at the whole step); a link touches when an object point is within
//! [`TOUCH_MARGIN`] of it. The table does not stop a finger (fingertips slide along it, as they
//! do on a real table); where the closed hand ends up below it, the caller raises the hand.

use super::ObjectView;
use super::object_view::NearPoints;
use crate::error::FieldError;
use crate::hand::kinematics::{
    ForwardKinematics, HandCollision, HandSynergy, KinematicHand, PosedCollision, ProjectionMemo,
};
use nalgebra::{Isometry3, Point3, Vector3};

/// Steps along the whole closing path.
pub const STEPS: usize = 24;
/// Halvings of the step at a first touch.
pub const BISECTIONS: usize = 4;
/// A link touches the object when a point is closer than this, m.
pub const TOUCH_MARGIN: f64 = 0.002;
/// Points this close to a touching link make its contact patch, m.
pub const PATCH_MARGIN: f64 = 0.004;
/// Object points this close to a contact tell whether it lies on one face or by an edge (its
/// coherence), m: about a fingertip pad's radius, the reach of the pad rolling under the
/// squeeze.
pub const COHERENCE_RADIUS: f64 = 0.008;

/// One contact found by the sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepContact {
    /// Kinematic finger index; None for the palm (or any body that is not a finger's).
    pub finger: Option<usize>,
    /// The touching body.
    pub body: usize,
    /// The object point nearest the link (index into the planner's cloud).
    pub point: usize,
    /// Mean of the patch's points and of their outward normals.
    pub position: Point3<f64>,
    pub normal: Vector3<f64>,
    /// Distance from the link's surface to `position` (how well the link meets the contact), m.
    pub gap: f64,
    /// Length of the mean of the patch's unit normals: 1 for a flat patch, about 0.7 for one
    /// astride a box's edge (its mean normal is then neither face's).
    pub coherence: f64,
}

/// The result of closing.
#[derive(Debug, Clone)]
pub struct Closed {
    /// Joints with every finger at its touch (the grasp configuration).
    pub joints: Vec<f64>,
    /// Per taking-part finger: the path parameter of each flexion joint at the end.
    pub s: Vec<(usize, Vec<f64>)>,
    pub contacts: Vec<SweepContact>,

    /// Largest push of a linked finger into the object, m.
    pub push: f64,
}

/// Bodies of each finger's chain that carry collision pieces, palm side first, with the piece
/// indices of each.
pub fn finger_links(
    hand: &KinematicHand,
    collision: &HandCollision,
    finger: usize,
) -> Vec<(usize, Vec<usize>)> {
    hand.fingers[finger]
        .bodies
        .iter()
        .filter_map(|&b| {
            let pieces: Vec<usize> = (0..collision.pieces.len())
                .filter(|&k| collision.pieces[k].body == b)
                .collect();
            (!pieces.is_empty()).then_some((b, pieces))
        })
        .collect()
}

/// What a sweep needs of the hand.
pub struct SweepHand<'a> {
    pub hand: &'a KinematicHand,
    pub synergy: &'a HandSynergy,
    pub collision: &'a HandCollision,
    /// Where the linkage projections of the hand's sweeps are kept.
    pub projections: &'a ProjectionMemo,
    /// The model's root in the world (fixed while the fingers close).
    pub root_in_world: Isometry3<f64>,
}

impl SweepHand<'_> {
    /// The hand posed at `q`, its forward kinematics from `at_base`'s (those at `base`) for the
    /// joints that differ from `base`: the fingers that do not close keep their bodies' poses.
    fn posed(
        &self,
        q: &[f64],
        base: &[f64],
        at_base: &ForwardKinematics,
    ) -> Result<PosedCollision<'_>, FieldError> {
        let changed: Vec<usize> = (0..q.len())
            .filter(|&j| q[j].to_bits() != base[j].to_bits())
            .collect();
        let fk = self.hand.tree.forward_from(q, at_base, &changed)?;
        Ok(self.collision.posed_fk(&fk, &self.root_in_world))
    }

    /// Joints for per-finger, per-flexion-joint path parameters, and the hand posed there (a
    /// linkage's projection ends with the forward kinematics of the joints it settles on).
    /// A linkage's projection starts from `warm` (the joints of a nearby step on the path, so
    /// that a few Newton steps settle it), the other joints from `base`.
    fn configure_posed(
        &self,
        base: &[f64],
        at_base: &ForwardKinematics,
        s: &[(usize, Vec<f64>)],
        warm: &[f64],
    ) -> Result<(Vec<f64>, PosedCollision<'_>), FieldError> {
        let mut q = base.to_vec();
        let mut constrained = false;
        let mut held = Vec::new();
        for (f, sv) in s {
            let fs = &self.synergy.fingers[*f];
            for (fj, &v) in fs.flexion.iter().zip(sv) {
                q[fj.joint] = fj.at(v);
                held.push(fj.joint);
            }
            constrained |= fs.constrained;
        }
        self.hand.tree.clamp(&mut q);
        let tree = &self.hand.tree;
        if constrained && !(tree.loop_closures.is_empty() && tree.couplings.is_empty()) {
            for (j, x) in q.iter_mut().enumerate() {
                if !held.contains(&j) {
                    *x = warm[j];
                }
            }
            let projected = self.projections.project(tree, &mut q, &held)?;
            let posed = self.collision.posed_fk(&projected.1, &self.root_in_world);
            return Ok((q, posed));
        }
        let posed = self.posed(&q, base, at_base)?;
        Ok((q, posed))
    }
}

/// Whether `link`'s pieces touch the object in `posed`.
fn link_touches(
    posed: &PosedCollision,
    pieces: &[usize],
    object: &ObjectView,
    near: &mut NearPoints,
) -> bool {
    pieces.iter().any(|&k| {
        let (c, r) = posed.sphere(k);
        object.near(&c, r + TOUCH_MARGIN)
            && posed.any_of(
                k,
                &object.points,
                near.within(k, object, &c, r + TOUCH_MARGIN),
                TOUCH_MARGIN,
                &Vector3::zeros(),
            )
    })
}

/// Closes `fingers` (each starting at path parameter `s0`) from the joints `base` (setting
/// joints of the pre-shape, other fingers in their posture). See the module documentation.
pub fn close_fingers(
    h: &SweepHand,
    base: &[f64],
    fingers: &[usize],
    s0: f64,
    object: &ObjectView,
) -> Result<Closed, FieldError> {
    let links: Vec<Vec<(usize, Vec<usize>)>> = fingers
        .iter()
        .map(|&f| finger_links(h.hand, h.collision, f))
        .collect();
    // Per finger: the flexion joints that move each link (palm side first, so link i is moved
    // by the flexion joints on bodies up to and including it).
    let movers: Vec<Vec<Vec<usize>>> = fingers
        .iter()
        .zip(&links)
        .map(|(&f, ls)| {
            let fs = &h.synergy.fingers[f];
            ls.iter()
                .map(|(b, _)| {
                    (0..fs.flexion.len())
                        .filter(|&k| h.hand.tree.joint_moves(fs.flexion[k].joint, *b))
                        .collect()
                })
                .collect()
        })
        .collect();
    let mut s: Vec<(usize, Vec<f64>)> = fingers
        .iter()
        .map(|&f| (f, vec![s0; h.synergy.fingers[f].flexion.len()]))
        .collect();
    let mut active: Vec<Vec<bool>> = s.iter().map(|(_, v)| vec![true; v.len()]).collect();
    let mut stopped_links: Vec<Vec<bool>> = links.iter().map(|l| vec![false; l.len()]).collect();
    // Linked fingers advance as one: a group is done when all its fingers touched.
    let linked: Vec<bool> = fingers
        .iter()
        .map(|&f| h.synergy.fingers[f].constrained)
        .collect();
    let mut linked_touch: Vec<Option<f64>> = vec![None; fingers.len()];
    let ds = 1.0 / STEPS as f64;
    let mut near = NearPoints::default();
    let at_base = h.hand.tree.forward(base)?;
    let mut warm = base.to_vec();
    for _ in 0..(2 * STEPS) {
        if active.iter().all(|a| a.iter().all(|x| !x)) {
            break;
        }
        let advance = |s: &[(usize, Vec<f64>)], act: &[Vec<bool>], step: f64| {
            s.iter()
                .zip(act)
                .map(|((f, v), a)| {
                    (
                        *f,
                        v.iter()
                            .zip(a)
                            .map(|(x, on)| if *on { (x + step).min(1.0) } else { *x })
                            .collect::<Vec<f64>>(),
                    )
                })
                .collect::<Vec<_>>()
        };
        let next = advance(&s, &active, ds);
        let (q_next, posed) = h.configure_posed(base, &at_base, &next, &warm)?;
        // Which still-moving links touch: per finger, per link (None: not moving).
        let touching = |posed: &PosedCollision,
                        stopped_links: &[Vec<bool>],
                        active: &[Vec<bool>],
                        near: &mut NearPoints| {
            links
                .iter()
                .enumerate()
                .map(|(i, ls)| {
                    ls.iter()
                        .enumerate()
                        .map(|(l, (_, pieces))| {
                            let moving =
                                !stopped_links[i][l] && movers[i][l].iter().any(|&k| active[i][k]);
                            moving.then(|| link_touches(posed, pieces, object, near))
                        })
                        .collect::<Vec<Option<bool>>>()
                })
                .collect::<Vec<_>>()
        };
        let any = |t: &[Vec<Option<bool>>]| t.iter().flatten().any(|x| *x == Some(true));
        let mut at_hi = touching(&posed, &stopped_links, &active, &mut near);
        if !any(&at_hi) {
            s = next;
            warm = q_next;
            // Joints that reached the closed limit stop.
            for (i, (_, v)) in s.iter().enumerate() {
                for (k, x) in v.iter().enumerate() {
                    if *x >= 1.0 {
                        active[i][k] = false;
                    }
                }
            }
            continue;
        }
        // Refine the first touch: the largest fraction of the step that touches nothing. Only
        // the fingers that touch at the whole step are posed and tested (the others, which
        // touch nothing there, are taken to touch nothing before), unless a linkage ties the
        // fingers' joints together.
        let tied = linked.iter().any(|&x| x);
        let refined: Vec<Vec<bool>> = active
            .iter()
            .zip(&at_hi)
            .map(|(a, t)| {
                let touched = t.contains(&Some(true));
                a.iter().map(|&on| on && (touched || tied)).collect()
            })
            .collect();
        let (mut lo, mut hi) = (0.0, ds);
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (lo + hi);
            let (_, posed) =
                h.configure_posed(base, &at_base, &advance(&s, &refined, mid), &warm)?;
            let at_mid = touching(&posed, &stopped_links, &refined, &mut near);
            if any(&at_mid) {
                hi = mid;
                at_hi = at_mid;
            } else {
                lo = mid
            }
        }
        s = advance(&s, &active, lo);
        // Stop the joints moving each link that touches at `hi`.
        for (i, ls) in at_hi.iter().enumerate() {
            for (l, t) in ls.iter().enumerate() {
                if *t != Some(true) {
                    continue;
                }
                stopped_links[i][l] = true;
                if linked[i] {
                    linked_touch[i].get_or_insert(s[i].1.first().copied().unwrap_or(0.0));
                    continue;
                }
                for &k in &movers[i][l] {
                    active[i][k] = false;
                }
            }
        }
        // A linked group stops when all its fingers touched (or its joints are closed).
        if linked.iter().any(|&x| x) {
            let all = (0..fingers.len())
                .filter(|&i| linked[i])
                .all(|i| linked_touch[i].is_some());
            if all {
                for (i, a) in active.iter_mut().enumerate() {
                    if linked[i] {
                        a.iter_mut().for_each(|x| *x = false);
                    }
                }
            }
        }
    }
    let (joints, posed) = h.configure_posed(base, &at_base, &s, &warm)?;
    let mut contacts = Vec::new();
    for (i, ls) in links.iter().enumerate() {
        for (b, pieces) in ls {
            if let Some(c) = patch(&posed, pieces, object, *b, Some(fingers[i]), &mut near) {
                contacts.push(c);
            }
        }
    }
    // How far the linked fingers that touched first were carried on into the object.
    let mut push: f64 = 0.0;
    for (i, t) in linked_touch.iter().enumerate() {
        if t.is_some() {
            for (_, pieces) in &links[i] {
                for &k in pieces {
                    for (_, d) in posed.touching(k, &object.points, &object.index, 0.0) {
                        push = push.max(-d);
                    }
                }
            }
        }
    }
    Ok(Closed {
        joints,
        s,
        contacts,
        push,
    })
}

/// The unit mean of a patch's unit normals and its coherence, the length of their mean (1 for
/// a flat patch; cos 45° = 0.71 for one half on each face of a box's edge); None for an empty
/// patch or normals that cancel.
pub fn mean_normal(normals: impl Iterator<Item = Vector3<f64>>) -> Option<(Vector3<f64>, f64)> {
    let (sum, n) = normals.fold((Vector3::zeros(), 0usize), |(s, n), v| (s + v, n + 1));
    let unit = sum.try_normalize(1e-9)?;
    Some((unit, sum.norm() / n as f64))
}

/// The coherence of the object's normals within [`COHERENCE_RADIUS`] of a contact's
/// `position` (the length of their unit mean, [`mean_normal`]).
///
/// A fingertip on a can's side a few mm below its rim has a patch of side points only, yet
/// under the squeeze it rolls onto the rim and the can slips out downward: measured on the
/// Table 5.2 run (20 trials per cell, paired), judging the edge by the patch alone left the
/// Shadow's tuna-can grasps on the rim (7 of 20 held). The neighbourhood is a ball about the
/// contact, not a band about the link: a finger coming down beside a low box passes its top
/// edge with the rest of its link, wherever its tip presses (docs/final-configuration.md,
/// "Contacts by an edge, and no joint opens").
fn neighbourhood_coherence(object: &ObjectView, position: &Point3<f64>) -> Option<f64> {
    mean_normal(
        object
            .index
            .within_unsorted(position, COHERENCE_RADIUS)
            .map(|i| object.normals.get(object.source[i])),
    )
    .map(|(_, c)| c)
}

/// The contact patch of `body`'s pieces: the object points within [`PATCH_MARGIN`], their mean
/// position and normal, and the nearest point (`near`: the sweep's points about each piece).
pub fn patch(
    posed: &PosedCollision,
    pieces: &[usize],
    object: &ObjectView,
    body: usize,
    finger: Option<usize>,
    near: &mut NearPoints,
) -> Option<SweepContact> {
    let mut pts: Vec<(usize, f64)> = Vec::new();
    for &k in pieces {
        let (c, r) = posed.sphere(k);
        if !object.near(&c, r + PATCH_MARGIN) {
            continue;
        }
        let within = near.within(k, object, &c, r + PATCH_MARGIN);
        for (i, d) in posed.touching_of(k, &object.points, within, PATCH_MARGIN) {
            match pts.iter_mut().find(|(j, _)| *j == i) {
                Some(e) => e.1 = e.1.min(d),
                None => pts.push((i, d)),
            }
        }
    }
    if pts.is_empty() {
        return None;
    }
    pts.sort_by_key(|&(i, _)| i);
    let n = pts.len() as f64;
    let position = Point3::from(
        pts.iter()
            .map(|&(i, _)| object.points[i].coords)
            .sum::<Vector3<f64>>()
            / n,
    );
    let (normal, _) = mean_normal(
        pts.iter()
            .map(|&(i, _)| object.normals.get(object.source[i])),
    )?;
    let nearest = pts
        .iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|&(i, _)| i)?;
    // A patch wrapping a thin part or a rounded corner has its mean inside the object, with no
    // object point within reach: its edge is then judged about its nearest point.
    let coherence = neighbourhood_coherence(object, &position)
        .or_else(|| neighbourhood_coherence(object, &object.points[nearest]))?;
    let point = object.source[nearest];
    let gap = pieces
        .iter()
        .map(|&k| posed.signed_distance(k, &position).abs())
        .fold(f64::INFINITY, f64::min);
    Some(SweepContact {
        finger,
        body,
        point,
        position,
        normal,
        gap,
        coherence,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A patch on one face is coherent; one astride a box's edge, half on each face, has the
    /// mean normal at 45° and coherence cos 45°; a fingertip patch of ±20° on a ball keeps
    /// coherence above the edge threshold (the mean of cos θ over a cap of half-angle α is
    /// cos²(α/2) = 0.97); normals that cancel give none.
    #[test]
    fn coherence_tells_a_face_from_an_edge() {
        let x = Vector3::x();
        let z = Vector3::z();
        let (n, c) = mean_normal([x, x, x].into_iter()).unwrap();
        assert!((n - x).norm() < 1e-12 && (c - 1.0).abs() < 1e-12);
        let (n, c) = mean_normal([x, x, z, z].into_iter()).unwrap();
        assert!((n - (x + z).normalize()).norm() < 1e-12);
        assert!((c - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12, "{c}");
        assert!(c < super::super::EDGE_COHERENCE);
        // A cap of half-angle 20° sampled evenly in solid angle (rings of equal area).
        let alpha = 20f64.to_radians();
        let mut cap = Vec::new();
        for i in 0..200 {
            let cos_t = 1.0 - (1.0 - alpha.cos()) * (i as f64 + 0.5) / 200.0;
            let sin_t = (1.0 - cos_t * cos_t).sqrt();
            for k in 0..12 {
                let phi = std::f64::consts::TAU * k as f64 / 12.0;
                cap.push(Vector3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t));
            }
        }
        let (_, c) = mean_normal(cap.into_iter()).unwrap();
        assert!((c - (alpha / 2.0).cos().powi(2)).abs() < 1e-3, "{c}");
        assert!(c > super::super::EDGE_COHERENCE);
        assert!(mean_normal([x, -x].into_iter()).is_none());
        assert!(mean_normal(std::iter::empty()).is_none());
    }

    /// A two-finger hand; the first finger's tip is a sphere of 8 mm radius centred 5 cm below
    /// the palm, the second finger is 20 cm away.
    const FINGERTIP: &str = r#"<mujoco>
  <worldbody>
    <body name="palm">
      <geom type="box" size="0.02 0.02 0.005"/>
      <body name="finger">
        <joint name="j" axis="0 1 0" range="0 1.5"/>
        <body name="tip" pos="0 0 -0.05"><geom type="sphere" size="0.008"/></body>
      </body>
      <body name="other" pos="0.2 0 0">
        <joint name="k" axis="0 1 0" range="0 1.5"/>
        <body name="other_tip" pos="0 0 -0.05"><geom type="sphere" size="0.008"/></body>
      </body>
    </body>
  </worldbody>
</mujoco>"#;

    /// A can of radius 4 cm and height 33 mm standing on z = 0 (side every 2 mm and 4°, top
    /// every 2 mm), its axis through (x, 0), with its true normals.
    fn can(x: f64) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        let (r, h) = (0.04, 0.033);
        let mut points = Vec::new();
        let mut normals = Vec::new();
        for k in 0..90 {
            let a = (k as f64 * 4.0).to_radians();
            for i in 0..=16 {
                points.push(Point3::new(
                    x + r * a.cos(),
                    r * a.sin(),
                    0.002 * i as f64 + 0.001,
                ));
                normals.push(Vector3::new(a.cos(), a.sin(), 0.0));
            }
        }
        for i in -20..=20 {
            for j in -20..=20 {
                let (u, v) = (0.002 * i as f64, 0.002 * j as f64);
                if u * u + v * v < r * r {
                    points.push(Point3::new(x + u, v, h));
                    normals.push(Vector3::z());
                }
            }
        }
        (points, normals)
    }

    /// A fingertip touching a can's side halfway up lies on one face; one touching it 6 mm
    /// below the rim is by an edge (the squeeze rolls it onto the rim: top points lie within
    /// `COHERENCE_RADIUS` of the contact), though its contact patch alone holds side points
    /// only.
    #[test]
    fn a_fingertip_below_a_rim_is_by_an_edge() {
        use crate::cloud::{CloudIndex, LazyNormals, Orientation};
        let hand = KinematicHand::from_mjcf_str(FINGERTIP, ".").unwrap();
        let collision = hand.collision_model().unwrap();
        let tip_body = hand.tree.body_index("tip").unwrap();
        let pieces: Vec<usize> = (0..collision.pieces.len())
            .filter(|&k| collision.pieces[k].body == tip_body)
            .collect();
        let coherence_at = |below_rim: f64| {
            // Lift the hand so that the fingertip's centre is `below_rim` under the can's top,
            // its sphere 1 mm from the side.
            let root = Isometry3::translation(0.0, 0.0, 0.033 - below_rim + 0.05);
            let fk = hand.tree.forward(&[0.0, 0.0]).unwrap();
            let posed = collision.posed_fk(&fk, &root);
            let (points, normals) = can(-(0.04 + 0.008 + 0.001));
            let index = CloudIndex::new(&points);
            let lazy = LazyNormals::new(
                &points,
                &index,
                12,
                Orientation::AwayFromCentroid,
                Some(normals),
            );
            let object = ObjectView::new(&points, &lazy, None);
            let p = patch(
                &posed,
                &pieces,
                &object,
                tip_body,
                Some(0),
                &mut NearPoints::default(),
            )
            .expect("touches");
            let (_, patch_alone) = mean_normal(
                posed
                    .touching(pieces[0], &object.points, &object.index, PATCH_MARGIN)
                    .iter()
                    .map(|&(i, _)| object.normals.get(object.source[i])),
            )
            .unwrap();
            (p.coherence, patch_alone, p.normal)
        };
        let (mid, _, n) = coherence_at(0.0165);
        assert!(mid > super::super::EDGE_COHERENCE, "{mid}");
        assert!(n.x > 0.99, "{n:?}");
        let (rim, patch_alone, _) = coherence_at(0.006);
        assert!(rim < super::super::EDGE_COHERENCE, "{rim}");
        assert!(patch_alone > super::super::EDGE_COHERENCE, "{patch_alone}");
    }
}
