//! The geometric rule that chooses the grasp type and the attention point from a point cloud alone
//! (no image, or no vision model). It stays the fallback of the perception pipeline.
//!
//! # Grasp type (Feix taxonomy, object dimensions)
//! With the principal extents d1 ≥ d2 ≥ d3 of the object cloud:
//!
//! | shape | condition | type | Feix |
//! |---|---|---|---|
//! | tiny | d1 ≤ 2.5 cm | pinch | palmar pinch |
//! | small | d1 ≤ 5 cm | tripod | tripod |
//! | flat (disc, plate) | d3 < 0.45·d2 | precision if d2 ≤ 12 cm, else pinch (rim) | precision disk / pinch |
//! | elongated | d1 ≥ 1.8·d2 | small_wrap if d2 < 3.5 cm, large_wrap if d2 ≤ 10 cm, else power | small / large diameter wrap |
//! | round | d1 ≤ 1.3·d3 | power | power sphere |
//! | compact | otherwise | large_wrap if d2 ≤ 10 cm, else precision | large diameter / precision |
//!
//! So a 7 cm cylinder 12 cm tall is a large wrap, a 2 cm handle a small wrap, a 3 cm cube a
//! tripod, an apple a power grasp, a tuna can a precision grasp. Single-view clouds see about half
//! of an object, so d2 and d3 can be under-estimated; the rule is deliberately coarse.
//!
//! # Attention point
//! The approach direction a is chosen first: from above (−up) for fingertip types (pinch, tripod,
//! precision) and for objects lower than 6 cm; otherwise from the side — horizontally from the
//! viewpoint when it is known, else across the object's longest horizontal axis. Without a known
//! up direction (no support plane, no `up` hint) the approach is from the viewpoint, and without a
//! viewpoint either, along −z of the input frame. p_att is the surface point the hand meets first
//! when it moves along a through the object's centre: among the points within 1.5 cm (widened if
//! needed) of the line through the centre along a, the one with the least (p − centre)·a.

use super::object_shape::ObjectShape;
use crate::grasp_type::GraspType;
use nalgebra::{Point3, Vector3};

/// The rule's choice of grasp type from the object's extents.
pub fn grasp_type_by_rule(shape: &ObjectShape) -> GraspType {
    let [d1, d2, d3] = shape.extents;
    if d1 <= 0.025 {
        GraspType::Pinch
    } else if d1 <= 0.05 {
        GraspType::Tripod
    } else if d3 < 0.45 * d2 {
        if d2 <= 0.12 {
            GraspType::Precision
        } else {
            GraspType::Pinch
        }
    } else if d1 >= 1.8 * d2 {
        if d2 < 0.035 {
            GraspType::SmallWrap
        } else if d2 <= 0.10 {
            GraspType::LargeWrap
        } else {
            GraspType::Power
        }
    } else if d1 <= 1.3 * d3 {
        GraspType::Power
    } else if d2 <= 0.10 {
        GraspType::LargeWrap
    } else {
        GraspType::Precision
    }
}

/// The approach direction of the rule (unit, pointing from the hand toward the object).
pub fn approach_by_rule(
    shape: &ObjectShape,
    grasp_type: GraspType,
    points: &[Point3<f64>],
    up: Option<&Vector3<f64>>,
    viewpoint: Option<&Point3<f64>>,
) -> Vector3<f64> {
    let from_view = viewpoint.and_then(|v| (shape.center - v).try_normalize(1e-9));
    let Some(up) = up else {
        return from_view.unwrap_or(-Vector3::z());
    };
    let height = points
        .iter()
        .map(|p| p.coords.dot(up))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    let height = height.1 - height.0;
    let fingertip = matches!(
        grasp_type,
        GraspType::Pinch | GraspType::Tripod | GraspType::Precision
    );
    if fingertip || height < 0.06 {
        return -up;
    }
    let horizontal = |v: Vector3<f64>| (v - up * v.dot(up)).try_normalize(1e-6);
    if let Some(h) = from_view.and_then(horizontal) {
        return h;
    }
    // Approach along the longest horizontal axis so the hand closes across the narrower side.
    shape
        .axes
        .iter()
        .filter_map(|a| horizontal(*a))
        .next()
        .unwrap_or(-up)
}

