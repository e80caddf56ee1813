//! Random tabletop scenes and their ray-cast RGB-D frames with per-pixel grasp-type labels.
//!
//! A scene is 1–5 objects on a table: YCB meshes from the shared test data and procedural
//! primitives (standing and lying cylinders, boxes, thin plates, spheres, small items, thin
//! rods, and bodies with a handle), each with a random pose, size, two colours and a texture (plain, stripes, checker,
//! blotches). One directional light with ambient, diffuse and specular terms, a random table
//! colour and texture, a random background, a camera 0.35–0.85 m from the objects' centroid at 25–80° elevation and any
//! azimuth, f = 500–620 px. Depth gets Gaussian noise and dropouts like a structured-light
//! sensor. Every object pixel is labelled by [`crate::labels`].

use crate::labels::{PartDims, PartLabels, part_labels};
use graspd_core::perception::{CameraIntrinsics, DecodedFrame};
use graspd_testkit::texture::ObjectTexture;
use graspd_testkit::{Camera, Object, mesh};
use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use parry3d_f64::math::Vector;
use parry3d_f64::query::Ray;
use parry3d_f64::shape::{Ball, Cuboid, Cylinder, Shape};
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{FRAC_PI_2, TAU};
use std::sync::Arc;

/// How a surface is coloured between its two colours.
#[derive(Debug, Clone, Copy)]
pub enum Texture {
    Plain,
    /// Bands along a local axis, `period` m.
    Stripes {
        axis: Vector3<f64>,
        period: f64,
    },
    Checker {
        size: f64,
    },
    /// Value noise on a grid of `size` m.
    Blotches {
        size: f64,
    },
}

impl Texture {
    fn random(rng: &mut ChaCha8Rng) -> Self {
        match rng.random_range(0..4) {
            0 => Texture::Plain,
            1 => Texture::Stripes {
                axis: random_unit(rng),
                period: rng.random_range(0.005..0.06),
            },
            2 => Texture::Checker {
                size: rng.random_range(0.005..0.04),
            },
            _ => Texture::Blotches {
                size: rng.random_range(0.004..0.03),
            },
        }
    }

    /// Weight of the second colour at local point `p`, 0…1.
    fn weight(&self, p: &Point3<f64>) -> f64 {
        match *self {
            Texture::Plain => 0.0,
            Texture::Stripes { axis, period } => {
                if (p.coords.dot(&axis) / period).rem_euclid(1.0) < 0.5 {
                    0.0
                } else {
                    1.0
                }
            }
            Texture::Checker { size } => {
                let s = (p.x / size).floor() + (p.y / size).floor() + (p.z / size).floor();
                (s as i64).rem_euclid(2) as f64
            }
            Texture::Blotches { size } => {
                let c = p.coords / size;
                hash3(c.x.floor() as i64, c.y.floor() as i64, c.z.floor() as i64)
            }
        }
    }
}

