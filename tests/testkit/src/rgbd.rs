//! RGB-D frames of YCB objects on a table, made by ray casting: one ray per pixel of a pinhole
//! camera in the convention of ROS `CameraInfo` (pixel centres at integer (u, v), the ray of
//! (u, v) along `((u − cx)/fx, (v − cy)/fy, 1)` in the optical frame x right, y down,
//! z forward), depth along the optical axis, a flat colour per object (or its scanned texture,
//! [`SceneObject::scanned`]) shaded by the angle to the camera, and a ground-truth label per
//! pixel.
//!
//! ```no_run
//! use graspd_testkit::rgbd::{RgbdScene, SceneObject};
//! use graspd_testkit::Object;
//! let scene = RgbdScene::on_table(vec![SceneObject::new(Object::TomatoSoupCan, 0.0, 0.0, [200, 30, 30])]);
//! let frame = scene.render().unwrap();
//! assert_eq!(frame.depth.len(), 640 * 480);
//! ```

use crate::render::{Camera, Intrinsics, gaussian};
use crate::texture::{ObjectTexture, texture};
use crate::ycb::{Object, mesh, mesh_aabb};
use crate::{Result, TriMesh};
use image::{ExtendedColorType, ImageEncoder, codecs::png::PngEncoder};
use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use parry3d_f64::math::Vector;
use parry3d_f64::query::{PointQuery, Ray, RayCast};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::Arc;

/// An object on the table: its mesh is shifted so that its bounding-box centre is above
/// (`x`, `y`); it keeps standing on z = 0.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneObject {
    pub object: Object,
    pub x: f64,
    pub y: f64,
    pub color: [u8; 3],
    /// Show the scan's texture map instead of `color` (where the object has one).
    pub scanned: bool,
}

impl SceneObject {
    pub fn new(object: Object, x: f64, y: f64, color: [u8; 3]) -> Self {
        Self {
            object,
            x,
            y,
            color,
            scanned: false,
        }
    }

    /// The object with its scanned texture (the chips can, which has none, in grey).
    pub fn scanned(object: Object, x: f64, y: f64) -> Self {
        Self {
            scanned: true,
            ..Self::new(object, x, y, [150, 150, 150])
        }
    }
}

/// A table scene and the camera that looks at it.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbdScene {
    pub objects: Vec<SceneObject>,
    /// The table: a square of this half side at z = 0 centred on the origin.
    pub table_half_extent: f64,
    pub table_color: [u8; 3],
    /// What rays that hit nothing see (their depth is 0: no reading).
    pub background_color: [u8; 3],
    /// Position, target and up of the camera (its intrinsics must be a full frame).
    pub camera: Camera,
    /// Gaussian noise on the depth, m.
    pub depth_noise_sigma: f64,
    /// Share of pixels whose depth is dropped (0: no reading), as structured-light sensors do.
    pub dropout: f64,
    pub seed: u64,
}

impl RgbdScene {
    /// `objects` on a 1.2 m square grey table, seen by a 640 × 480 camera 0.7 m from the
    /// origin, 45° above the table, from the −x side; 1 mm depth noise, 1 % dropouts.
    pub fn on_table(objects: Vec<SceneObject>) -> Self {
        let mut camera = Camera::orbit(Point3::new(0.0, 0.0, 0.04), 0.7, 45.0, 180.0);
        camera.intrinsics = Intrinsics {
            cx: 319.5,
            cy: 239.5,
            ..Intrinsics::VGA
        };
        Self {
            objects,
            table_half_extent: 0.6,
            table_color: [150, 150, 140],
            background_color: [40, 40, 50],
            camera,
            depth_noise_sigma: 0.001,
            dropout: 0.01,
            seed: 7,
        }
    }

