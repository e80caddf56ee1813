//! The grasp postures a hand's posture synergies are fitted to (dissertation §7.3): graspd's own
//! plans for the hand, with its kinematics, over a fixed set of generated objects — spheres,
//! upright cylinders and boxes from 3 to 15 cm on a table — once per grasp type the hand
//! realises. The dissertation mapped recorded human grasps onto the Shadow hand; planning
//! instead works for any hand graspd can import. Each object is a whole surface with exact
//! outward normals (nothing to complete), and a feasible plan's touching joints are one posture
//! labelled with the type it realised. Deterministic for a seed.

use super::{KinematicModel, PlanHints, PlanInput, PlannerOptions, plan};
use crate::cloud::{Plane, PointCloud};
use crate::error::PlanError;
use crate::hand::posture_synergies::LabelledPosture;
use nalgebra::{Point3, Vector3};
use std::f64::consts::{PI, TAU};
use std::sync::Arc;

/// Spacing of the generated objects' surface points, m.
const SPACING: f64 = 0.005;

/// An object the postures are planned on, standing on the table z = 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Primitive {
    Sphere {
        radius: f64,
    },
    /// Upright, on one of its ends.
    Cylinder {
        radius: f64,
        height: f64,
    },
    /// Axis-aligned, on its x–y face.
    Box {
        size: [f64; 3],
    },
}

/// The objects, small to large: what asks a pinch or a precision grasp, and what a wrap.
pub const OBJECTS: [Primitive; 9] = [
    Primitive::Sphere { radius: 0.02 },
    Primitive::Sphere { radius: 0.035 },
    Primitive::Sphere { radius: 0.05 },
    Primitive::Cylinder {
        radius: 0.015,
        height: 0.12,
    },
    Primitive::Cylinder {
        radius: 0.035,
        height: 0.10,
    },
    Primitive::Cylinder {
        radius: 0.045,
        height: 0.15,
    },
    Primitive::Box {
        size: [0.04, 0.04, 0.04],
    },
    Primitive::Box {
        size: [0.03, 0.08, 0.15],
    },
    Primitive::Box {
        size: [0.11, 0.06, 0.04],
    },
];

impl Primitive {
    /// Surface points about every [`SPACING`] and their outward normals (the face on the table
    /// left out: nothing sees or touches it).
    pub fn surface(&self) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        let mut points = Vec::new();
        let mut normals = Vec::new();
        match *self {
            Primitive::Sphere { radius } => {
                let rings = ((PI * radius / SPACING).ceil() as usize).max(4);
                for i in 0..=rings {
                    let polar = PI * i as f64 / rings as f64;
                    let around = ((TAU * radius * polar.sin() / SPACING).ceil() as usize).max(1);
                    for k in 0..around {
                        let az = TAU * k as f64 / around as f64;
                        let n = Vector3::new(
                            polar.sin() * az.cos(),
                            polar.sin() * az.sin(),
                            polar.cos(),
                        );
                        points.push(Point3::new(0.0, 0.0, radius) + n * radius);
                        normals.push(n);
                    }
                }
            }
            Primitive::Cylinder { radius, height } => {
                let around = (TAU * radius / SPACING).ceil() as usize;
                let levels = (height / SPACING).ceil() as usize;
                for l in 0..=levels {
                    let z = height * l as f64 / levels as f64;
                    for k in 0..around {
                        let az = TAU * k as f64 / around as f64;
                        let n = Vector3::new(az.cos(), az.sin(), 0.0);
                        points.push(Point3::new(radius * n.x, radius * n.y, z));
                        normals.push(n);
                    }
                }
                let rings = (radius / SPACING).ceil() as usize;
                for i in 1..rings {
                    let r = radius * i as f64 / rings as f64;
                    let around = (TAU * r / SPACING).ceil() as usize;
                    for k in 0..around {
                        let az = TAU * k as f64 / around as f64;
                        points.push(Point3::new(r * az.cos(), r * az.sin(), height));
                        normals.push(Vector3::z());
                    }
                }
                points.push(Point3::new(0.0, 0.0, height));
                normals.push(Vector3::z());
            }
            Primitive::Box { size } => {
                let half = [size[0] / 2.0, size[1] / 2.0];
                // Five faces: ±x, ±y and the top; each a grid over its two other axes.
                let faces: [(usize, f64); 5] = [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0)];
                for (axis, sign) in faces {
                    let (u, v) = match axis {
                        0 => (1, 2),
                        1 => (0, 2),
                        _ => (0, 1),
                    };
                    let span = |k: usize| {
                        if k == 2 {
                            (0.0, size[2])
                        } else {
                            (-half[k], half[k])
                        }
                    };
                    let (u0, u1) = span(u);
                    let (v0, v1) = span(v);
                    let nu = ((u1 - u0) / SPACING).ceil() as usize;
                    let nv = ((v1 - v0) / SPACING).ceil() as usize;
                    for i in 0..=nu {
                        for j in 0..=nv {
                            let mut p = [0.0; 3];
                            p[u] = u0 + (u1 - u0) * i as f64 / nu as f64;
                            p[v] = v0 + (v1 - v0) * j as f64 / nv as f64;
                            p[axis] = if axis == 2 {
                                size[2]
                            } else {
                                sign * half[axis]
                            };
                            let mut n = Vector3::zeros();
                            n[axis] = sign;
                            points.push(Point3::from(p));
                            normals.push(n);
                        }
                    }
                }
            }
        }
        (points, normals)
    }
}

