//! A pinhole depth sensor made of ray casts: one ray per pixel centre, the first hit on the
//! mesh (or on a finite table patch at z = 0) gives a point in the world frame, optionally with
//! Gaussian noise along the ray.
//!
//! The camera follows the OpenCV convention (x right, y down, z forward; pixel (u, v) looks
//! along `((u + 0.5 - cx) / fx, (v + 0.5 - cy) / fy, 1)`), so that a region of interest is just
//! a shifted principal point and a smaller image: [`Camera::crop_to`] renders the same rays a
//! full frame would, only those around the object.

use graspd_core::cloud::PointCloud;
use nalgebra::{Point3, Vector3};
use parry3d_f64::math::Vector;
use parry3d_f64::query::{Ray, RayCast};
use parry3d_f64::shape::TriMesh;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Pinhole intrinsics, pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub width: usize,
    pub height: usize,
}

impl Intrinsics {
    /// A 640 × 480 structured-light sensor (PrimeSense / Kinect v1 class: f = 525 px, about
    /// 63° × 49° field of view; 1.1 mm between pixels at 0.6 m).
    pub const VGA: Intrinsics = Intrinsics {
        fx: 525.0,
        fy: 525.0,
        cx: 320.0,
        cy: 240.0,
        width: 640,
        height: 480,
    };
}

/// A square patch of the table plane z = 0, centred at (`center_x`, `center_y`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TablePatch {
    pub center_x: f64,
    pub center_y: f64,
    /// Half the side length, m.
    pub half_extent: f64,
}

impl TablePatch {
    fn contains(&self, x: f64, y: f64) -> bool {
        (x - self.center_x).abs() <= self.half_extent
            && (y - self.center_y).abs() <= self.half_extent
    }

    fn corners(&self) -> [Point3<f64>; 4] {
        let (x, y, h) = (self.center_x, self.center_y, self.half_extent);
        [
            Point3::new(x - h, y - h, 0.0),
            Point3::new(x + h, y - h, 0.0),
            Point3::new(x - h, y + h, 0.0),
            Point3::new(x + h, y + h, 0.0),
        ]
    }
}

/// A depth camera in the world frame (z up).
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    pub position: Point3<f64>,
    /// The point the optical axis goes through.
    pub target: Point3<f64>,
    /// World "up" used to roll the camera (its image y axis points away from it).
    pub up: Vector3<f64>,
    pub intrinsics: Intrinsics,
    /// Standard deviation of the Gaussian range noise along each ray, m (0: none).
    pub depth_noise_sigma: f64,
    /// Seed of the noise (draws are made in scan-line order, so a render is deterministic).
    pub noise_seed: u64,
    /// Table patch at z = 0 that the rays may hit (and that hides what lies below it).
    pub table: Option<TablePatch>,
    /// Farthest range the sensor reports, m.
    pub max_range: f64,
}

impl Camera {
    /// A VGA camera `distance` m from `target`, `elevation_deg` above the horizontal plane
    /// through the target and at `azimuth_deg` about z (0: on the +x side, 90: on +y),
    /// looking at the target. No noise, no table.
    pub fn orbit(
        target: Point3<f64>,
        distance: f64,
        elevation_deg: f64,
        azimuth_deg: f64,
    ) -> Camera {
        let (el, az) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
        let dir = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
        Camera {
            position: target + dir * distance,
            target,
            up: Vector3::z(),
            intrinsics: Intrinsics::VGA,
            depth_noise_sigma: 0.0,
            noise_seed: 0,
            table: None,
            max_range: 10.0,
        }
    }

    /// Adds Gaussian range noise.
    pub fn with_noise(mut self, sigma: f64, seed: u64) -> Camera {
        self.depth_noise_sigma = sigma;
        self.noise_seed = seed;
        self
    }

    /// Adds a table patch.
    pub fn with_table(mut self, table: TablePatch) -> Camera {
        self.table = Some(table);
        self
    }

