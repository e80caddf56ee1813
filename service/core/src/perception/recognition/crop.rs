//! The view of one segmented object that the recogniser reads (§3.2.1): a square crop of the
//! frame around the object's pixels with everything that is not the object blanked, and the
//! object's metric size, which a crop scaled to the object's extent no longer shows. Training
//! data is made by this same code (models/recogniser), so the network sees at training what it
//! sees in service.

use super::super::depth_to_cloud::{CloudFrame, PixelCloud};
use super::super::grasp_type::{IMAGENET_MEAN, IMAGENET_STD};
use super::super::rgbd::DecodedFrame;
use crate::cloud::Plane;
use nalgebra::{Point3, Vector3};

/// Side of the crop, pixels.
pub const CROP_SIDE: usize = 64;
/// Planes of the crop: R, G, B (ImageNet-normalised), the object's share of the cell, and the
/// depth relative to the object's median.
pub const CROP_CHANNELS: usize = 5;
/// Size features: height above the support plane, longer and shorter horizontal extent.
pub const SIZE_FEATURES: usize = 3;
/// The crop's side is the object's pixel box's longer side times this (a margin around it).
const MARGIN: f64 = 1.15;
/// Depth relative to the object's median is divided by this (m) and clipped to ±1.
const DEPTH_SCALE: f32 = 0.1;
/// Sizes are given in decimetres, so the features are of order 1.
const SIZE_UNIT: f64 = 0.1;

/// One object as the recogniser sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectCrop {
    /// `[CROP_CHANNELS, CROP_SIDE, CROP_SIDE]`, plane-major, row-major.
    pub planes: Vec<f32>,
    /// Height above the plane, longer and shorter horizontal extent, decimetres.
    pub size: [f32; SIZE_FEATURES],
}

/// The crop of the object made of `cloud` points `indices` (see the module docs). `plane`: the
/// support plane (its normal points up); without one, the camera's up (−y of the image)
/// stands in for it. Empty `indices` give an all-zero crop.
pub fn object_crop(
    frame: &DecodedFrame,
    cloud: &PixelCloud,
    indices: &[usize],
    plane: Option<&Plane>,
) -> ObjectCrop {
    let s = CROP_SIDE;
    let mut planes = vec![0.0f32; CROP_CHANNELS * s * s];
    if indices.is_empty() {
        return ObjectCrop {
            planes,
            size: [0.0; SIZE_FEATURES],
        };
    }
    let w = cloud.width;
    let (mut u0, mut v0, mut u1, mut v1) = (usize::MAX, usize::MAX, 0, 0);
    for &i in indices {
        let (u, v) = cloud.pixel(i);
        (u0, v0, u1, v1) = (u0.min(u), v0.min(v), u1.max(u), v1.max(v));
    }
    let (bw, bh) = (u1 - u0 + 1, v1 - v0 + 1);
    // The object's pixels in its box.
    let mut member = vec![false; bw * bh];
    let mut depths: Vec<f32> = Vec::with_capacity(indices.len());
    for &i in indices {
        let (u, v) = cloud.pixel(i);
        member[(v - v0) * bw + (u - u0)] = true;
        depths.push(frame.depth[v * w + u]);
    }
    let mid = depths.len() / 2;
    let median = *depths.select_nth_unstable_by(mid, f32::total_cmp).1;
    let side = bw.max(bh) as f64 * MARGIN;
    let (cu, cv) = ((u0 + u1) as f64 / 2.0 + 0.5, (v0 + v1) as f64 / 2.0 + 0.5);
    let cell = side / s as f64;
    let n = s * s;
    for y in 0..s {
        // Source rows of this cell: at least the one under its centre.
        let (r0, r1) = cell_span(cv - side / 2.0, cell, y);
        for x in 0..s {
            let (c0, c1) = cell_span(cu - side / 2.0, cell, x);
            let (mut rgb, mut depth, mut count, mut area) = ([0.0f32; 3], 0.0f32, 0u32, 0u32);
            for v in r0..r1 {
                for u in c0..c1 {
                    area += 1;
                    let inside = (u0 as i64..=u1 as i64).contains(&u)
                        && (v0 as i64..=v1 as i64).contains(&v);
                    if !inside {
                        continue;
                    }
                    let (lu, lv) = (u as usize - u0, v as usize - v0);
                    if !member[lv * bw + lu] {
                        continue;
                    }
                    let p = v as usize * w + u as usize;
                    for (k, c) in rgb.iter_mut().enumerate() {
                        *c += frame.rgb[3 * p + k] as f32;
                    }
                    depth += frame.depth[p];
                    count += 1;
                }
            }
            if count == 0 {
                continue;
            }
            let i = y * s + x;
            let k = count as f32;
            for (c, sum) in rgb.iter().enumerate() {
                planes[c * n + i] = (sum / k / 255.0 - IMAGENET_MEAN[c]) / IMAGENET_STD[c];
            }
            planes[3 * n + i] = (k / area.max(1) as f32).min(1.0);
            planes[4 * n + i] = ((depth / k - median) / DEPTH_SCALE).clamp(-1.0, 1.0);
        }
    }
    ObjectCrop {
        planes,
        size: object_size(frame, cloud, indices, plane),
    }
}

