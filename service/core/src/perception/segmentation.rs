//! Object segmentation from depth (method.md §4: "segment objects from depth (support-plane
//! removal + Euclidean clustering) and accept a caller's hint (pixel, box or cluster)").
//!
//! 1. **Support plane**: the caller's plane, else RANSAC ([`detect_support_plane`], seeded, on
//!    an even subsample of at most [`SegmentationParams::plane_sample`] points), then every
//!    point within [`SegmentationParams::plane_margin`] of it, or below it, is support.
//! 2. **Euclidean clustering** of the points above the plane: two points belong to one object
//!    when a chain of points links them with steps ≤ [`SegmentationParams::cluster_radius`]
//!    (1 cm). Computed on voxels of half that radius (their centroids linked through a kiddo
//!    k-d tree, union–find), so a 640×480 frame costs milliseconds instead of a radius query per
//!    point; the error is at most one voxel diagonal. Clusters smaller than
//!    [`SegmentationParams::min_cluster_points`] are noise.
//! 3. **Target object** (the object region O of Ω, method.md §1), in this order:
//!    - a hint pixel (`hints.attention_pixel`): the cluster holding that pixel, else the cluster
//!      with the pixel nearest to it;
//!    - a hint box (`hints.region`, [u_min, u_max) × [v_min, v_max)): the cluster with most
//!      pixels inside it;
//!    - a saliency map (VOCUS2, [`super::saliency`]): the cluster with the highest mean
//!      saliency over its pixels (ch. 4.2.1: "the region with the highest mean saliency");
//!    - otherwise the cluster whose pixel centroid is nearest the image centre.
//!
//! Without a caller's plane and with none found (no table in view, or one that fails the
//! checks of [`detect_support_plane`]), nothing is removed and every connected surface is a
//! cluster; [`Segmentation::plane`] is then `None`.

use super::depth_to_cloud::PixelCloud;
use crate::cloud::{CloudIndex, Plane, PointCloud, RansacParams, detect_support_plane};
use crate::error::FieldError;
use nalgebra::Point3;
use std::collections::HashMap;

/// Parameters of the segmentation.
#[derive(Debug, Clone, Copy)]
pub struct SegmentationParams {
    /// RANSAC of the support plane (iterations, inlier band, smallest share).
    pub ransac: RansacParams,
    /// At most this many points (an even subsample) go into the RANSAC search.
    pub plane_sample: usize,
    /// Points closer to the plane than this (m), or below it, are support.
    pub plane_margin: f64,
    /// Euclidean clustering distance, m.
    pub cluster_radius: f64,
    /// Fewest points of an object cluster.
    pub min_cluster_points: usize,
    /// Seeds the RANSAC.
    pub seed: u64,
}

impl Default for SegmentationParams {
    /// 200 RANSAC iterations on ≤ 20 000 points with a 4 mm band, 5 mm support margin (depth
    /// noise plus 16-bit millimetre quantisation), 1 cm clustering, 150-point objects.
    fn default() -> Self {
        Self {
            ransac: RansacParams::default(),
            plane_sample: 20_000,
            plane_margin: 0.005,
            cluster_radius: 0.01,
            min_cluster_points: 150,
            seed: 0,
        }
    }
}

/// How the caller points at the object.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum TargetHint {
    /// No hint: the most salient cluster if a saliency map is given, else the most central.
    #[default]
    Auto,
    /// The object at (or nearest to) pixel (u, v) (`hints.attention_pixel`).
    Pixel { u: u32, v: u32 },
    /// The object with most pixels in [u_min, u_max) × [v_min, v_max) (`hints.region`).
    Region {
        u_min: u32,
        v_min: u32,
        u_max: u32,
        v_max: u32,
    },
    /// The object the recogniser takes for this name (`hints.object`, [`super::recognition`]);
    /// [`segment`] alone cannot serve it.
    Object(String),
}

/// What decided the target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TargetChoice {
    Pixel,
    Region,
    Object,
    Saliency,
    ImageCentre,
}

impl TargetChoice {
    /// The API name (`pixel`, `region`, `saliency`, `image_centre`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Pixel => "pixel",
            Self::Region => "region",
            Self::Object => "object",
            Self::Saliency => "saliency",
            Self::ImageCentre => "image_centre",
        }
    }

    /// The inverse of [`Self::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        [
            Self::Pixel,
            Self::Region,
            Self::Object,
            Self::Saliency,
            Self::ImageCentre,
        ]
        .into_iter()
        .find(|c| c.name() == name)
    }
}