    /// The camera axes in the world frame: (right, down, forward).
    pub fn axes(&self) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let f = (self.target - self.position).normalize();
        let mut r = f.cross(&self.up);
        if r.norm() < 1e-9 {
            // Looking along `up`: any perpendicular will do.
            r = f.cross(&Vector3::x());
        }
        let r = r.normalize();
        let d = f.cross(&r);
        (r, d, f)
    }

    /// Pixel coordinates (u, v) and depth of a world point; `None` behind the camera.
    pub fn project(&self, p: &Point3<f64>) -> Option<(f64, f64, f64)> {
        let (r, d, f) = self.axes();
        let q = p - self.position;
        let z = q.dot(&f);
        if z <= 1e-9 {
            return None;
        }
        let k = &self.intrinsics;
        Some((k.fx * q.dot(&r) / z + k.cx, k.fy * q.dot(&d) / z + k.cy, z))
    }

    /// Crops the image to the pixels whose rays can reach the given points (their projected
    /// bounding box plus `margin_px`), clamped to the image. Rays are unchanged.
    pub fn crop_to(&mut self, points: &[Point3<f64>], margin_px: f64) {
        let k = self.intrinsics;
        let (mut u0, mut v0, mut u1, mut v1) = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        for p in points {
            if let Some((u, v, _)) = self.project(p) {
                u0 = u0.min(u);
                v0 = v0.min(v);
                u1 = u1.max(u);
                v1 = v1.max(v);
            }
        }
        if !u0.is_finite() {
            return;
        }
        let clamp = |x: f64, hi: usize| x.clamp(0.0, hi as f64) as usize;
        let (a, b) = (
            clamp((u0 - margin_px).floor(), k.width),
            clamp((u1 + margin_px).ceil(), k.width),
        );
        let (c, d) = (
            clamp((v0 - margin_px).floor(), k.height),
            clamp((v1 + margin_px).ceil(), k.height),
        );
        self.intrinsics = Intrinsics {
            cx: k.cx - a as f64,
            cy: k.cy - c as f64,
            width: b.saturating_sub(a),
            height: d.saturating_sub(c),
            ..k
        };
    }

    /// A sensor with `factor` times the resolution (same field of view).
    pub fn zoomed(mut self, factor: f64) -> Camera {
        let k = self.intrinsics;
        self.intrinsics = Intrinsics {
            fx: k.fx * factor,
            fy: k.fy * factor,
            cx: k.cx * factor,
            cy: k.cy * factor,
            width: (k.width as f64 * factor).round() as usize,
            height: (k.height as f64 * factor).round() as usize,
        };
        self
    }
}

/// A rendered view.
#[derive(Debug, Clone)]
pub struct RenderedView {
    /// Hit points in the world frame (no normals: a depth sensor does not give them).
    pub cloud: PointCloud,
    /// True surface normal at each point (of the mesh or table), turned toward the camera.
    pub normals: Vec<Vector3<f64>>,
    /// Whether each point lies on the table patch.
    pub is_table: Vec<bool>,
    /// The camera position.
    pub viewpoint: Point3<f64>,
    /// Number of rays cast.
    pub rays: usize,
}

impl RenderedView {
    /// The points on the object only, with their true normals.
    pub fn object_only(&self) -> (PointCloud, Vec<Vector3<f64>>) {
        let keep = |i: &usize| !self.is_table[*i];
        let idx: Vec<usize> = (0..self.is_table.len()).filter(keep).collect();
        (
            PointCloud::new(idx.iter().map(|&i| self.cloud.points[i]).collect()),
            idx.iter().map(|&i| self.normals[i]).collect(),
        )
    }
}