/// p_att: index of the first surface point met along `approach` through the object's centre.
pub fn attention_point_by_rule(
    shape: &ObjectShape,
    points: &[Point3<f64>],
    approach: &Vector3<f64>,
) -> usize {
    let c = shape.center;
    let mut radius = 0.015;
    loop {
        let best = points
            .iter()
            .enumerate()
            .filter(|(_, p)| {
                let d = *p - c;
                (d - approach * d.dot(approach)).norm() < radius
            })
            .min_by(|(_, a), (_, b)| (*a - c).dot(approach).total_cmp(&(*b - c).dot(approach)));
        if let Some((i, _)) = best {
            return i;
        }
        radius *= 2.0;
        if radius > 10.0 {
            // Cannot happen for a non-empty cloud; keep a defined answer.
            return 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on the surface of an axis-aligned box of the given size standing on z = 0.
    fn box_cloud(sx: f64, sy: f64, sz: f64) -> Vec<Point3<f64>> {
        let n = 12;
        let mut v = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                for k in 0..=n {
                    if [i, j, k].iter().any(|&q| q == 0 || q == n) {
                        let f = |q: usize, s: f64| s * q as f64 / n as f64;
                        v.push(Point3::new(
                            f(i, sx) - sx / 2.0,
                            f(j, sy) - sy / 2.0,
                            f(k, sz),
                        ));
                    }
                }
            }
        }
        v
    }

    /// Points on a closed cylinder of diameter d and height h standing on z = 0.
    fn cylinder(d: f64, h: f64) -> Vec<Point3<f64>> {
        let mut v = Vec::new();
        for i in 0..48 {
            let th = 2.0 * std::f64::consts::PI * i as f64 / 48.0;
            for k in 0..=20 {
                v.push(Point3::new(
                    d / 2.0 * th.cos(),
                    d / 2.0 * th.sin(),
                    h * k as f64 / 20.0,
                ));
            }
            for r in 1..6 {
                let rr = d / 2.0 * r as f64 / 6.0;
                v.push(Point3::new(rr * th.cos(), rr * th.sin(), 0.0));
                v.push(Point3::new(rr * th.cos(), rr * th.sin(), h));
            }
        }
        v
    }

    fn rule(pts: &[Point3<f64>]) -> GraspType {
        grasp_type_by_rule(&ObjectShape::of(pts))
    }

    #[test]
    fn the_documented_examples() {
        assert_eq!(rule(&cylinder(0.07, 0.12)), GraspType::LargeWrap);
        assert_eq!(rule(&cylinder(0.02, 0.15)), GraspType::SmallWrap);
        assert_eq!(rule(&box_cloud(0.03, 0.03, 0.03)), GraspType::Tripod);
        assert_eq!(rule(&box_cloud(0.02, 0.015, 0.01)), GraspType::Pinch);
        assert_eq!(rule(&cylinder(0.085, 0.033)), GraspType::Precision);
        assert_eq!(rule(&cylinder(0.075, 0.072)), GraspType::Power);
        assert_eq!(rule(&box_cloud(0.2, 0.2, 0.01)), GraspType::Pinch);
    }

    #[test]
    fn attention_point_faces_the_approach() {
        let pts = cylinder(0.07, 0.12);
        let shape = ObjectShape::of(&pts);
        let up = Vector3::z();
        let view = Point3::new(0.5, 0.0, 0.4);
        let a = approach_by_rule(&shape, GraspType::LargeWrap, &pts, Some(&up), Some(&view));
        assert!(
            a.z.abs() < 1e-9 && a.x < -0.99,
            "side approach from the viewpoint: {a:?}"
        );
        let i = attention_point_by_rule(&shape, &pts, &a);
        assert!(
            pts[i].x > 0.03,
            "on the side facing the camera: {:?}",
            pts[i]
        );
        let top = approach_by_rule(&shape, GraspType::Tripod, &pts, Some(&up), Some(&view));
        assert!((top + up).norm() < 1e-12);
        let j = attention_point_by_rule(&shape, &pts, &top);
        assert!((pts[j].z - 0.12).abs() < 1e-9);
    }
}