/// One object cluster: indices into the [`PixelCloud`].
#[derive(Debug, Clone, PartialEq)]
pub struct Cluster {
    pub indices: Vec<usize>,
    /// Mean (u, v) of its pixels.
    pub pixel_centroid: (f64, f64),
}

/// The segmentation of a frame.
#[derive(Debug, Clone)]
pub struct Segmentation {
    /// The support plane (normal toward the objects), in the cloud's frame; `None` if none was
    /// given or found.
    pub plane: Option<Plane>,
    /// Object clusters, largest first.
    pub clusters: Vec<Cluster>,
    /// Index of the target in `clusters`.
    pub target: usize,
    pub choice: TargetChoice,
    /// The target's points (the cloud's frame) and their pixels.
    pub object: PointCloud,
    pub object_pixels: Vec<u32>,
    /// The target's pixel mask, row-major `width × height`.
    pub mask: Vec<bool>,
}

/// Union–find with path halving.
struct Dsu(Vec<u32>);

impl Dsu {
    fn find(&mut self, mut i: u32) -> u32 {
        while self.0[i as usize] != i {
            let p = self.0[self.0[i as usize] as usize];
            self.0[i as usize] = p;
            i = p;
        }
        i
    }

    fn union(&mut self, a: u32, b: u32) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            // Keep the smaller root: the result does not depend on the order of unions.
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            self.0[hi as usize] = lo;
        }
    }
}

/// Euclidean clusters (see the module docs) of `points[idx]`: lists of entries of `idx`, each
/// with ≥ `min_points`, largest first (ties: earliest first point).
pub fn euclidean_clusters(
    points: &[Point3<f64>],
    idx: &[usize],
    radius: f64,
    min_points: usize,
) -> Vec<Vec<usize>> {
    if idx.is_empty() {
        return Vec::new();
    }
    let voxel = radius / 2.0;
    let mut voxel_of: HashMap<[i32; 3], u32> = HashMap::with_capacity(idx.len() / 8);
    let mut sums: Vec<(nalgebra::Vector3<f64>, usize)> = Vec::new();
    let mut point_voxel = Vec::with_capacity(idx.len());
    for &i in idx {
        let p = &points[i];
        let key = [
            (p.x / voxel).floor() as i32,
            (p.y / voxel).floor() as i32,
            (p.z / voxel).floor() as i32,
        ];
        let id = *voxel_of.entry(key).or_insert_with(|| {
            sums.push((nalgebra::Vector3::zeros(), 0));
            (sums.len() - 1) as u32
        });
        sums[id as usize].0 += p.coords;
        sums[id as usize].1 += 1;
        point_voxel.push(id);
    }
    let centroids: Vec<Point3<f64>> = sums
        .iter()
        .map(|(s, n)| Point3::from(s / *n as f64))
        .collect();
    let index = CloudIndex::new(&centroids);
    let mut dsu = Dsu((0..centroids.len() as u32).collect());
    for (a, c) in centroids.iter().enumerate() {
        for b in index.within_unsorted(c, radius) {
            if b > a {
                dsu.union(a as u32, b as u32);
            }
        }
    }
    let mut cluster_of_root: HashMap<u32, usize> = HashMap::new();
    let mut clusters: Vec<Vec<usize>> = Vec::new();
    for (&i, &vx) in idx.iter().zip(&point_voxel) {
        let root = dsu.find(vx);
        let c = *cluster_of_root.entry(root).or_insert_with(|| {
            clusters.push(Vec::new());
            clusters.len() - 1
        });
        clusters[c].push(i);
    }
    clusters.retain(|c| c.len() >= min_points.max(1));
    // Stable sort: equal sizes keep the order of their first point.
    clusters.sort_by_key(|c| std::cmp::Reverse(c.len()));
    clusters
}

/// Segments `cloud` (see the module docs). `support_plane`: a plane the caller knows (in the
/// cloud's frame); `saliency`: a row-major map of the frame's size, higher = more salient.
///
/// Errors name `hints.attention_pixel` / `hints.region` for hints outside the image, a region
/// holding no object, and `rgbd.depth` when nothing stands on the plane.
pub fn segment(
    cloud: &PixelCloud,
    hint: TargetHint,
    saliency: Option<&[f32]>,
    support_plane: Option<Plane>,
    params: &SegmentationParams,
) -> Result<Segmentation, FieldError> {
    let (w, h) = (cloud.width, cloud.height);
    check_hint(&hint, w, h)?;
    if let Some(s) = saliency
        && s.len() != w * h
    {
        return Err(FieldError::new(
            "saliency",
            format!("{} values for a {w}×{h} frame", s.len()),
        ));
    }
    let (plane, clusters) = segment_objects(cloud, support_plane, params)?;
    let (target, choice) = choose_target(cloud, &clusters, hint, saliency)?;
    Ok(Segmentation::with_target(
        cloud, plane, clusters, target, choice,
    ))
}