/// A hash of a grid cell to [0, 1).
fn hash3(i: i64, j: i64, k: i64) -> f64 {
    let mut h = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (k as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^= h >> 31;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 29;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

fn random_unit(rng: &mut ChaCha8Rng) -> Vector3<f64> {
    loop {
        let v = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let n = v.norm();
        if n > 0.1 && n <= 1.0 {
            return v / n;
        }
    }
}

fn random_color(rng: &mut ChaCha8Rng) -> [f64; 3] {
    [
        rng.random_range(15.0..250.0),
        rng.random_range(15.0..250.0),
        rng.random_range(15.0..250.0),
    ]
}

/// How a part's surface is coloured.
#[derive(Clone)]
pub enum Appearance {
    /// Between two colours by a procedural texture.
    Painted {
        colors: [[f64; 3]; 2],
        texture: Texture,
    },
    /// The YCB scan's own texture map (the part's shape is the object's mesh), each channel
    /// times `gain` (a sensor's white balance).
    Scanned {
        object: Object,
        texture: Arc<ObjectTexture>,
        gain: [f64; 3],
    },
}

impl Appearance {
    /// Two random colours and a random texture.
    pub fn random_paint(rng: &mut ChaCha8Rng) -> Self {
        Appearance::Painted {
            colors: [random_color(rng), random_color(rng)],
            texture: Texture::random(rng),
        }
    }
}

/// One rigid part of an object.
struct Part {
    shape: Arc<dyn Shape>,
    /// Local → world.
    pose: Isometry3<f64>,
    inverse: Isometry3<f64>,
    /// World bounding sphere, for a cheap rejection per ray.
    center: Point3<f64>,
    radius: f64,
    appearance: Appearance,
    labels: PartLabels,
    /// The scene object it belongs to (1-based, as in [`Frame::objects`]).
    object: u8,
}

impl Part {
    fn new(
        shape: Arc<dyn Shape>,
        pose: Isometry3<f64>,
        dims: PartDims,
        appearance: Appearance,
        object: u8,
    ) -> Self {
        let bs = shape.compute_local_bounding_sphere();
        let c = bs.center();
        Self {
            center: pose * Point3::new(c.x, c.y, c.z),
            radius: bs.radius(),
            inverse: pose.inverse(),
            labels: part_labels(&dims),
            shape,
            pose,
            appearance,
            object,
        }
    }

    /// The colour (0…255, before shading) at world point `p` on triangle `triangle`.
    fn colour(&self, p: &Point3<f64>, triangle: u32) -> [f64; 3] {
        let local = self.inverse * p;
        match &self.appearance {
            Appearance::Painted { colors, texture } => {
                let w = texture.weight(&local);
                [0, 1, 2].map(|c| colors[0][c] * (1.0 - w) + colors[1][c] * w)
            }
            Appearance::Scanned {
                object,
                texture,
                gain,
            } => {
                let t = texture
                    .colour(*object, triangle, &local)
                    .unwrap_or([128.0; 3]);
                [0, 1, 2].map(|c| t[c] * gain[c])
            }
        }
    }

    /// Distance along the world ray, the world normal and the triangle (of a mesh) of the
    /// first hit.
    fn cast(
        &self,
        o: &Point3<f64>,
        dir: &Vector3<f64>,
        max: f64,
    ) -> Option<(f64, Vector3<f64>, u32)> {
        // Ray–sphere rejection.
        let oc = self.center - o;
        let along = oc.dot(dir);
        if oc.norm_squared() - along * along > self.radius * self.radius {
            return None;
        }
        let lo = self.inverse * o;
        let ld = self.inverse.rotation * dir;
        let ray = Ray::new(Vector::new(lo.x, lo.y, lo.z), Vector::new(ld.x, ld.y, ld.z));
        let hit = self.shape.cast_local_ray_and_get_normal(&ray, max, true)?;
        let n = self.pose.rotation * Vector3::new(hit.normal.x, hit.normal.y, hit.normal.z);
        Some((hit.time_of_impact, n, hit.subshape))
    }
}

/// A random scene.
pub struct Scene {
    parts: Vec<Part>,
    /// What each scene object is (index k − 1 for object k of [`Frame::objects`]): a YCB
    /// object, or `None` for a procedural one.
    pub identities: Vec<Option<Object>>,
    table_half_extent: f64,
    table_colors: [[f64; 3]; 2],
    table_texture: Texture,
    background: [f64; 3],
    light: Vector3<f64>,
    ambient: f64,
    diffuse: f64,
    specular: f64,
    shininess: i32,
    pub camera: Camera,
    depth_noise_sigma: f64,
    dropout: f64,
    noise_seed: u64,
}

/// The pose of a part standing at (x, y) turned by `yaw`, its local frame lifted by `z`.
fn placed(x: f64, y: f64, z: f64, yaw: f64, tilt: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw) * tilt,
    )
}