    /// Renders the scene.
    pub fn render(&self) -> Result<RgbdRender> {
        let meshes: Vec<Arc<TriMesh>> = self
            .objects
            .iter()
            .map(|o| mesh(o.object))
            .collect::<Result<_>>()?;
        let textures: Vec<Option<Arc<ObjectTexture>>> = self
            .objects
            .iter()
            .map(|o| {
                if o.scanned {
                    texture(o.object)
                } else {
                    Ok(None)
                }
            })
            .collect::<Result<_>>()?;
        let offsets: Vec<Vector3<f64>> = self
            .objects
            .iter()
            .zip(&meshes)
            .map(|(o, m)| {
                let (lo, hi) = mesh_aabb(m);
                let c = nalgebra::center(&lo, &hi);
                Vector3::new(o.x - c.x, o.y - c.y, 0.0)
            })
            .collect();
        let k = self.camera.intrinsics;
        let (r, d, f) = self.camera.axes();
        let rot = Matrix3::from_columns(&[r, d, f]);
        let camera_to_world = Isometry3::from_parts(
            Translation3::from(self.camera.position.coords),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rot)),
        );
        let o = self.camera.position;
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let n = k.width * k.height;
        let mut rgb = Vec::with_capacity(3 * n);
        let mut depth = Vec::with_capacity(n);
        let mut labels = Vec::with_capacity(n);
        for v in 0..k.height {
            for u in 0..k.width {
                let ray_cam = Vector3::new((u as f64 - k.cx) / k.fx, (v as f64 - k.cy) / k.fy, 1.0);
                let len = ray_cam.norm();
                let dir = rot * ray_cam / len;
                // (range, normal, label, triangle): label 0 = table, k + 1 = object k.
                let mut best: Option<(f64, Vector3<f64>, i32, u32)> = None;
                for (j, (m, off)) in meshes.iter().zip(&offsets).enumerate() {
                    let local = o - off;
                    let ray = Ray::new(
                        Vector::new(local.x, local.y, local.z),
                        Vector::new(dir.x, dir.y, dir.z),
                    );
                    if let Some(hit) = m.cast_local_ray_and_get_normal(&ray, 10.0, false)
                        && best.is_none_or(|(t, _, _, _)| hit.time_of_impact < t)
                    {
                        let nn = Vector3::new(hit.normal.x, hit.normal.y, hit.normal.z);
                        best = Some((hit.time_of_impact, nn, j as i32 + 1, hit.subshape));
                    }
                }
                if dir.z < -1e-12 && o.z > 0.0 {
                    let t = -o.z / dir.z;
                    let p = o + dir * t;
                    let h = self.table_half_extent;
                    if p.x.abs() <= h && p.y.abs() <= h && best.is_none_or(|(tb, _, _, _)| t < tb) {
                        best = Some((t, Vector3::z(), 0, 0));
                    }
                }
                let noise = if self.depth_noise_sigma > 0.0 {
                    self.depth_noise_sigma * gaussian(&mut rng)
                } else {
                    0.0
                };
                let drop = self.dropout > 0.0 && rng.random::<f64>() < self.dropout;
                match best {
                    Some((t, nn, label, triangle)) => {
                        let k = label as usize;
                        let base = if label == 0 {
                            self.table_color.map(f64::from)
                        } else {
                            let scan = textures[k - 1].as_ref().and_then(|tex| {
                                // The hit in the mesh's own frame.
                                let p = o - offsets[k - 1] + dir * t;
                                tex.colour(self.objects[k - 1].object, triangle, &p)
                            });
                            scan.unwrap_or(self.objects[k - 1].color.map(f64::from))
                        };
                        let shade = 0.55 + 0.45 * nn.dot(&dir).abs();
                        rgb.extend(base.iter().map(|&c| (c * shade).round().min(255.0) as u8));
                        let z = t / len + noise;
                        depth.push(if drop { 0.0 } else { z as f32 });
                        labels.push(label);
                    }
                    None => {
                        rgb.extend_from_slice(&self.background_color);
                        depth.push(0.0);
                        labels.push(-1);
                    }
                }
            }
        }
        Ok(RgbdRender {
            width: k.width,
            height: k.height,
            rgb,
            depth,
            labels,
            intrinsics: k,
            camera_to_world,
            meshes,
            offsets,
        })
    }
}

/// A rendered frame with its ground truth.
#[derive(Debug, Clone)]
pub struct RgbdRender {
    pub width: usize,
    pub height: usize,
    /// R, G, B per pixel, row-major.
    pub rgb: Vec<u8>,
    /// Depth along the optical axis, m; 0 where there is no reading.
    pub depth: Vec<f32>,
    /// What each pixel sees: −1 nothing, 0 the table, k + 1 object k of the scene.
    pub labels: Vec<i32>,
    pub intrinsics: Intrinsics,
    pub camera_to_world: Isometry3<f64>,
    meshes: Vec<Arc<TriMesh>>,
    offsets: Vec<Vector3<f64>>,
}

