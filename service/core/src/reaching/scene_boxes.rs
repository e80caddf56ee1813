//! The obstacles of a frame (§3.4.2: the other objects on the table): one box per object the
//! segmentation found, but the one the grasp is for, standing upright on the support plane.
//!
//! A box's axes are the support plane's normal and the principal horizontal direction of the
//! object's points; it reaches from the plane to the object's top. A single view sees an object's
//! front only, so the box is made at least as deep, away from the camera, as it is wide (the
//! unseen half of a can or a box is about as deep as its visible face is wide).

use super::obstacles::Obstacle;
use crate::cloud::Plane;
use nalgebra::{Matrix2, Point3, Rotation3, SymmetricEigen, UnitQuaternion, Vector2, Vector3};

/// Boxes round each cluster of points but the one nearest to `goal` (the grasp's object).
/// `plane` is the support plane (its normal is up; without one, +z is), `viewpoint` the camera's
/// position, all in one frame.
pub fn obstacle_boxes(
    clusters: &[Vec<Point3<f64>>],
    plane: Option<&Plane>,
    viewpoint: &Point3<f64>,
    goal: &Point3<f64>,
) -> Vec<Obstacle> {
    let nearest = |c: &Vec<Point3<f64>>| {
        c.iter()
            .map(|p| (p - goal).norm())
            .fold(f64::INFINITY, f64::min)
    };
    let target = (0..clusters.len())
        .min_by(|&a, &b| nearest(&clusters[a]).total_cmp(&nearest(&clusters[b])));
    clusters
        .iter()
        .enumerate()
        .filter(|(i, c)| Some(*i) != target && c.len() >= 3)
        .map(|(_, c)| upright_box(c, plane, viewpoint))
        .collect()
}

/// The upright box of one object's points (module doc).
fn upright_box(points: &[Point3<f64>], plane: Option<&Plane>, viewpoint: &Point3<f64>) -> Obstacle {
    let up = plane.map_or(Vector3::z(), |p| p.normal);
    let e1 = if up.x.abs() < 0.9 {
        up.cross(&Vector3::x())
    } else {
        up.cross(&Vector3::y())
    }
    .normalize();
    let e2 = up.cross(&e1);
    let n = points.len() as f64;
    let centroid = points.iter().map(|p| p.coords).sum::<Vector3<f64>>() / n;
    // The principal horizontal direction of the points.
    let flat: Vec<Vector2<f64>> = points
        .iter()
        .map(|p| {
            let d = p.coords - centroid;
            Vector2::new(d.dot(&e1), d.dot(&e2))
        })
        .collect();
    let cov = flat.iter().map(|f| f * f.transpose()).sum::<Matrix2<f64>>() / n;
    let eig = SymmetricEigen::new(cov);
    let major = if eig.eigenvalues[0] >= eig.eigenvalues[1] {
        eig.eigenvectors.column(0).into_owned()
    } else {
        eig.eigenvectors.column(1).into_owned()
    };
    let x = (major[0] * e1 + major[1] * e2).normalize();
    let y = up.cross(&x);
    let along = |axis: &Vector3<f64>| {
        points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                let t = p.coords.dot(axis);
                (lo.min(t), hi.max(t))
            })
    };
    let (mut xs, mut ys, (z_lo, z_hi)) = (along(&x), along(&y), along(&up));
    // Down to the table: its height along `up` where the plane is (n·p + d = 0).
    let z_lo = plane.map_or(z_lo, |p| -p.offset);
    // As deep as wide, away from the camera, along the axis the camera looks most along.
    let look = centroid - viewpoint.coords;
    let away = |axis: &Vector3<f64>| look.dot(axis);
    let along_x = away(&x).abs() >= away(&y).abs();
    let (axis, other) = if along_x {
        (&x, ys.1 - ys.0)
    } else {
        (&y, xs.1 - xs.0)
    };
    let deep = if along_x { &mut xs } else { &mut ys };
    let short = other - (deep.1 - deep.0);
    if short > 0.0 {
        if away(axis) >= 0.0 {
            deep.1 += short;
        } else {
            deep.0 -= short;
        }
    }
    let mid = |r: (f64, f64)| 0.5 * (r.0 + r.1);
    let half = |r: (f64, f64)| (0.5 * (r.1 - r.0)).max(1e-3);
    Obstacle {
        centre: Point3::from(x * mid(xs) + y * mid(ys) + up * mid((z_lo, z_hi))),
        half_extents: Vector3::new(half(xs), half(ys), half((z_lo, z_hi))),
        orientation: UnitQuaternion::from_rotation_matrix(&Rotation3::from_basis_unchecked(&[
            x, y, up,
        ])),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The front face of an 8 cm wide, 20 cm tall object seen from the camera at the origin
    /// looking along +x, its face 2 cm deep in x, standing on the table z = −0.5.
    fn front(cx: f64, cy: f64) -> Vec<Point3<f64>> {
        let mut v = Vec::new();
        for i in 0..9 {
            for k in 0..21 {
                let y = cy - 0.04 + 0.01 * i as f64;
                let depth = 0.02 * (1.0 - ((y - cy) / 0.04).powi(2));
                v.push(Point3::new(cx - depth, y, -0.5 + 0.01 * k as f64));
            }
        }
        v
    }

    #[test]
    fn each_other_object_becomes_an_upright_box_as_deep_as_wide() {
        let table = Plane::checked(Vector3::z(), 0.5, "table").unwrap();
        let clusters = vec![front(1.0, 0.0), front(1.0, 0.3)];
        // The grasp is at the first object: only the second is an obstacle.
        let boxes = obstacle_boxes(
            &clusters,
            Some(&table),
            &Point3::origin(),
            &Point3::new(0.98, 0.0, -0.4),
        );
        assert_eq!(boxes.len(), 1);
        let b = boxes[0];
        // From the table (z = −0.5) to the top (−0.3).
        let z = b.orientation * Vector3::z();
        assert!((z - Vector3::z()).norm() < 1e-9);
        assert!((b.centre.z + 0.4).abs() < 1e-9 && (b.half_extents.z - 0.1).abs() < 1e-9);
        // 8 cm wide along y; 2 cm of visible depth made 8 cm, away from the camera (+x).
        let (hx, hy) = (b.half_extents.x, b.half_extents.y);
        assert!(
            (hx.max(hy) - 0.04).abs() < 1e-9 && (hx.min(hy) - 0.04).abs() < 1e-9,
            "{hx} {hy}"
        );
        assert!(
            (b.centre.x - (0.98 + 0.04 - 0.0)).abs() < 0.011,
            "{}",
            b.centre
        );
        assert!((b.centre.y - 0.3).abs() < 1e-9);
        // A point behind the visible face, 5 cm further from the camera, is inside the box.
        assert!(b.distance(&Point3::new(1.03, 0.3, -0.4)).0 < 0.0);
    }
}