impl Scene {
    /// Draws a scene from `seed` (the same seed gives the same scene): the grasp-type data's
    /// 1–5 objects, each part painted at random.
    pub fn random(seed: u64) -> graspd_testkit::Result<Self> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let count = rng.random_range(1..=5usize);
        Self::assemble(
            rng,
            count,
            |rng| Ok((random_object(rng)?, None)),
            |rng, _| Appearance::random_paint(rng),
        )
    }

    /// Places `count` objects drawn by `draw` (its parts and its identity) without overlap
    /// within ±18 cm, paints each part with `paint`, and draws the table, the light and the
    /// camera (module docs).
    pub(crate) fn assemble(
        mut rng: ChaCha8Rng,
        count: usize,
        mut draw: impl FnMut(&mut ChaCha8Rng) -> graspd_testkit::Result<(ObjectParts, Option<Object>)>,
        mut paint: impl FnMut(&mut ChaCha8Rng, Option<Object>) -> Appearance,
    ) -> graspd_testkit::Result<Self> {
        let mut parts = Vec::new();
        let mut identities = Vec::new();
        // Footprint circles (x, y, r) of the objects placed so far.
        let mut placed_at: Vec<(f64, f64, f64)> = Vec::new();
        for _ in 0..count {
            let (object, identity) = draw(&mut rng)?;
            let r = object.footprint;
            let spot = (0..60).find_map(|_| {
                let (x, y) = (rng.random_range(-0.18..0.18), rng.random_range(-0.18..0.18));
                placed_at
                    .iter()
                    .all(|&(px, py, pr)| {
                        ((x - px).powi(2) + (y - py).powi(2)).sqrt() > r + pr + 0.01
                    })
                    .then_some((x, y))
            });
            let Some((x, y)) = spot else { continue };
            placed_at.push((x, y, r));
            identities.push(identity);
            let id = identities.len() as u8;
            let yaw = rng.random_range(0.0..TAU);
            let base = placed(x, y, 0.0, yaw, UnitQuaternion::identity());
            for (shape, local, dims) in object.parts {
                let appearance = paint(&mut rng, identity);
                parts.push(Part::new(shape, base * local, dims, appearance, id));
            }
        }
        // Look at the objects' centroid (or the table centre when none fits).
        let n = placed_at.len().max(1) as f64;
        let (cx, cy) = placed_at
            .iter()
            .fold((0.0, 0.0), |(x, y), p| (x + p.0 / n, y + p.1 / n));
        let target = Point3::new(
            cx + rng.random_range(-0.05..0.05),
            cy + rng.random_range(-0.05..0.05),
            rng.random_range(0.0..0.08),
        );
        let mut camera = Camera::orbit(
            target,
            rng.random_range(0.35..0.85),
            rng.random_range(25.0..80.0),
            rng.random_range(0.0..360.0),
        );
        let f = rng.random_range(500.0..620.0);
        camera.intrinsics.fx = f;
        camera.intrinsics.fy = f * rng.random_range(0.99..1.01);
        camera.intrinsics.cx = 319.5 + rng.random_range(-6.0..6.0);
        camera.intrinsics.cy = 239.5 + rng.random_range(-6.0..6.0);
        let light = {
            let az = rng.random_range(0.0..TAU);
            let el = rng.random_range(0.3..FRAC_PI_2);
            Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
        };
        Ok(Self {
            parts,
            identities,
            table_half_extent: rng.random_range(0.3..0.8),
            table_colors: [random_color(&mut rng), random_color(&mut rng)],
            table_texture: Texture::random(&mut rng),
            background: random_color(&mut rng).map(|c| c * 0.5),
            light,
            ambient: rng.random_range(0.25..0.55),
            diffuse: rng.random_range(0.35..0.75),
            specular: rng.random_range(0.0..0.35),
            shininess: rng.random_range(4..40),
            camera,
            depth_noise_sigma: rng.random_range(0.0005..0.003),
            dropout: rng.random_range(0.0..0.03),
            noise_seed: rng.next_u64(),
        })
    }

    /// A uniform draw in [0, 1) for pixel `i`, stream `k`: a hash rather than an RNG so that a
    /// pixel's noise does not depend on which other pixels were cast.
    fn uniform(&self, i: usize, k: u64, n: u64) -> f64 {
        hash3(self.noise_seed as i64, i as i64, (4 * k + n) as i64)
    }

    /// A standard normal draw for pixel `i`, stream `k` (Box–Muller).
    fn noise(&self, i: usize, k: u64) -> f64 {
        let u1 = 1.0 - self.uniform(i, k, 1);
        let u2 = self.uniform(i, k, 2);
        (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
    }

    /// Ray-casts the frame at the camera's full size. Only rows and columns with `need_row[v]`
    /// and `need_col[u]` are cast (the others stay black with depth 0 and label 0): a model that
    /// reads a downsampled frame only ever sees those.
    pub fn render(&self, need_row: &[bool], need_col: &[bool]) -> Frame {
        let k = self.camera.intrinsics;
        let (r, d, f) = self.camera.axes();
        let rot = Matrix3::from_columns(&[r, d, f]);
        let o = self.camera.position;
        let n = k.width * k.height;
        let mut frame = Frame {
            width: k.width,
            height: k.height,
            rgb: vec![0; 3 * n],
            depth: vec![0.0; n],
            labels: vec![0; n],
            objects: vec![0; n],
            camera_to_world: Isometry3::from_parts(
                Translation3::from(o.coords),
                UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rot)),
            ),
        };
        for v in (0..k.height).filter(|&v| need_row[v]) {
            for u in (0..k.width).filter(|&u| need_col[u]) {
                let i = v * k.width + u;
                let ray_cam = Vector3::new((u as f64 - k.cx) / k.fx, (v as f64 - k.cy) / k.fy, 1.0);
                let len = ray_cam.norm();
                let dir = rot * ray_cam / len;
                // (range, normal, part + 1 or 0 for the table, triangle)
                let mut best: Option<(f64, Vector3<f64>, usize, u32)> = None;
                for (j, p) in self.parts.iter().enumerate() {
                    let max = best.map_or(10.0, |b| b.0);
                    if let Some((t, nn, tri)) = p.cast(&o, &dir, max)
                        && best.is_none_or(|b| t < b.0)
                    {
                        best = Some((t, nn, j + 1, tri));
                    }
                }
                if dir.z < -1e-12 {
                    let t = -o.z / dir.z;
                    let p = o + dir * t;
                    let h = self.table_half_extent;
                    if p.x.abs() <= h && p.y.abs() <= h && best.is_none_or(|b| t < b.0) {
                        best = Some((t, Vector3::z(), 0, 0));
                    }
                }
                let Some((t, normal, hit, triangle)) = best else {
                    let c = self.background;
                    frame.rgb[3 * i..3 * i + 3].copy_from_slice(&c.map(|x| x as u8));
                    continue;
                };
                let p = o + dir * t;
                let colour = if hit == 0 {
                    let (c, w) = (&self.table_colors, self.table_texture.weight(&p));
                    [0, 1, 2].map(|k| c[0][k] * (1.0 - w) + c[1][k] * w)
                } else {
                    let part = &self.parts[hit - 1];
                    frame.labels[i] = part.labels.at(normal.z);
                    frame.objects[i] = part.object;
                    part.colour(&p, triangle)
                };
                // Shade with the normal facing the camera.
                let nn = if normal.dot(&dir) > 0.0 {
                    -normal
                } else {
                    normal
                };
                let lambert = nn.dot(&self.light).max(0.0);
                let reflect = 2.0 * nn.dot(&self.light) * nn - self.light;
                let spec = self.specular * reflect.dot(&-dir).max(0.0).powi(self.shininess);
                let light = self.ambient + self.diffuse * lambert;
                for (c, out) in frame.rgb[3 * i..3 * i + 3].iter_mut().enumerate() {
                    let x = colour[c] * light + 255.0 * spec + 2.0 * self.noise(i, c as u64);
                    *out = x.round().clamp(0.0, 255.0) as u8;
                }
                let drop = self.uniform(i, 3, 0) < self.dropout;
                let z = t / len + self.depth_noise_sigma * self.noise(i, 4);
                frame.depth[i] = if drop { 0.0 } else { z as f32 };
            }
        }
        frame
    }
}