/// The source pixels [first, end) of crop cell `k` along one axis, starting at `origin` with
/// cells of `cell` pixels: every pixel whose centre lies in the cell, else the one under the
/// cell's centre (a crop larger than the object).
fn cell_span(origin: f64, cell: f64, k: usize) -> (i64, i64) {
    let a = origin + cell * k as f64;
    let (first, end) = ((a - 0.5).ceil() as i64, (a + cell - 0.5).ceil() as i64);
    if end > first {
        (first, end)
    } else {
        let c = (a + cell / 2.0).floor() as i64;
        (c, c + 1)
    }
}

/// Height above the plane and the longer and shorter horizontal extents (2nd to 98th
/// percentile, so that a few flying pixels at the rim do not count), decimetres.
fn object_size(
    frame: &DecodedFrame,
    cloud: &PixelCloud,
    indices: &[usize],
    plane: Option<&Plane>,
) -> [f32; SIZE_FEATURES] {
    let points: Vec<Point3<f64>> = indices.iter().map(|&i| cloud.cloud.points[i]).collect();
    let camera_up = Vector3::new(0.0, -1.0, 0.0);
    let up = match (plane, cloud.frame, frame.camera_to_world.as_ref()) {
        (Some(p), _, _) => p.normal,
        (None, CloudFrame::World, Some(t)) => t.rotation * camera_up,
        _ => camera_up,
    };
    let heights: Vec<f64> = match plane {
        Some(p) => points.iter().map(|q| p.distance(q)).collect(),
        None => points.iter().map(|q| q.coords.dot(&up)).collect(),
    };
    let height = match plane {
        Some(_) => quantile(&heights, 0.98).max(0.0),
        None => quantile(&heights, 0.98) - quantile(&heights, 0.02),
    };
    // Horizontal spread: the principal axes of the points projected along `up`.
    let n = points.len() as f64;
    let mean = points.iter().fold(Vector3::zeros(), |a, q| a + q.coords) / n;
    let flat: Vec<Vector3<f64>> = points
        .iter()
        .map(|q| {
            let d = q.coords - mean;
            d - up * d.dot(&up)
        })
        .collect();
    let cov = flat
        .iter()
        .fold(nalgebra::Matrix3::zeros(), |a, d| a + d * d.transpose())
        / n;
    let eig = cov.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let extent = |axis: Vector3<f64>| {
        let along: Vec<f64> = flat.iter().map(|d| d.dot(&axis)).collect();
        quantile(&along, 0.98) - quantile(&along, 0.02)
    };
    let major = extent(eig.eigenvectors.column(order[0]).into_owned());
    let minor = extent(eig.eigenvectors.column(order[1]).into_owned());
    [height, major, minor].map(|m| (m / SIZE_UNIT) as f32)
}