impl RgbdRender {
    /// Ground-truth mask of object `k` (every pixel that sees it, with or without depth).
    pub fn object_mask(&self, k: usize) -> Vec<bool> {
        self.labels.iter().map(|&l| l == k as i32 + 1).collect()
    }

    /// Distance from a world point to the surface of object `k`, m.
    pub fn distance_to_object(&self, k: usize, p: &Point3<f64>) -> f64 {
        let q = p - self.offsets[k];
        self.meshes[k]
            .distance_to_local_point(Vector::new(q.x, q.y, q.z), false)
            .abs()
    }

    /// Pixel (u, v) nearest the centroid of object `k`'s ground-truth mask.
    pub fn object_pixel(&self, k: usize) -> (u32, u32) {
        let (mut su, mut sv, mut n) = (0.0, 0.0, 0.0);
        for (i, _) in self
            .labels
            .iter()
            .enumerate()
            .filter(|(_, l)| **l == k as i32 + 1)
        {
            su += (i % self.width) as f64;
            sv += (i / self.width) as f64;
            n += 1.0;
        }
        ((su / n).round() as u32, (sv / n).round() as u32)
    }

    /// The depth as `16UC1` bytes (little-endian millimetres, 0 = no reading).
    pub fn depth_mm_le(&self) -> Vec<u8> {
        self.depth_mm()
            .iter()
            .flat_map(|d| d.to_le_bytes())
            .collect()
    }

    /// The depth in whole millimetres (0 = no reading).
    pub fn depth_mm(&self) -> Vec<u16> {
        self.depth
            .iter()
            .map(|&d| (d as f64 * 1000.0).round().clamp(0.0, 65535.0) as u16)
            .collect()
    }

    /// The colour as an 8-bit RGB PNG file.
    pub fn color_png(&self) -> Vec<u8> {
        png(&self.rgb, self.width, self.height, ExtendedColorType::Rgb8)
    }

    /// The depth as a 16-bit grey PNG file in millimetres (0 = no reading).
    pub fn depth_png(&self) -> Vec<u8> {
        // PNG stores 16-bit samples big-endian; the encoder takes them in native order.
        let bytes: Vec<u8> = self
            .depth_mm()
            .iter()
            .flat_map(|d| d.to_ne_bytes())
            .collect();
        png(&bytes, self.width, self.height, ExtendedColorType::L16)
    }

    /// The depth as `32FC1` bytes (little-endian metres).
    pub fn depth_f32_le(&self) -> Vec<u8> {
        self.depth.iter().flat_map(|d| d.to_le_bytes()).collect()
    }
}

fn png(data: &[u8], w: usize, h: usize, ty: ExtendedColorType) -> Vec<u8> {
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(data, w as u32, h as u32, ty)
        .expect("PNG encoding into memory");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_back_projects_onto_the_mesh_and_labels_are_right() {
        let mut scene = RgbdScene::on_table(vec![SceneObject::new(
            Object::TomatoSoupCan,
            0.0,
            0.0,
            [200, 30, 30],
        )]);
        scene.depth_noise_sigma = 0.0;
        scene.dropout = 0.0;
        let f = scene.render().unwrap();
        let k = f.intrinsics;
        let mut on_object = 0;
        for (i, (&z, &l)) in f.depth.iter().zip(&f.labels).enumerate() {
            let (u, v) = ((i % f.width) as f64, (i / f.width) as f64);
            let pc = Point3::new(
                (u - k.cx) * z as f64 / k.fx,
                (v - k.cy) * z as f64 / k.fy,
                z as f64,
            );
            let p = f.camera_to_world * pc;
            match l {
                1 => {
                    on_object += 1;
                    assert!(f.distance_to_object(0, &p) < 1e-5, "{p}");
                }
                0 => assert!(p.z.abs() < 1e-5, "{p}"),
                _ => assert_eq!(z, 0.0),
            }
        }
        // A 7 × 10 cm can 0.7 m away covers a few thousand pixels.
        assert!(on_object > 3000, "{on_object}");
        let (u, v) = f.object_pixel(0);
        assert_eq!(f.labels[v as usize * f.width + u as usize], 1);
        // Red on the can, grey on the table.
        let i = 3 * (v as usize * f.width + u as usize);
        assert!(f.rgb[i] > 2 * f.rgb[i + 1]);
    }
}