/// The support plane and the objects on it, as [`Cluster`]s (steps 1 and 2 of the module
/// docs). Errors name `rgbd.depth` when nothing stands on the plane.
pub fn segment_objects(
    cloud: &PixelCloud,
    support_plane: Option<Plane>,
    params: &SegmentationParams,
) -> Result<(Option<Plane>, Vec<Cluster>), FieldError> {
    let points = &cloud.cloud.points;
    let (plane, lists, above) = objects_on_plane(points, support_plane, params);
    if lists.is_empty() {
        return Err(FieldError::new(
            "rgbd.depth",
            format!(
                "no object found: {} of {} depth points lie {} the support plane, no cluster of \
                 ≥ {} points within {} m of each other stands on it",
                points.len() - above,
                points.len(),
                if plane.is_some() {
                    "on or below"
                } else {
                    "(none found)"
                },
                params.min_cluster_points,
                params.cluster_radius
            ),
        ));
    }
    let clusters = lists
        .into_iter()
        .map(|indices| {
            let (mut su, mut sv) = (0.0, 0.0);
            for &i in &indices {
                let (u, v) = cloud.pixel(i);
                su += u as f64;
                sv += v as f64;
            }
            let n = indices.len() as f64;
            Cluster {
                indices,
                pixel_centroid: (su / n, sv / n),
            }
        })
        .collect();
    Ok((plane, clusters))
}

impl Segmentation {
    /// The segmentation with `clusters[target]` as the target object.
    pub fn with_target(
        cloud: &PixelCloud,
        plane: Option<Plane>,
        clusters: Vec<Cluster>,
        target: usize,
        choice: TargetChoice,
    ) -> Self {
        let c = &clusters[target];
        let points = &cloud.cloud.points;
        let object = PointCloud::new(c.indices.iter().map(|&i| points[i]).collect());
        let object_pixels: Vec<u32> = c.indices.iter().map(|&i| cloud.pixels[i]).collect();
        let mut mask = vec![false; cloud.width * cloud.height];
        for &p in &object_pixels {
            mask[p as usize] = true;
        }
        Self {
            plane,
            clusters,
            target,
            choice,
            object,
            object_pixels,
            mask,
        }
    }
}

fn check_hint(hint: &TargetHint, w: usize, h: usize) -> Result<(), FieldError> {
    match *hint {
        TargetHint::Auto => Ok(()),
        TargetHint::Object(_) => Ok(()),
        TargetHint::Pixel { u, v } => {
            if (u as usize) < w && (v as usize) < h {
                Ok(())
            } else {
                Err(FieldError::new(
                    "hints.attention_pixel",
                    format!("({u}, {v}) lies outside the {w}×{h} image"),
                ))
            }
        }
        TargetHint::Region {
            u_min,
            v_min,
            u_max,
            v_max,
        } => {
            if u_min < u_max && v_min < v_max && u_max as usize <= w && v_max as usize <= h {
                Ok(())
            } else {
                Err(FieldError::new(
                    "hints.region",
                    format!(
                        "[{u_min}, {u_max}) × [{v_min}, {v_max}) is empty or not inside the \
                         {w}×{h} image"
                    ),
                ))
            }
        }
    }
}

/// The objects standing on the support plane: the plane (given, else found by RANSAC), the
/// Euclidean clusters of the points above it (indices into `points`, largest first) and how
/// many points lie above it.
pub fn objects_on_plane(
    points: &[Point3<f64>],
    support_plane: Option<Plane>,
    params: &SegmentationParams,
) -> (Option<Plane>, Vec<Vec<usize>>, usize) {
    let plane = support_plane.or_else(|| find_plane(points, params));
    let above: Vec<usize> = match &plane {
        Some(pl) => (0..points.len())
            .filter(|&i| pl.distance(&points[i]) > params.plane_margin)
            .collect(),
        None => (0..points.len()).collect(),
    };
    let lists = euclidean_clusters(
        points,
        &above,
        params.cluster_radius,
        params.min_cluster_points,
    );
    (plane, lists, above.len())
}

