//! The face planes of a convex collision piece, grouped by the direction of their normals so that
//! a point's signed distance skips the groups that cannot hold its largest face-plane distance.
//!
//! A Menagerie Shadow link's hull has about 1,700 faces, and the closing sweep asks for the
//! distance of thousands of cloud points per candidate: a plain scan of every plane was a quarter
//! of a Shadow plan's time. A group of faces whose normals lie within θ of its axis a, with
//! `top` = max over the group of n·c − d (c the piece's centre), bounds every plane of the group at
//! a point x = c + v: n·x − d = (n·c − d) + n·v ≤ top + |v|·cos(max(0, ∠(a, v) − θ)), since the
//! angle between n and v is at least ∠(a, v) − θ. Groups whose bound cannot beat the best plane
//! found so far are skipped, so the result is the very value a full scan gives.

use parry3d_f64::math::Vector as PVec;

/// Plane tests below this many faces are a plain scan (a box, a small hull).
const GROUPED_FROM: usize = 48;
/// Directions faces are grouped about (a Fibonacci sphere): about 19° between neighbours.
const DIRECTIONS: usize = 96;
/// Added to each group's bound: the float rounding of n·x − d is far below it.
const BOUND_SLOP: f64 = 1e-9;
/// Cells per edge of each face of the cube map from a direction to the face whose normal is
/// nearest it.
const CUBE_CELLS: usize = 8;

/// Faces whose normals lie within θ of `axis`: planes `start..end`.
#[derive(Debug, Clone)]
struct FaceGroup {
    axis: PVec,
    cos: f64,
    sin: f64,
    /// max over the group's planes of n·centre − d.
    top: f64,
    start: usize,
    end: usize,
}

/// The face planes (outward unit normal n, offset d with n·x ≤ d inside) of a convex piece in
/// its shape's frame, grouped by normal direction (module doc).
#[derive(Debug, Clone)]
pub struct ConvexFaces {
    planes: Vec<(PVec, f64)>,
    groups: Vec<FaceGroup>,
    centre: PVec,
    /// Per cube-map cell (a direction from the centre), the plane whose normal is nearest it:
    /// the one a point far out that way is most likely rejected by, tried before any scan.
    facing: Vec<u32>,
}

/// The cube-map cell of direction `v` (not zero).
fn cube_cell(v: PVec) -> usize {
    let a = v.abs();
    let (side, major, u, w) = if a.x >= a.y && a.x >= a.z {
        (usize::from(v.x < 0.0), a.x, v.y, v.z)
    } else if a.y >= a.z {
        (2 + usize::from(v.y < 0.0), a.y, v.x, v.z)
    } else {
        (4 + usize::from(v.z < 0.0), a.z, v.x, v.y)
    };
    let cell =
        |t: f64| (((t / major + 1.0) * 0.5 * CUBE_CELLS as f64) as usize).min(CUBE_CELLS - 1);
    (side * CUBE_CELLS + cell(u)) * CUBE_CELLS + cell(w)
}

