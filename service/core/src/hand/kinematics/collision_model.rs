//! Collision geometry of a hand with known kinematics (issue 6 §3): the collision geoms of the
//! palm and of every body below it as convex parry3d shapes, posed by forward kinematics.
//!
//! - primitives map to their parry shapes (MuJoCo's cylinders and capsules run along z, parry's
//!   cylinder along y: the piece is turned accordingly); an ellipsoid becomes the hull of 98
//!   points on its surface; planes are skipped;
//! - a mesh becomes the convex hull of its vertices (a decomposed mesh, such as the Barrett's
//!   `*_convex_decomposition_p*` parts, stays a union of hulls; a non-convex single mesh is
//!   over-approximated by its hull); a flat mesh whose hull is degenerate becomes its bounding box;
//! - every body of the model takes part, the ones above the palm too: a wrist, a forearm or a
//!   flange is mounted with the hand and meets the table and the object like the fingers do.
//!
//! A posed hand answers the questions of the planner's collision checks: the least signed
//! distance to the support plane, how many cloud points lie deeper than a tolerance inside it,
//! and which points one piece touches (signed distance below a margin, found through the cloud's
//! k-d tree within the piece's bounding sphere).

use super::convex_faces::ConvexFaces;
use super::hand_model::KinematicHand;
use super::kinematic_tree::GeomShape;
use crate::cloud::Plane;
use crate::error::FieldError;
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use parry3d_f64::math::{Pose3, Rot3, Vector as PVec};
use parry3d_f64::shape::SharedShape;
use std::cell::OnceCell;
use std::sync::Arc;

/// How far past a margin [`PosedCollision::round_distance_bound`] must be to decide without
/// parry's projection, m: float rounding between the two computations is far below it.
const ROUND_BOUND_SLOP: f64 = 1e-9;

fn pv(v: &Vector3<f64>) -> PVec {
    PVec::new(v.x, v.y, v.z)
}

fn pose3(iso: &Isometry3<f64>) -> Pose3 {
    let q = iso.rotation;
    Pose3::from_parts(
        pv(&iso.translation.vector),
        Rot3::from_xyzw(q.i, q.j, q.k, q.w),
    )
}

/// One convex piece: a shape fixed to a body.
#[derive(Clone)]
pub struct CollisionPiece {
    /// The body it moves with.
    pub body: usize,
    /// Pose of the shape in the body frame.
    pub pose: Isometry3<f64>,
    pub shape: SharedShape,
    /// For a convex polyhedron or a box: its face planes (outward unit normal n, offset d with
    /// n·x ≤ d inside), in the shape's frame; the depth of an inside point is min over faces of
    /// d − n·x.
    pub faces: Option<FacePlanes>,
    /// Bounding sphere in the body frame: centre and radius.
    pub centre: Point3<f64>,
    pub radius: f64,
    /// For a ball, capsule or cylinder: the ends of its axis in the body frame and its radius.
    pub axis: Option<RoundAxis>,
}

/// The ends of a round piece's axis and its radius (a ball's ends are its centre; a cylinder
/// lies inside the capsule on its axis).
pub type RoundAxis = (Point3<f64>, Point3<f64>, f64);

/// Face planes (outward unit normal, offset) of a convex piece.
pub type FacePlanes = Arc<ConvexFaces>;

/// The face planes of a convex polyhedron or a box, grouped about the centre of its bounds.
fn face_planes(shape: &SharedShape) -> Option<FacePlanes> {
    let aabb = shape.compute_local_aabb();
    let centre = (aabb.mins + aabb.maxs) * 0.5;
    let planes = plane_list(shape)?;
    Some(Arc::new(ConvexFaces::new(planes, centre)))
}

/// The face planes of a convex polyhedron or a box, as listed by its shape.
fn plane_list(shape: &SharedShape) -> Option<Vec<(PVec, f64)>> {
    if let Some(b) = shape.as_cuboid() {
        let h = b.half_extents;
        let planes: Vec<(PVec, f64)> = vec![
            (PVec::X, h.x),
            (-PVec::X, h.x),
            (PVec::Y, h.y),
            (-PVec::Y, h.y),
            (PVec::Z, h.z),
            (-PVec::Z, h.z),
        ];
        return Some(planes);
    }
    let poly = shape.as_convex_polyhedron()?;
    let pts = poly.points();
    let adj = poly.vertices_adj_to_face();
    let planes: Vec<(PVec, f64)> = poly
        .faces()
        .iter()
        .map(|f| {
            let v = pts[adj[f.first_vertex_or_edge as usize] as usize];
            (f.normal, f.normal.dot(v))
        })
        .collect();
    Some(planes)
}