/// RANSAC on an even subsample, so that the cost does not grow with the resolution.
fn find_plane(points: &[Point3<f64>], params: &SegmentationParams) -> Option<Plane> {
    let stride = points.len().div_ceil(params.plane_sample.max(3)).max(1);
    let sample: Vec<Point3<f64>> = points.iter().step_by(stride).copied().collect();
    let min_remaining = (params.min_cluster_points / stride).max(8);
    detect_support_plane(&sample, params.ransac, params.seed, min_remaining).map(|f| f.plane)
}

fn choose_target(
    cloud: &PixelCloud,
    clusters: &[Cluster],
    hint: TargetHint,
    saliency: Option<&[f32]>,
) -> Result<(usize, TargetChoice), FieldError> {
    let argmax = |score: &dyn Fn(&Cluster) -> f64| {
        let mut best = (0, f64::NEG_INFINITY);
        for (k, c) in clusters.iter().enumerate() {
            let s = score(c);
            if s > best.1 {
                best = (k, s);
            }
        }
        best
    };
    match hint {
        TargetHint::Object(_) => Err(FieldError::new(
            "hints.object",
            "naming the object needs the recogniser, and graspd runs without one \
             (--recogniser-model none, or the model failed to load)",
        )),
        TargetHint::Pixel { u, v } => {
            let target = (v as usize * cloud.width + u as usize) as u32;
            let (k, _) = argmax(&|c: &Cluster| {
                let d2 = c
                    .indices
                    .iter()
                    .map(|&i| {
                        let p = cloud.pixels[i];
                        if p == target {
                            return 0;
                        }
                        let (pu, pv) = cloud.pixel(i);
                        let (du, dv) = (pu as i64 - u as i64, pv as i64 - v as i64);
                        du * du + dv * dv
                    })
                    .min()
                    .unwrap_or(i64::MAX);
                -(d2 as f64)
            });
            Ok((k, TargetChoice::Pixel))
        }
        TargetHint::Region {
            u_min,
            v_min,
            u_max,
            v_max,
        } => {
            let (k, n) = argmax(&|c: &Cluster| {
                c.indices
                    .iter()
                    .filter(|&&i| {
                        let (u, v) = cloud.pixel(i);
                        (u_min as usize..u_max as usize).contains(&u)
                            && (v_min as usize..v_max as usize).contains(&v)
                    })
                    .count() as f64
            });
            if n < 1.0 {
                return Err(FieldError::new(
                    "hints.region",
                    format!(
                        "no object in [{u_min}, {u_max}) × [{v_min}, {v_max}); the objects' \
                         pixel centroids are at {}",
                        clusters
                            .iter()
                            .map(|c| format!(
                                "({:.0}, {:.0})",
                                c.pixel_centroid.0, c.pixel_centroid.1
                            ))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ));
            }
            Ok((k, TargetChoice::Region))
        }
        TargetHint::Auto => match saliency {
            Some(map) => {
                let (k, _) = argmax(&|c: &Cluster| {
                    c.indices
                        .iter()
                        .map(|&i| map[cloud.pixels[i] as usize] as f64)
                        .sum::<f64>()
                        / c.indices.len() as f64
                });
                Ok((k, TargetChoice::Saliency))
            }
            None => {
                let (cu, cv) = (cloud.width as f64 / 2.0, cloud.height as f64 / 2.0);
                let (k, _) = argmax(&|c: &Cluster| {
                    -((c.pixel_centroid.0 - cu).powi(2) + (c.pixel_centroid.1 - cv).powi(2))
                });
                Ok((k, TargetChoice::ImageCentre))
            }
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::depth_to_cloud::CloudFrame;

    /// A synthetic organised cloud: a 64×48 image of a table z = 0 with two 16 cm boxes 4 cm
    /// tall at image columns 8–23 and 40–55 (rows 16–31), seen from above (1 pixel = 1 cm).
    fn scene() -> PixelCloud {
        let (w, h) = (64, 48);
        let mut points = Vec::new();
        let mut pixels = Vec::new();
        for v in 0..h {
            for u in 0..w {
                let on_box =
                    (16..32).contains(&v) && ((8..24).contains(&u) || (40..56).contains(&u));
                // A few holes (invalid depth) in the table.
                if (u * 7 + v * 3) % 29 == 0 && !on_box {
                    continue;
                }
                let z = if on_box { 0.04 } else { 0.0 };
                // Dense sampling: 4 points per pixel at 2.5 mm spacing keep 1 cm links.
                for k in 0..4 {
                    points.push(Point3::new(
                        u as f64 * 0.01 + (k % 2) as f64 * 0.005,
                        v as f64 * 0.01 + (k / 2) as f64 * 0.005,
                        z,
                    ));
                    pixels.push((v * w + u) as u32);
                }
            }
        }
        PixelCloud {
            cloud: PointCloud::new(points),
            pixels,
            width: w,
            height: h,
            frame: CloudFrame::World,
        }
    }

    fn params() -> SegmentationParams {
        SegmentationParams {
            min_cluster_points: 100,
            ..Default::default()
        }
    }

    #[test]
    fn removes_the_table_and_finds_two_boxes() {
        let s = segment(&scene(), TargetHint::Auto, None, None, &params()).unwrap();
        let pl = s.plane.unwrap();
        assert!(pl.normal.z > 0.999 && pl.offset.abs() < 1e-6, "{pl:?}");
        assert_eq!(s.clusters.len(), 2);
        assert_eq!(s.clusters[0].indices.len(), 16 * 16 * 4);
        assert_eq!(s.choice, TargetChoice::ImageCentre);
        assert!(s.object.points.iter().all(|p| (p.z - 0.04).abs() < 1e-12));
        assert_eq!(s.mask.iter().filter(|m| **m).count(), 256);
    }

    #[test]
    fn hints_pick_the_object() {
        let c = scene();
        let right = segment(
            &c,
            TargetHint::Pixel { u: 50, v: 20 },
            None,
            None,
            &params(),
        )
        .unwrap();
        assert_eq!(right.choice, TargetChoice::Pixel);
        assert!(right.object.centroid().x > 0.4);
        // A pixel on the table picks the nearest object.
        let near_left =
            segment(&c, TargetHint::Pixel { u: 2, v: 2 }, None, None, &params()).unwrap();
        assert!(near_left.object.centroid().x < 0.3);
        let region = TargetHint::Region {
            u_min: 20,
            v_min: 0,
            u_max: 64,
            v_max: 48,
        };
        let r = segment(&c, region, None, None, &params()).unwrap();
        assert!(r.object.centroid().x > 0.4);
        let empty = TargetHint::Region {
            u_min: 0,
            v_min: 40,
            u_max: 64,
            v_max: 48,
        };
        let e = segment(&c, empty, None, None, &params()).unwrap_err();
        assert_eq!(e.field, "hints.region");
        let outside = TargetHint::Pixel { u: 64, v: 0 };
        let e = segment(&c, outside, None, None, &params()).unwrap_err();
        assert_eq!(e.field, "hints.attention_pixel");
    }

    #[test]
    fn saliency_picks_the_most_salient_cluster() {
        let c = scene();
        let mut map = vec![0.1f32; 64 * 48];
        for v in 16..32 {
            for u in 40..56 {
                map[v * 64 + u] = 0.9;
            }
        }
        let s = segment(&c, TargetHint::Auto, Some(&map), None, &params()).unwrap();
        assert_eq!(s.choice, TargetChoice::Saliency);
        assert!(s.object.centroid().x > 0.4);
    }

    #[test]
    fn nothing_on_the_table_is_an_error() {
        let mut c = scene();
        for p in &mut c.cloud.points {
            p.z = 0.0;
        }
        let pl = Plane::checked(nalgebra::Vector3::z(), 0.0, "p").unwrap();
        let e = segment(&c, TargetHint::Auto, None, Some(pl), &params()).unwrap_err();
        assert_eq!(e.field, "rgbd.depth");
    }

    #[test]
    fn clusters_join_across_gaps_below_the_radius_only() {
        let line = |x0: f64, n: usize, dx: f64| -> Vec<Point3<f64>> {
            (0..n)
                .map(|i| Point3::new(x0 + i as f64 * dx, 0.0, 0.0))
                .collect()
        };
        let mut pts = line(0.0, 50, 0.002);
        pts.extend(line(0.098 + 0.006, 50, 0.002)); // 6 mm gap: joined
        pts.extend(line(0.5, 50, 0.002)); // far: separate
        let idx: Vec<usize> = (0..pts.len()).collect();
        let cl = euclidean_clusters(&pts, &idx, 0.01, 10);
        assert_eq!(cl.len(), 2);
        assert_eq!(cl[0].len(), 100);
        assert_eq!(cl[1].len(), 50);
        let cl = euclidean_clusters(&pts, &idx, 0.01, 60);
        assert_eq!(cl.len(), 1);
    }
}