fn g(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

/// One standard normal draw (Box–Muller).
pub(crate) fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Renders `mesh` (world frame) as seen by `camera`: one ray per pixel, first hit on the mesh or
/// the table patch. Points are in the world frame, in scan-line order.
pub fn render_view(mesh: &TriMesh, camera: &Camera) -> RenderedView {
    let k = camera.intrinsics;
    let (r, d, f) = camera.axes();
    let o = camera.position;
    let mut rng = ChaCha8Rng::seed_from_u64(camera.noise_seed);
    let mut points = Vec::new();
    let mut normals = Vec::new();
    let mut is_table = Vec::new();
    for v in 0..k.height {
        for u in 0..k.width {
            let xc = (u as f64 + 0.5 - k.cx) / k.fx;
            let yc = (v as f64 + 0.5 - k.cy) / k.fy;
            let dir = (r * xc + d * yc + f).normalize();
            let ray = Ray::new(g(&o.coords), g(&dir));
            let mut best: Option<(f64, Vector3<f64>, bool)> = None;
            if let Some(hit) = mesh.cast_local_ray_and_get_normal(&ray, camera.max_range, false) {
                let n = Vector3::new(hit.normal.x, hit.normal.y, hit.normal.z);
                best = Some((hit.time_of_impact, n, false));
            }
            if let Some(table) = &camera.table
                && dir.z < -1e-12
                && o.z > 0.0
            {
                let t = -o.z / dir.z;
                let p = o + dir * t;
                if t <= camera.max_range
                    && table.contains(p.x, p.y)
                    && best.is_none_or(|(tb, _, _)| t < tb)
                {
                    best = Some((t, Vector3::z(), true));
                }
            }
            let Some((t, n, on_table)) = best else {
                continue;
            };
            let t = if camera.depth_noise_sigma > 0.0 {
                t + camera.depth_noise_sigma * gaussian(&mut rng)
            } else {
                t
            };
            points.push(o + dir * t);
            let n = if n.dot(&dir) > 0.0 { -n } else { n };
            normals.push(n.try_normalize(1e-12).unwrap_or(-dir));
            is_table.push(on_table);
        }
    }
    RenderedView {
        cloud: PointCloud::new(points),
        normals,
        is_table,
        viewpoint: o,
        rays: k.width * k.height,
    }
}

/// The corners to crop a camera to so that it sees an AABB and, if any, the table patch.
pub fn crop_corners(
    lo: &Point3<f64>,
    hi: &Point3<f64>,
    table: Option<&TablePatch>,
) -> Vec<Point3<f64>> {
    let mut c: Vec<Point3<f64>> = (0..8)
        .map(|i| {
            Point3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    if let Some(t) = table {
        c.extend(t.corners());
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_cube() -> TriMesh {
        // A 10 cm cube standing on the table, outward winding.
        let s = 0.05;
        let v: Vec<Vector> = (0..8)
            .map(|i| {
                Vector::new(
                    if i & 1 == 0 { -s } else { s },
                    if i & 2 == 0 { -s } else { s },
                    if i & 4 == 0 { 0.0 } else { 2.0 * s },
                )
            })
            .collect();
        let idx = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        TriMesh::new(v, idx).unwrap()
    }

    #[test]
    fn projection_and_rays_agree() {
        let cam = Camera::orbit(Point3::new(0.1, 0.2, 0.05), 0.6, 40.0, 30.0);
        let (u, v, z) = cam.project(&cam.target).unwrap();
        assert!((u - 320.0).abs() < 1e-9 && (v - 240.0).abs() < 1e-9);
        assert!((z - 0.6).abs() < 1e-12);
        // A point above the target appears higher in the image (smaller v).
        let (_, v2, _) = cam.project(&(cam.target + Vector3::z() * 0.05)).unwrap();
        assert!(v2 < v);
        assert!(
            cam.project(&(cam.position - (cam.target - cam.position)))
                .is_none()
        );
    }

    #[test]
    fn cube_view_sees_top_and_sides_and_table() {
        let mesh = unit_cube();
        let mut cam =
            Camera::orbit(Point3::new(0.0, 0.0, 0.05), 0.6, 45.0, 0.0).with_table(TablePatch {
                center_x: 0.0,
                center_y: 0.0,
                half_extent: 0.15,
            });
        let corners = crop_corners(
            &Point3::new(-0.05, -0.05, 0.0),
            &Point3::new(0.05, 0.05, 0.1),
            cam.table.as_ref(),
        );
        let full_cam = cam.clone();
        cam.crop_to(&corners, 2.0);
        assert!(cam.intrinsics.width < 640 && cam.intrinsics.height < 480);
        let view = render_view(&mesh, &cam);
        let table = view.is_table.iter().filter(|t| **t).count();
        let object = view.is_table.len() - table;
        assert!(
            table > 1000 && object > 1000,
            "table {table}, object {object}"
        );
        for (p, n) in view.cloud.points.iter().zip(&view.normals) {
            assert!(p.z > -1e-9 && p.z < 0.1 + 1e-9);
            // Only the top (+z) and the +x side face a camera on the +x side.
            assert!(n.z > 0.99 || n.x > 0.99, "{n}");
        }
        // The same rays as the full frame: cropping does not change what is hit.
        let full = render_view(&mesh, &full_cam);
        assert_eq!(full.cloud.points, view.cloud.points);
    }
}