/// The postures: per object, per type the hand realises, the touching joints of a feasible
/// plan (seed `seed`). Returns the joint names (the model's order), the postures and the number
/// of plans made.
pub fn synergy_postures(
    model: &Arc<KinematicModel>,
    seed: u64,
) -> Result<(Vec<String>, Vec<LabelledPosture>, usize), PlanError> {
    let hand = model.describe()?;
    let names: Vec<String> = model
        .hand
        .tree
        .joints
        .iter()
        .map(|j| j.name.clone())
        .collect();
    let mut postures = Vec::new();
    let mut plans = 0;
    for object in OBJECTS {
        let (points, normals) = object.surface();
        for grasp_type in hand.realisable_types() {
            plans += 1;
            let p = plan(PlanInput {
                cloud: PointCloud {
                    points: points.clone(),
                    normals: Some(normals.clone()),
                },
                hand: hand.clone(),
                hints: PlanHints {
                    grasp_type: Some(grasp_type),
                    support_plane: Some(Plane {
                        normal: Vector3::z(),
                        offset: 0.0,
                    }),
                    viewpoint: Some(Point3::new(0.35, 0.0, 0.45)),
                    ..Default::default()
                },
                options: PlannerOptions {
                    seed,
                    complete_unseen: false,
                    ..Default::default()
                },
                kinematics: Some(model.clone()),
                grasp_quality: None,
            })?;
            tracing::debug!(
                ?object,
                ?grasp_type,
                feasible = p.feasible,
                reason = p.infeasible_reason.as_deref().unwrap_or(""),
                "synergy posture"
            );
            if !p.feasible || p.joints.is_empty() {
                continue;
            }
            postures.push(LabelledPosture {
                joints: p.joints.iter().map(|(_, v)| *v).collect(),
                grasp_type: p.grasp_type,
            });
        }
    }
    Ok((names, postures, plans))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitive_surfaces_lie_on_their_shapes_with_outward_normals() {
        for object in OBJECTS {
            let (points, normals) = object.surface();
            assert!(points.len() > 100, "{object:?}: {}", points.len());
            for (p, n) in points.iter().zip(&normals) {
                assert!((n.norm() - 1.0).abs() < 1e-12);
                assert!(p.z >= -1e-12, "{object:?} {p}");
                let (off, out) = match object {
                    Primitive::Sphere { radius } => {
                        let c = Point3::new(0.0, 0.0, radius);
                        ((p - c).norm() - radius, (p - c).dot(n))
                    }
                    Primitive::Cylinder { radius, height } => {
                        let r = (p.x * p.x + p.y * p.y).sqrt();
                        if n.z > 0.5 {
                            (p.z - height, 1.0)
                        } else {
                            (r - radius, p.x * n.x + p.y * n.y)
                        }
                    }
                    Primitive::Box { size } => {
                        let k = n.iamax();
                        let face = if k == 2 { size[2] } else { size[k] / 2.0 };
                        (
                            p[k].abs() - face,
                            p[k] * n[k] - if k == 2 { size[2] / 2.0 } else { 0.0 },
                        )
                    }
                };
                assert!(off.abs() < 1e-9, "{object:?}: {p} off its surface by {off}");
                assert!(out > 0.0, "{object:?}: normal {n} at {p} points inward");
            }
        }
    }
}