/// A rendered frame: colour, depth along the optical axis (m, 0 = no reading) and the label
/// byte of [`crate::labels`] and the scene object (1-based, [`Scene::identities`]) per pixel
/// (0 off objects).
pub struct Frame {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
    pub depth: Vec<f32>,
    pub labels: Vec<u8>,
    pub objects: Vec<u8>,
    pub camera_to_world: Isometry3<f64>,
}

impl Frame {
    /// The frame as graspd decodes one (camera `k`'s intrinsics).
    pub fn decoded(&self, k: &graspd_testkit::Intrinsics) -> DecodedFrame {
        DecodedFrame {
            width: self.width,
            height: self.height,
            rgb: self.rgb.clone(),
            depth: self.depth.clone(),
            intrinsics: CameraIntrinsics {
                fx: k.fx,
                fy: k.fy,
                cx: k.cx,
                cy: k.cy,
            },
            camera_to_world: Some(self.camera_to_world),
            valid_depth: self.depth.iter().filter(|d| **d > 0.0).count(),
        }
    }
}

/// An object before placement: its parts in the object's frame (origin on the table, z up) and
/// the radius of its footprint.
pub(crate) struct ObjectParts {
    parts: Vec<PartSpec>,
    footprint: f64,
}

/// A part in its object's frame.
type PartSpec = (Arc<dyn Shape>, Isometry3<f64>, PartDims);