impl std::fmt::Debug for CollisionPiece {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CollisionPiece")
            .field("body", &self.body)
            .field("pose", &self.pose)
            .field("shape", &self.shape.shape_type())
            .finish()
    }
}

/// The convex pieces of a hand, built once per hand.
#[derive(Debug, Clone)]
pub struct HandCollision {
    pub pieces: Vec<CollisionPiece>,
}

/// The pieces posed in the world for one configuration and hand pose. The shapes are the hand's
/// own, borrowed, and each piece is posed when first asked for: the closing sweep poses the hand
/// hundreds of times per candidate and tests only the moving fingers' pieces.
#[derive(Debug, Clone)]
pub struct PosedCollision<'h> {
    hand: &'h HandCollision,
    /// Each body's pose in the world.
    bodies: Vec<Isometry3<f64>>,
    pieces: Vec<OnceCell<PosedPiece>>,
}

/// One piece posed in the world.
#[derive(Debug, Clone)]
struct PosedPiece {
    /// Pose of the shape.
    pose: Pose3,
    /// Bounding sphere: centre and radius.
    sphere: (Point3<f64>, f64),
    /// A round piece's axis ends and its radius ([`CollisionPiece::axis`]).
    axis: Option<RoundAxis>,
}

impl KinematicHand {
    /// Builds the convex collision pieces of every body of the model.
    pub fn collision_model(&self) -> Result<HandCollision, FieldError> {
        let mut pieces = Vec::new();
        let mut stack = vec![0];
        while let Some(b) = stack.pop() {
            let body = &self.tree.bodies[b];
            stack.extend(body.children.iter().rev().copied());
            for g in body.geoms.iter().filter(|g| g.collision) {
                let field = || format!("hand.bodies[{}].geoms", body.name);
                let (shape, turn) = match &g.shape {
                    GeomShape::Sphere { radius } => (SharedShape::ball(*radius), None),
                    GeomShape::Capsule {
                        radius,
                        half_length,
                    } => (SharedShape::capsule_z(*half_length, *radius), None),
                    GeomShape::Cylinder {
                        radius,
                        half_length,
                    } => (
                        SharedShape::cylinder(*half_length, *radius),
                        // parry's cylinder runs along y; MuJoCo's along z.
                        Some(UnitQuaternion::from_axis_angle(
                            &Vector3::x_axis(),
                            std::f64::consts::FRAC_PI_2,
                        )),
                    ),
                    GeomShape::Box { half_extents } => (
                        SharedShape::cuboid(half_extents.x, half_extents.y, half_extents.z),
                        None,
                    ),
                    GeomShape::Ellipsoid { radii } => {
                        let pts: Vec<PVec> = (0..7)
                            .flat_map(|i| {
                                let th = std::f64::consts::PI * (i as f64 + 0.5) / 7.0;
                                (0..14).map(move |k| {
                                    let ph = std::f64::consts::TAU * k as f64 / 14.0;
                                    (th, ph)
                                })
                            })
                            .map(|(th, ph)| {
                                PVec::new(
                                    radii.x * th.sin() * ph.cos(),
                                    radii.y * th.sin() * ph.sin(),
                                    radii.z * th.cos(),
                                )
                            })
                            .collect();
                        let s = SharedShape::convex_hull(&pts).ok_or_else(|| {
                            FieldError::new(field(), "degenerate ellipsoid (a zero radius)")
                        })?;
                        (s, None)
                    }
                    GeomShape::Plane => continue,
                    GeomShape::Mesh { name, vertices, .. } => {
                        if vertices.is_empty() {
                            return Err(FieldError::new(
                                field(),
                                format!("collision mesh '{name}' has no vertices"),
                            ));
                        }
                        (hull_or_box(vertices), None)
                    }
                };
                let pose = match turn {
                    Some(r) => g.pose * r,
                    None => g.pose,
                };
                let aabb = shape.compute_local_aabb();
                let (lo, hi) = (aabb.mins, aabb.maxs);
                let local_centre = Point3::new(
                    0.5 * (lo.x + hi.x),
                    0.5 * (lo.y + hi.y),
                    0.5 * (lo.z + hi.z),
                );
                // A round piece's axis, and its own bounding sphere (its bounds' corners lie
                // outside it: a capsule's by a tenth of its radius, the ball each touch test
                // queries the cloud with); a polyhedron's stays its bounds' (its face-plane
                // distance reaches past its corners).
                let ends = |a: PVec, b: PVec, r: f64| {
                    let p = |v: PVec| pose * Point3::new(v.x, v.y, v.z);
                    Some((p(a), p(b), r))
                };
                let (axis, radius) = if let Some(ball) = shape.as_ball() {
                    (ends(PVec::ZERO, PVec::ZERO, ball.radius), ball.radius)
                } else if let Some(c) = shape.as_capsule() {
                    (
                        ends(c.segment.a, c.segment.b, c.radius),
                        c.half_height() + c.radius,
                    )
                } else if let Some(c) = shape.as_cylinder() {
                    let h = PVec::new(0.0, c.half_height, 0.0);
                    (ends(-h, h, c.radius), c.half_height.hypot(c.radius))
                } else {
                    (None, 0.5 * (hi - lo).length())
                };
                pieces.push(CollisionPiece {
                    body: b,
                    centre: pose * local_centre,
                    radius,
                    axis,
                    pose,
                    faces: face_planes(&shape),
                    shape,
                });
            }
        }
        Ok(HandCollision { pieces })
    }
}

