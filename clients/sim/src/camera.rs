//! A virtual RGB-D camera without a GPU: one MuJoCo ray per pixel (`mj_multiRay`) gives the
//! depth and the geom hit; colour is the geom's colour under a headlight (Lambert).
//!
//! Camera frame as OpenCV and graspd's RgbdFrame: +x right, +y down, +z forward (optical axis).
//! Default intrinsics: 640×480, fx = fy = 525, cx = 319.5, cy = 239.5 (a Kinect-class sensor,
//! 62.8° horizontal field of view).

use crate::scene::Scene;
use mujoco_rs::prelude::*;
use nalgebra::{Isometry3, Point3, Rotation3, UnitQuaternion, Vector3};

/// Pinhole intrinsics.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Intrinsics {
    pub width: u32,
    pub height: u32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

impl Intrinsics {
    /// The default sensor at `width`×`height` (fx scaled with the width).
    pub fn kinect(width: u32, height: u32) -> Self {
        let f = 525.0 * width as f64 / 640.0;
        Intrinsics {
            width,
            height,
            fx: f,
            fy: f,
            cx: (width as f64 - 1.0) / 2.0,
            cy: (height as f64 - 1.0) / 2.0,
        }
    }
}

/// A rendered frame: row-major rgb8 and depth in metres along the optical axis (0 = no return).
#[derive(Debug, Clone)]
pub struct RgbdImage {
    pub intrinsics: Intrinsics,
    pub rgb: Vec<u8>,
    pub depth: Vec<f32>,
    /// Camera pose in the world.
    pub camera_to_world: Isometry3<f64>,
    /// Geom hit per pixel (None: background).
    pub geoms: Vec<Option<usize>>,
}

/// A camera at `eye` looking at `target`, with the image's up roughly along world +z.
pub fn look_at(eye: Point3<f64>, target: Point3<f64>) -> Isometry3<f64> {
    let z = (target - eye).normalize();
    let mut x = z.cross(&Vector3::z());
    if x.norm() < 1e-6 {
        x = Vector3::x();
    }
    let x = x.normalize();
    let y = z.cross(&x);
    let r = Rotation3::from_basis_unchecked(&[x, y, z]);
    Isometry3::from_parts(eye.coords.into(), UnitQuaternion::from_rotation_matrix(&r))
}

/// The benchmark's view: 0.55 m from the table centre, 50° above the table, looking at a point
/// 5 cm above it, from the -x side.
pub fn default_view() -> Isometry3<f64> {
    let elev = 50f64.to_radians();
    let d = 0.55;
    let target = Point3::new(0.0, 0.0, 0.05);
    look_at(
        target + Vector3::new(-d * elev.cos(), 0.0, d * elev.sin()),
        target,
    )
}

/// `n` views of the benchmark's scene: `first`, and the same camera turned about the vertical
/// through the point the default view looks at by 360°/n each — a robot's wrist camera moved
/// around the table, or a cell with n cameras.
pub fn views_around(first: &Isometry3<f64>, n: usize) -> Vec<Isometry3<f64>> {
    let target = Vector3::new(0.0, 0.0, 0.05);
    (0..n.max(1))
        .map(|k| {
            let turn = UnitQuaternion::from_axis_angle(
                &Vector3::z_axis(),
                std::f64::consts::TAU * k as f64 / n.max(1) as f64,
            );
            let about = Isometry3::from_parts(target.into(), turn)
                * Isometry3::translation(-target.x, -target.y, -target.z);
            about * first
        })
        .collect()
}

/// Renders the scene's current state (call `forward` first). Geoms of groups ≥ 3 (the hand
/// models' collision geoms) are left out, so the visual meshes are what is seen.
pub fn render(
    scene: &Scene,
    data: &mut MjData<&MjModel>,
    intr: Intrinsics,
    camera_to_world: Isometry3<f64>,
) -> RgbdImage {
    let (w, h) = (intr.width as usize, intr.height as usize);
    let rot = camera_to_world.rotation;
    let mut dirs = Vec::with_capacity(w * h);
    let mut zscale = Vec::with_capacity(w * h);
    for v in 0..h {
        for u in 0..w {
            let c = Vector3::new(
                (u as f64 - intr.cx) / intr.fx,
                (v as f64 - intr.cy) / intr.fy,
                1.0,
            );
            let n = c.norm();
            let d = rot * (c / n);
            dirs.push([d.x, d.y, d.z]);
            zscale.push(1.0 / n);
        }
    }
    let eye = camera_to_world.translation.vector;
    let groups: [u8; 6] = [1, 1, 1, 0, 0, 0];
    let mut normals = vec![[0.0; 3]; w * h];
    let (geoms, dist) = data.multi_ray(
        &[eye.x, eye.y, eye.z],
        &dirs,
        Some(&groups),
        true,
        None,
        10.0,
        Some(&mut normals),
    );
    let rgba = scene.model.geom_rgba();
    let mut rgb = vec![0u8; w * h * 3];
    let mut depth = vec![0f32; w * h];
    for i in 0..w * h {
        let Some(g) = geoms[i] else {
            // Background: a dim grey wall.
            rgb[3 * i..3 * i + 3].copy_from_slice(&[40, 40, 44]);
            continue;
        };
        depth[i] = (dist[i] * zscale[i]) as f32;
        let n = Vector3::from(normals[i]);
        let d = Vector3::from(dirs[i]);
        // Headlight plus a light from above.
        let shade = 0.25 + 0.45 * (-n.dot(&d)).max(0.0) + 0.3 * n.z.max(0.0);
        for k in 0..3 {
            rgb[3 * i + k] = (rgba[g][k] as f64 * shade * 255.0).clamp(0.0, 255.0) as u8;
        }
    }
    RgbdImage {
        intrinsics: intr,
        rgb,
        depth,
        camera_to_world,
        geoms,
    }
}

impl RgbdImage {
    /// The object's points (pixels whose ray hit one of `geoms`) in the world, for plans from a
    /// cloud instead of the image.
    pub fn points_of(&self, is_object: impl Fn(usize) -> bool) -> Vec<Point3<f64>> {
        let intr = self.intrinsics;
        let mut out = Vec::new();
        for (i, g) in self.geoms.iter().enumerate() {
            if g.is_some_and(&is_object) && self.depth[i] > 0.0 {
                let (u, v) = (
                    (i % intr.width as usize) as f64,
                    (i / intr.width as usize) as f64,
                );
                let z = self.depth[i] as f64;
                let c = Point3::new((u - intr.cx) / intr.fx * z, (v - intr.cy) / intr.fy * z, z);
                out.push(self.camera_to_world * c);
            }
        }
        out
    }
}

/// Writes the colour image as PNG.
pub fn save_png(img: &RgbdImage, path: &std::path::Path) -> Result<(), crate::SimError> {
    image::save_buffer(
        path,
        &img.rgb,
        img.intrinsics.width,
        img.intrinsics.height,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| crate::SimError::Input(format!("{}: {e}", path.display())))
}