impl ConvexFaces {
    /// Groups `planes` about directions spread over the sphere; `centre` is a point inside the
    /// piece (its bounds' centre).
    pub fn new(planes: Vec<(PVec, f64)>, centre: PVec) -> Self {
        if planes.len() < GROUPED_FROM {
            return ConvexFaces {
                planes,
                groups: Vec::new(),
                centre,
                facing: Vec::new(),
            };
        }
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let dirs: Vec<PVec> = (0..DIRECTIONS)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / DIRECTIONS as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let t = golden * i as f64;
                PVec::new(r * t.cos(), r * t.sin(), z)
            })
            .collect();
        let nearest = |n: &PVec| {
            (0..dirs.len())
                .max_by(|&a, &b| dirs[a].dot(*n).total_cmp(&dirs[b].dot(*n)))
                .unwrap_or(0)
        };
        let mut by_dir: Vec<Vec<(PVec, f64)>> = vec![Vec::new(); dirs.len()];
        for p in planes {
            by_dir[nearest(&p.0)].push(p);
        }
        let mut ordered = Vec::new();
        let mut groups = Vec::new();
        for (axis, members) in dirs.into_iter().zip(by_dir) {
            if members.is_empty() {
                continue;
            }
            let cos = members
                .iter()
                .map(|(n, _)| n.dot(axis))
                .fold(1.0f64, f64::min)
                .clamp(-1.0, 1.0);
            let top = members
                .iter()
                .map(|(n, d)| n.dot(centre) - d)
                .fold(f64::NEG_INFINITY, f64::max);
            let start = ordered.len();
            ordered.extend(members);
            groups.push(FaceGroup {
                axis,
                cos,
                sin: (1.0 - cos * cos).max(0.0).sqrt(),
                top,
                start,
                end: ordered.len(),
            });
        }
        // Each cell's centre direction, and the plane whose normal is nearest it.
        let cells = 6 * CUBE_CELLS * CUBE_CELLS;
        let facing = (0..cells)
            .map(|i| {
                let (side, rest) = (i / (CUBE_CELLS * CUBE_CELLS), i % (CUBE_CELLS * CUBE_CELLS));
                let at = |k: usize| (k as f64 + 0.5) / CUBE_CELLS as f64 * 2.0 - 1.0;
                let (u, w) = (at(rest / CUBE_CELLS), at(rest % CUBE_CELLS));
                let sign = if side % 2 == 0 { 1.0 } else { -1.0 };
                let d = match side / 2 {
                    0 => PVec::new(sign, u, w),
                    1 => PVec::new(u, sign, w),
                    _ => PVec::new(u, w, sign),
                };
                debug_assert_eq!(cube_cell(d), i);
                (0..ordered.len())
                    .max_by(|&a, &b| ordered[a].0.dot(d).total_cmp(&ordered[b].0.dot(d)))
                    .unwrap_or(0) as u32
            })
            .collect();
        ConvexFaces {
            planes: ordered,
            groups,
            centre,
            facing,
        }
    }

    /// The planes, in no particular order.
    pub fn planes(&self) -> &[(PVec, f64)] {
        &self.planes
    }

    /// The largest face-plane distance n·x − d of `local` (negative inside: minus its depth)
    /// when it is below `margin`, else None. Plane `hint` is tried first and is set to the one
    /// that rejected the point: nearby points (a k-d tree query's, in its order) are mostly
    /// rejected by the same face. The value is the one a scan of every plane gives.
    pub fn distance_below(&self, local: PVec, margin: f64, hint: &mut usize) -> Option<f64> {
        if let Some((n, d)) = self.planes.get(*hint)
            && n.dot(local) - d >= margin
        {
            return None;
        }
        let mut best = f64::NEG_INFINITY;
        let mut scan = |range: std::ops::Range<usize>, best: &mut f64| -> bool {
            for j in range {
                let (n, d) = &self.planes[j];
                let e = n.dot(local) - d;
                if e >= margin {
                    *hint = j;
                    return true;
                }
                *best = best.max(e);
            }
            false
        };
        if self.groups.is_empty() {
            return (!scan(0..self.planes.len(), &mut best)).then_some(best);
        }
        let v = local - self.centre;
        if v != PVec::ZERO {
            let j = self.facing[cube_cell(v)] as usize;
            let (n, d) = &self.planes[j];
            if n.dot(local) - d >= margin {
                *hint = j;
                return None;
            }
        }
        let len = v.length();
        let bound = |g: &FaceGroup| -> f64 {
            let c = if len > 0.0 { g.axis.dot(v) / len } else { 1.0 };
            let reach = if c >= g.cos {
                len
            } else {
                len * (c * g.cos + (1.0 - c * c).max(0.0).sqrt() * g.sin)
            };
            g.top + reach + BOUND_SLOP
        };
        let mut bounds = [0.0; DIRECTIONS];
        let bounds = &mut bounds[..self.groups.len()];
        for (b, g) in bounds.iter_mut().zip(&self.groups) {
            *b = bound(g);
        }
        // The group most likely to hold the largest plane first, so that the rest are skipped.
        let first = (0..bounds.len())
            .max_by(|&a, &b| bounds[a].total_cmp(&bounds[b]))
            .unwrap_or(0);
        let g = &self.groups[first];
        if scan(g.start..g.end, &mut best) {
            return None;
        }
        for (i, g) in self.groups.iter().enumerate() {
            if i == first || bounds[i] <= best {
                continue;
            }
            if scan(g.start..g.end, &mut best) {
                return None;
            }
        }
        Some(best)
    }

    /// The largest face-plane distance of `local` (exact off the faces, short of the distance
    /// near edges and corners).
    pub fn distance(&self, local: PVec) -> f64 {
        self.distance_below(local, f64::INFINITY, &mut 0)
            .unwrap_or(f64::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Planes tangent to a unit sphere at many directions (a finely faceted ball, as a mesh hull
    /// is): the grouped answer is the plain scan's, bit for bit, inside, near and far outside,
    /// and at every margin.
    #[test]
    fn grouped_planes_answer_as_a_scan_of_every_plane() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let planes: Vec<(PVec, f64)> = (0..700)
            .map(|_| {
                let n = PVec::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
                .normalize();
                (n, rng.random_range(0.9..1.0))
            })
            .collect();
        let faces = ConvexFaces::new(planes.clone(), PVec::new(0.01, -0.02, 0.0));
        assert!(faces.groups.len() > 10);
        assert_eq!(faces.planes().len(), planes.len());
        let scan = |x: PVec| {
            planes
                .iter()
                .map(|(n, d)| n.dot(x) - d)
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let mut hint = 0;
        for _ in 0..5000 {
            let x = PVec::new(
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.5..1.5),
            );
            let exact = scan(x);
            assert_eq!(faces.distance(x), exact);
            for margin in [-0.5, 0.0, 0.002, 0.3] {
                let got = faces.distance_below(x, margin, &mut hint);
                assert_eq!(
                    got,
                    (exact < margin).then_some(exact),
                    "x {x:?} margin {margin}"
                );
            }
        }
    }

    /// A box's six faces: inside, the depth to the nearest face; outside a face, the distance.
    #[test]
    fn a_box_is_scanned_plainly() {
        let planes = vec![
            (PVec::X, 1.0),
            (-PVec::X, 1.0),
            (PVec::Y, 2.0),
            (-PVec::Y, 2.0),
            (PVec::Z, 3.0),
            (-PVec::Z, 3.0),
        ];
        let faces = ConvexFaces::new(planes, PVec::ZERO);
        assert_eq!(faces.distance(PVec::new(0.5, 0.0, 0.0)), -0.5);
        assert_eq!(faces.distance(PVec::new(0.0, 2.5, 0.0)), 0.5);
        assert_eq!(
            faces.distance_below(PVec::new(0.0, 2.5, 0.0), 0.4, &mut 0),
            None
        );
    }
}