/// Convex hull of mesh vertices (deduplicated), or their bounding box if the hull is degenerate.
fn hull_or_box(vertices: &[Point3<f64>]) -> SharedShape {
    let mut pts: Vec<[u64; 3]> = vertices
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect();
    pts.sort_unstable();
    pts.dedup();
    let pts: Vec<PVec> = pts
        .iter()
        .map(|b| {
            PVec::new(
                f64::from_bits(b[0]),
                f64::from_bits(b[1]),
                f64::from_bits(b[2]),
            )
        })
        .collect();
    if let Some(h) = SharedShape::convex_hull(&pts) {
        return h;
    }
    let (lo, hi) = pts.iter().fold(
        (PVec::splat(f64::INFINITY), PVec::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let half = ((hi - lo) * 0.5).max(PVec::splat(1e-4));
    let centre = (hi + lo) * 0.5;
    SharedShape::compound(vec![(
        Pose3::from_translation(centre),
        SharedShape::cuboid(half.x, half.y, half.z),
    )])
}

impl HandCollision {
    /// Poses the pieces for joint vector `q` with the hand frame at `hand_pose` in the world.
    pub fn posed(
        &self,
        hand: &KinematicHand,
        q: &[f64],
        hand_pose: &Isometry3<f64>,
    ) -> Result<PosedCollision<'_>, FieldError> {
        let fk = hand.tree.forward(q)?;
        // World ← hand frame ← palm body ← root.
        let root_in_world = hand_pose * (fk.body_poses[hand.palm] * hand.hand_frame).inverse();
        Ok(self.posed_fk(&fk, &root_in_world))
    }

    /// Poses the pieces from a forward-kinematics result with the model's root at
    /// `root_in_world`.
    pub fn posed_fk(
        &self,
        fk: &super::ForwardKinematics,
        root_in_world: &Isometry3<f64>,
    ) -> PosedCollision<'_> {
        PosedCollision {
            hand: self,
            bodies: fk.body_poses.iter().map(|b| root_in_world * b).collect(),
            pieces: vec![OnceCell::new(); self.pieces.len()],
        }
    }
}