/// The `q` quantile of `values` (nearest rank; 0 for none).
fn quantile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    let k = ((v.len() - 1) as f64 * q).round() as usize;
    *v.select_nth_unstable_by(k, f64::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::PointCloud;
    use crate::perception::rgbd::CameraIntrinsics;

    /// A 40 × 20 px red rectangle (pixels 100..140 × 50..70) of a 200 × 100 frame, seen 1 m away
    /// with f = 100 px, standing on a plane 2 cm below its lowest point.
    fn rectangle() -> (DecodedFrame, PixelCloud, Vec<usize>, Plane) {
        let (w, h) = (200, 100);
        let mut rgb = vec![0u8; 3 * w * h];
        let mut depth = vec![0.0f32; w * h];
        let k = CameraIntrinsics {
            fx: 100.0,
            fy: 100.0,
            cx: 100.0,
            cy: 50.0,
        };
        let (mut points, mut pixels) = (Vec::new(), Vec::new());
        for v in 50..70 {
            for u in 100..140 {
                let p = v * w + u;
                rgb[3 * p] = 255;
                depth[p] = 1.0;
                pixels.push(p as u32);
                points.push(Point3::new(
                    (u as f64 - k.cx) / k.fx,
                    (v as f64 - k.cy) / k.fy,
                    1.0,
                ));
            }
        }
        let n = points.len();
        let frame = DecodedFrame {
            width: w,
            height: h,
            rgb,
            depth,
            intrinsics: k,
            camera_to_world: None,
            valid_depth: n,
        };
        let cloud = PixelCloud {
            cloud: PointCloud::new(points),
            pixels,
            width: w,
            height: h,
            frame: CloudFrame::Camera,
        };
        // Up is −y; the lowest row (v = 69) is y = 0.19; the plane y = 0.21.
        let plane = Plane {
            normal: Vector3::new(0.0, -1.0, 0.0),
            offset: 0.21,
        };
        (frame, cloud, (0..n).collect(), plane)
    }

    #[test]
    fn crop_blanks_all_but_the_object_and_keeps_its_colour() {
        let (frame, cloud, idx, plane) = rectangle();
        let c = object_crop(&frame, &cloud, &idx, Some(&plane));
        let (s, n) = (CROP_SIDE, CROP_SIDE * CROP_SIDE);
        // The box is 40 px wide: the crop spans 46 px, 0.72 px per cell, centred.
        let centre = (s / 2) * s + s / 2;
        let red = (1.0 - IMAGENET_MEAN[0]) / IMAGENET_STD[0];
        let green = (0.0 - IMAGENET_MEAN[1]) / IMAGENET_STD[1];
        assert!((c.planes[centre] - red).abs() < 1e-5);
        assert!((c.planes[n + centre] - green).abs() < 1e-5);
        assert_eq!(c.planes[3 * n + centre], 1.0);
        assert_eq!(c.planes[4 * n + centre], 0.0);
        // Corners are outside the object (the box is twice as wide as high): blank.
        for ch in 0..CROP_CHANNELS {
            assert_eq!(c.planes[ch * n], 0.0);
        }
        // Rows: the object covers 20/46 of the crop's height, centred.
        let rows = (0..s)
            .filter(|&y| c.planes[3 * n + y * s + s / 2] > 0.5)
            .count();
        assert!((26..=30).contains(&rows), "{rows} rows");
    }

    #[test]
    fn size_is_height_and_extents_in_decimetres() {
        let (frame, cloud, idx, plane) = rectangle();
        let c = object_crop(&frame, &cloud, &idx, Some(&plane));
        // Height: 2 cm gap + 19 rows of 1 cm (the 98th percentile falls in the top row),
        // 0.21 m; horizontal extent along x 0.39 m (40 columns of 1 cm, the 2nd and 98th
        // percentiles in the first and last), along z none.
        assert!((c.size[0] - 2.1).abs() < 1e-4, "{:?}", c.size);
        assert!((c.size[1] - 3.9).abs() < 1e-4, "{:?}", c.size);
        assert!(c.size[2].abs() < 1e-6, "{:?}", c.size);
        // Without a plane the camera's up gives the height: the rectangle's own 19 rows.
        let c = object_crop(&frame, &cloud, &idx, None);
        assert!((c.size[0] - 1.9).abs() < 1e-4, "{:?}", c.size);
    }
}