/// A box of extents `e` standing on the table.
fn standing_box(e: [f64; 3]) -> PartSpec {
    (
        Arc::new(Cuboid::new(Vector::new(e[0] / 2.0, e[1] / 2.0, e[2] / 2.0))),
        Isometry3::translation(0.0, 0.0, e[2] / 2.0),
        PartDims::from_extents_m(e, e[2]),
    )
}

/// A cylinder of radius `r` and height `h` standing on the table (parry's axis is local y).
fn standing_cylinder(r: f64, h: f64) -> PartSpec {
    (
        Arc::new(Cylinder::new(h / 2.0, r)),
        Isometry3::from_parts(
            Translation3::new(0.0, 0.0, h / 2.0),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), FRAC_PI_2),
        ),
        PartDims::from_extents_m([2.0 * r, 2.0 * r, h], h),
    )
}

/// A cylinder of radius `r` and length `l` lying along x, its axis `z` above the table.
fn lying_cylinder(r: f64, l: f64, z: f64) -> PartSpec {
    (
        Arc::new(Cylinder::new(l / 2.0, r)),
        Isometry3::from_parts(
            Translation3::new(0.0, 0.0, z),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), FRAC_PI_2),
        ),
        PartDims::from_extents_m([2.0 * r, 2.0 * r, l], 2.0 * r),
    )
}

fn extents(rng: &mut ChaCha8Rng, xy: std::ops::Range<f64>, z: std::ops::Range<f64>) -> [f64; 3] {
    [
        rng.random_range(xy.clone()),
        rng.random_range(xy),
        rng.random_range(z),
    ]
}

/// Radius of the circle around a w × d footprint.
fn half_diagonal(w: f64, d: f64) -> f64 {
    0.5 * (w * w + d * d).sqrt()
}

