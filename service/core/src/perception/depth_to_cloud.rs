//! Back-projection of the depth image into a point cloud (method.md §4: the attention point and
//! the object's points are "back-projected with the depth image and intrinsics to 3-D").
//!
//! Pinhole model of `CameraInfo.K`: pixel (u, v) with depth z (along the optical axis) is the
//! camera-frame point `((u − cx)·z/fx, (v − cy)·z/fy, z)`. Pixels without a valid reading
//! (depth 0, which decoding makes of 0, NaN, ±inf and negative values) give no point: they are
//! skipped, never propagated.

use super::rgbd::{CameraIntrinsics, DecodedFrame};
use crate::cloud::PointCloud;
use nalgebra::{Isometry3, Point3};

/// Which frame the cloud is expressed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CloudFrame {
    /// The camera's optical frame (x right, y down, z forward).
    Camera,
    /// The world, through the frame's camera-to-world transform (camera frame without one).
    World,
}

/// A cloud whose points remember the pixel they came from.
#[derive(Debug, Clone, PartialEq)]
pub struct PixelCloud {
    pub cloud: PointCloud,
    /// Row-major pixel index (`v · width + u`) of each point.
    pub pixels: Vec<u32>,
    pub width: usize,
    pub height: usize,
    /// The frame the points are in ([`CloudFrame::Camera`] when the world was asked for but the
    /// frame has no camera-to-world transform).
    pub frame: CloudFrame,
}

impl PixelCloud {
    /// (u, v) of point `i`.
    pub fn pixel(&self, i: usize) -> (usize, usize) {
        let p = self.pixels[i] as usize;
        (p % self.width, p / self.width)
    }
}

/// The camera-frame point seen at pixel (u, v) with depth `z` metres.
pub fn back_project(k: &CameraIntrinsics, u: f64, v: f64, z: f64) -> Point3<f64> {
    Point3::new((u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z)
}

/// Back-projects every valid depth pixel of `frame` (scan-line order), in `target` frame.
pub fn depth_to_cloud(frame: &DecodedFrame, target: CloudFrame) -> PixelCloud {
    let k = &frame.intrinsics;
    let pose: Option<&Isometry3<f64>> = match target {
        CloudFrame::World => frame.camera_to_world.as_ref(),
        CloudFrame::Camera => None,
    };
    let mut points = Vec::with_capacity(frame.valid_depth);
    let mut pixels = Vec::with_capacity(frame.valid_depth);
    for v in 0..frame.height {
        let row = &frame.depth[v * frame.width..(v + 1) * frame.width];
        let y = (v as f64 - k.cy) / k.fy;
        for (u, &z) in row.iter().enumerate() {
            // Decoding leaves only finite positive depths or 0; the check keeps it so for
            // frames built by hand.
            if !(z > 0.0 && z.is_finite()) {
                continue;
            }
            let z = z as f64;
            let p = Point3::new((u as f64 - k.cx) / k.fx * z, y * z, z);
            points.push(match pose {
                Some(t) => t * p,
                None => p,
            });
            pixels.push((v * frame.width + u) as u32);
        }
    }
    PixelCloud {
        cloud: PointCloud::new(points),
        pixels,
        width: frame.width,
        height: frame.height,
        frame: if pose.is_some() {
            CloudFrame::World
        } else {
            CloudFrame::Camera
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    fn frame(depth: Vec<f32>, w: usize, pose: Option<Isometry3<f64>>) -> DecodedFrame {
        let h = depth.len() / w;
        DecodedFrame {
            width: w,
            height: h,
            rgb: vec![0; 3 * w * h],
            valid_depth: depth.iter().filter(|d| **d > 0.0).count(),
            depth,
            intrinsics: CameraIntrinsics {
                fx: 100.0,
                fy: 200.0,
                cx: 1.0,
                cy: 0.5,
            },
            camera_to_world: pose,
        }
    }

    #[test]
    fn pinhole_back_projection_and_invalid_pixels() {
        let f = frame(vec![1.0, 0.0, 2.0, f32::NAN, f32::INFINITY, 0.5], 3, None);
        let c = depth_to_cloud(&f, CloudFrame::World);
        assert_eq!(c.frame, CloudFrame::Camera);
        assert_eq!(c.pixels, vec![0, 2, 5]);
        assert_eq!(c.pixel(2), (2, 1));
        let p = &c.cloud.points;
        assert!((p[0] - Point3::new(-0.01, -0.0025, 1.0)).norm() < 1e-12);
        assert!((p[1] - Point3::new(0.02, -0.005, 2.0)).norm() < 1e-12);
        assert!((p[2] - Point3::new(0.005, 0.00125, 0.5)).norm() < 1e-12);
        assert!(p.iter().all(|q| q.coords.iter().all(|v| v.is_finite())));
        // Re-projection gives back the pixel.
        let k = &f.intrinsics;
        let q = back_project(k, 2.0, 1.0, 0.5);
        assert!((q - p[2]).norm() < 1e-12);
    }

    #[test]
    fn world_frame_applies_the_camera_pose() {
        let pose = Isometry3::from_parts(
            Translation3::new(0.1, 0.2, 0.3),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2),
        );
        let f = frame(vec![1.0, 1.0], 2, Some(pose));
        let cam = depth_to_cloud(&f, CloudFrame::Camera);
        let world = depth_to_cloud(&f, CloudFrame::World);
        assert_eq!(world.frame, CloudFrame::World);
        for (a, b) in cam.cloud.points.iter().zip(&world.cloud.points) {
            assert!((pose * a - b).norm() < 1e-12);
        }
    }
}