impl PosedCollision<'_> {
    /// Piece `k` posed in the world.
    fn posed(&self, k: usize) -> &PosedPiece {
        self.pieces[k].get_or_init(|| {
            let p = &self.hand.pieces[k];
            let body = &self.bodies[p.body];
            PosedPiece {
                pose: pose3(&(body * p.pose)),
                sphere: (body * p.centre, p.radius),
                axis: p.axis.map(|(a, b, r)| (body * a, body * b, r)),
            }
        })
    }

    /// Piece `k`'s pose in the world, its shape and its face planes.
    fn piece(&self, k: usize) -> (&Pose3, &SharedShape, Option<&ConvexFaces>) {
        let p = &self.hand.pieces[k];
        (&self.posed(k).pose, &p.shape, p.faces.as_deref())
    }

    /// Least signed distance of the hand geometry to `plane` (negative: through it), from each
    /// piece's support point against the plane normal.
    pub fn plane_clearance(&self, plane: &Plane) -> f64 {
        (0..self.pieces.len())
            .map(|k| self.piece_plane_clearance(k, plane))
            .fold(f64::INFINITY, f64::min)
    }

    /// Number of `points` deeper than `tolerance` inside any piece, counting at most `limit`.
    pub fn points_inside(&self, points: &[Point3<f64>], tolerance: f64, limit: usize) -> usize {
        let boxes: Vec<_> = (0..self.pieces.len())
            .map(|k| {
                let (pose, shape, _) = self.piece(k);
                shape.compute_aabb(pose)
            })
            .collect();
        let mut n = 0;
        for p in points {
            let v = PVec::new(p.x, p.y, p.z);
            let inside = boxes.iter().enumerate().any(|(k, aabb)| {
                let (pose, shape, faces) = self.piece(k);
                if v.cmplt(aabb.mins).any() || v.cmpgt(aabb.maxs).any() {
                    return false;
                }
                if let Some(faces) = faces {
                    // Exact for a convex polyhedron, without GJK.
                    let local = pose.inverse_transform_point(v);
                    return faces.distance_below(local, -tolerance, &mut 0).is_some();
                }
                if !shape.contains_point(pose, v) {
                    return false;
                }
                // Depth = distance to the boundary. parry's projection of a ball's or capsule's
                // exact centre is NaN (no direction): that point is the deepest one.
                let depth = (shape.project_point(pose, v, false).point - v).length();
                depth.is_nan() || depth > tolerance
            });
            if inside {
                n += 1;
                if n >= limit {
                    break;
                }
            }
        }
        n
    }

    /// Signed distance of `p` to piece `k`: negative inside (minus the depth). For a polyhedron or
    /// a box outside it, the largest face-plane distance, a lower bound of the distance (exact
    /// off the faces, short of it near edges and corners).
    pub fn signed_distance(&self, k: usize, p: &Point3<f64>) -> f64 {
        let (pose, shape, faces) = self.piece(k);
        let v = PVec::new(p.x, p.y, p.z);
        if let Some(faces) = faces {
            return faces.distance(pose.inverse_transform_point(v));
        }
        let proj = shape.project_point(pose, v, false);
        let d = (proj.point - v).length();
        if d.is_nan() {
            // parry cannot project a ball's or capsule's exact centre: the deepest point.
            return -self.posed(k).sphere.1;
        }
        if proj.is_inside { -d } else { d }
    }

    /// [`Self::signed_distance`] when it is below `margin`, else None (polyhedra stop at the
    /// first face the point is `margin` outside of).
    pub fn signed_distance_below(&self, k: usize, p: &Point3<f64>, margin: f64) -> Option<f64> {
        self.signed_distance_below_hinted(k, p, margin, &mut 0)
    }

    /// [`Self::signed_distance_below`] with a polyhedron's face `hint` tried first
    /// ([`ConvexFaces::distance_below`]): the queries of one piece share it.
    fn signed_distance_below_hinted(
        &self,
        k: usize,
        p: &Point3<f64>,
        margin: f64,
        hint: &mut usize,
    ) -> Option<f64> {
        let (pose, _, faces) = self.piece(k);
        if let Some(faces) = faces {
            let local = pose.inverse_transform_point(PVec::new(p.x, p.y, p.z));
            return faces.distance_below(local, margin, hint);
        }
        if let Some(far) = self.round_distance_bound(k, p)
            && far >= margin + ROUND_BOUND_SLOP
        {
            return None;
        }
        let d = self.signed_distance(k, p);
        (d < margin).then_some(d)
    }

    /// The points of `points` (indexed by `index`) closer to piece `k` than `margin` (signed
    /// distance < margin), with their signed distances.
    pub fn touching(
        &self,
        k: usize,
        points: &[Point3<f64>],
        index: &crate::cloud::CloudIndex,
        margin: f64,
    ) -> Vec<(usize, f64)> {
        let (c, r) = self.posed(k).sphere;
        self.touching_of(
            k,
            points,
            index.within_unsorted(&c, r + margin.max(0.0)),
            margin,
        )
    }

    /// [`Self::touching`] among `candidates` (the caller found them near the piece).
    pub fn touching_of(
        &self,
        k: usize,
        points: &[Point3<f64>],
        candidates: impl IntoIterator<Item = usize>,
        margin: f64,
    ) -> Vec<(usize, f64)> {
        self.below_among(k, points, candidates, margin, &Vector3::zeros())
            .collect()
    }

    /// The `candidates` of `points` (shifted by `offset`) closer to piece `k` than `margin`, with
    /// their signed distances, lazily; the queries share a polyhedron's face hint.
    fn below_among<'a>(
        &'a self,
        k: usize,
        points: &'a [Point3<f64>],
        candidates: impl IntoIterator<Item = usize> + 'a,
        margin: f64,
        offset: &'a Vector3<f64>,
    ) -> impl Iterator<Item = (usize, f64)> + 'a {
        let mut hint = 0;
        candidates.into_iter().filter_map(move |i| {
            self.signed_distance_below_hinted(k, &(points[i] - offset), margin, &mut hint)
                .map(|d| (i, d))
        })
    }

    /// A lower bound of a ball's, capsule's or cylinder's signed distance at `p` (a cylinder lies
    /// inside the capsule on its axis), computed directly from the axis posed in the world: most
    /// points a piece's bounding-sphere query returns are far from it, and parry's projection onto
    /// a capsule costs more than this test. None for other shapes.
    fn round_distance_bound(&self, k: usize, p: &Point3<f64>) -> Option<f64> {
        let (a, b, r) = self.posed(k).axis?;
        let ab = b - a;
        let len2 = ab.norm_squared();
        let t = if len2 > 0.0 {
            ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        Some((p - (a + ab * t)).norm() - r)
    }

    /// Whether any of `points` named by `candidates` (shifted by `offset`) is closer to piece `k`
    /// than `margin` (the caller found the candidates near the shifted piece).
    pub fn any_of(
        &self,
        k: usize,
        points: &[Point3<f64>],
        candidates: impl IntoIterator<Item = usize>,
        margin: f64,
        offset: &Vector3<f64>,
    ) -> bool {
        self.below_among(k, points, candidates, margin, offset)
            .next()
            .is_some()
    }

    /// Whether any of `points` (shifted by `offset`) is closer to piece `k` than `margin`.
    pub fn any_within(
        &self,
        k: usize,
        points: &[Point3<f64>],
        index: &crate::cloud::CloudIndex,
        margin: f64,
        offset: &Vector3<f64>,
    ) -> bool {
        let (c, r) = self.posed(k).sphere;
        let at = c + offset;
        let near = index.within_unsorted(&at, r + margin.max(0.0));
        self.any_of(k, points, near, margin, offset)
    }

    /// The body piece `k` belongs to.
    pub fn body_of(&self, k: usize) -> usize {
        self.hand.pieces[k].body
    }

    /// The bounding sphere of piece `k` in the world: centre and radius.
    pub fn sphere(&self, k: usize) -> (Point3<f64>, f64) {
        self.posed(k).sphere
    }

    /// Least signed distance of piece `k` to `plane`.
    pub fn piece_plane_clearance(&self, k: usize, plane: &Plane) -> f64 {
        let (pose, shape, _) = self.piece(k);
        let down = pv(&(-plane.normal));
        let p = match shape.as_support_map() {
            Some(s) => s.support_point(pose, down),
            None => {
                let aabb = shape.compute_aabb(pose);
                let pick = |lo: f64, hi: f64, d: f64| if d < 0.0 { lo } else { hi };
                PVec::new(
                    pick(aabb.mins.x, aabb.maxs.x, down.x),
                    pick(aabb.mins.y, aabb.maxs.y, down.y),
                    pick(aabb.mins.z, aabb.maxs.z, down.z),
                )
            }
        };
        plane.distance(&Point3::new(p.x, p.y, p.z))
    }

    /// Number of posed pieces.
    pub fn len(&self) -> usize {
        self.pieces.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pieces.is_empty()
    }
}