/// A YCB object standing on the table, centred on its bounding box.
pub(crate) fn ycb_object(object: Object) -> graspd_testkit::Result<ObjectParts> {
    let m = mesh(object)?;
    let aabb = m.local_aabb();
    let (lo, hi) = (aabb.mins, aabb.maxs);
    let ext = [hi.x - lo.x, hi.y - lo.y, hi.z - lo.z];
    let shift = Translation3::new(-(lo.x + hi.x) / 2.0, -(lo.y + hi.y) / 2.0, -lo.z);
    let shape: Arc<dyn Shape> = m;
    let pose = Isometry3::from_parts(shift, UnitQuaternion::identity());
    Ok(ObjectParts {
        parts: vec![(shape, pose, PartDims::from_extents_m(ext, ext[2]))],
        footprint: half_diagonal(ext[0], ext[1]),
    })
}

/// A random object: 30 % YCB meshes, the rest procedural ([`random_primitive`]).
pub(crate) fn random_object(rng: &mut ChaCha8Rng) -> graspd_testkit::Result<ObjectParts> {
    let kind = rng.random_range(0..100);
    if kind < 30 {
        ycb_object(Object::ALL[rng.random_range(0..Object::ALL.len())])
    } else {
        Ok(random_primitive(rng, kind))
    }
}

/// A procedural object of `kind` (30…99: the share of each kind in [`random_object`]'s draw).
pub(crate) fn random_primitive(rng: &mut ChaCha8Rng, kind: u32) -> ObjectParts {
    let (parts, footprint): (Vec<PartSpec>, f64) = if kind < 42 {
        let (r, h) = (rng.random_range(0.01..0.06), rng.random_range(0.03..0.25));
        (vec![standing_cylinder(r, h)], r)
    } else if kind < 52 {
        let (r, l): (f64, f64) = (rng.random_range(0.008..0.05), rng.random_range(0.06..0.25));
        (vec![lying_cylinder(r, l, r)], half_diagonal(l, 2.0 * r))
    } else if kind < 62 {
        let e = extents(rng, 0.02..0.16, 0.02..0.16);
        (vec![standing_box(e)], half_diagonal(e[0], e[1]))
    } else if kind < 68 {
        // A thin plate lying flat.
        let e = extents(rng, 0.06..0.2, 0.004..0.015);
        (vec![standing_box(e)], half_diagonal(e[0], e[1]))
    } else if kind < 76 {
        let r = rng.random_range(0.015..0.06);
        let ball: PartSpec = (
            Arc::new(Ball::new(r)),
            Isometry3::translation(0.0, 0.0, r),
            PartDims::from_extents_m([2.0 * r; 3], 2.0 * r),
        );
        (vec![ball], r)
    } else if kind < 86 {
        // A small item (a cap, a die, an eraser): a box or a standing cylinder of 1.5–6 cm.
        let e = extents(rng, 0.015..0.06, 0.015..0.06);
        let part = if rng.random_bool(0.5) {
            standing_box(e)
        } else {
            standing_cylinder(e[0] / 2.0, e[2])
        };
        (vec![part], half_diagonal(e[0], e[1]))
    } else if kind < 93 {
        // A thin rod lying on the table (a marker, a tool).
        let (r, l): (f64, f64) = (rng.random_range(0.005..0.018), rng.random_range(0.1..0.25));
        (vec![lying_cylinder(r, l, r)], l / 2.0)
    } else {
        // A body with a horizontal handle (a pot, a pan, a tool): the handle starts inside the
        // body's wall.
        let (r, h) = (rng.random_range(0.03..0.07), rng.random_range(0.04..0.16));
        let (hr, hl) = (rng.random_range(0.007..0.016), rng.random_range(0.08..0.16));
        let hz: f64 = rng.random_range(0.4..0.9) * h;
        let (shape, pose, dims) = lying_cylinder(hr, hl, hz.max(hr));
        let handle = (
            shape,
            Isometry3::translation(r - 0.005 + hl / 2.0, 0.0, 0.0) * pose,
            dims,
        );
        (vec![standing_cylinder(r, h), handle], r + hl)
    };
    ObjectParts { parts, footprint }
}
