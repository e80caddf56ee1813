//! The grasp-relevant information Ω = {ROI, grasp type, attention point} of an RGB-D frame
//! (method.md §4, dissertation ch. 4.2 and 5.3.1), in the order the method computes it:
//!
//! 1. the VOCUS2 saliency map ([`super::saliency`]);
//! 2. depth to points, support-plane removal, object clusters and the target
//!    ([`super::segmentation`]: the caller's pixel or box, the object the recogniser takes for
//!    the caller's name ([`super::recognition`]), else the most salient object);
//! 3. the ROI: the mean-shift region of highest mean saliency, intersected with the target's
//!    pixels ([`super::roi`]);
//! 4. with a grasp-type model: the six probability maps, P(s|O) over the ROI (Eq 4.3), and the
//!    attention pixel by mean shift on the map of s* inside the ROI, back-projected onto the
//!    object ([`super::grasp_type`]). Without a model (or when it fails) the planner's
//!    geometric rule decides the type from the object's points.
//!
//! The caller's attention pixel, when given, is the attention point (its nearest object pixel),
//! whatever the model says.

use super::depth_to_cloud::{CloudFrame, depth_to_cloud};
use super::grasp_type::{
    GraspTypeModel, TypeMaps, attention_pixel, choose_type, type_probabilities,
};
use super::recognition::{NotFound, RecognisedObject, RecognitionModel, find_named, recognise};
use super::rgbd::DecodedFrame;
use super::roi::{RegionParams, mask_box, region_of_interest, salient_regions_near};
use super::saliency::{SaliencyParams, saliency_map};
use super::segmentation::{
    Segmentation, SegmentationParams, TargetChoice, TargetHint, segment, segment_objects,
};
use crate::GraspType;
use crate::cloud::{Plane, PointCloud};
use crate::error::{FieldError, PlanError};
use nalgebra::{Isometry3, Point3};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Parameters of [`grasp_information`].
#[derive(Debug, Clone, Copy, Default)]
pub struct InformationParams {
    pub saliency: SaliencyParams,
    pub segmentation: SegmentationParams,
    pub regions: RegionParams,
    /// Mean-shift bandwidth (Gaussian σ) of the attention point, pixels; 0 = 1/4 of the ROI
    /// box's shorter side (at least 4 px): narrower kernels stop anywhere on a saturated map's
    /// plateau.
    pub attention_bandwidth_px: f64,
}

/// The type decided by the grasp-type model.
#[derive(Debug, Clone)]
pub struct TypeDetection {
    /// P(s|O) for s = 1..6 (Eq 4.3).
    pub probabilities: [f64; 6],
    /// s*: the most probable type the hand realises.
    pub s_star: GraspType,
    /// The six maps (sigmoid probabilities, the model's output resolution).
    pub maps: TypeMaps,
}

/// The networks perception runs, where configured.
#[derive(Debug, Clone, Copy, Default)]
pub struct PerceptionModels<'a> {
    /// The grasp-type network (ch. 4.2.2); without it the planner's geometric rule decides.
    pub grasp_type: Option<&'a GraspTypeModel>,
    /// The recogniser (§3.2.1); without it `hints.object` is refused.
    pub recogniser: Option<&'a RecognitionModel>,
}

/// Seconds per step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct PerceptionTimings {
    /// Decoding and validating the frame (set by the caller that decoded it).
    pub decode: f64,
    pub saliency: f64,
    pub segmentation: f64,
    /// Running the recogniser on the objects in view (`hints.object` only; part of
    /// `segmentation` too).
    #[serde(default)]
    pub recognition: f64,
    pub roi: f64,
    pub grasp_type: f64,
    pub total: f64,
}

/// Ω and what led to it. Points are in the world frame when the frame has a camera-to-world
/// transform, else in the camera frame.
#[derive(Debug, Clone)]
pub struct GraspInformation {
    /// The target object's points.
    pub object: PointCloud,
    /// The support plane, when found or given.
    pub plane: Option<Plane>,
    /// Object clusters found.
    pub objects: usize,
    /// What the recogniser took each of them for (`hints.object` only), in cluster order.
    pub recognised: Vec<RecognisedObject>,
    pub target_choice: TargetChoice,
    /// The target's pixel mask (row-major, the frame's size).
    pub object_mask: Vec<bool>,
    /// The ROI mask (row-major) and its box [u_min, v_min, u_max, v_max).
    pub roi: Vec<bool>,
    pub roi_box: [u32; 4],
    pub roi_pixels: usize,
    /// The model's decision, when a model was given and ran.
    pub detection: Option<TypeDetection>,
    /// Why the model did not decide, when one was given.
    pub model_error: Option<String>,
    /// The attention pixel and its point on the object (from the caller's pixel or the model).
    pub attention_pixel: Option<(f64, f64)>,
    pub attention_point: Option<Point3<f64>>,
    /// The camera's position (normals face it).
    pub viewpoint: Point3<f64>,
    pub timings: PerceptionTimings,
}

/// Extracts Ω from a decoded frame (see the module docs). `models`: the networks configured;
/// `realisable`: the types the hand can realise (s* is chosen among them); `support_plane`: a
/// plane the caller knows, in the output frame.
///
/// Errors name the field: `hints.attention_pixel` / `hints.region` outside the image or on no
/// object, `rgbd.depth` when no object stands in view, `hints.object` (not found) for a name
/// the recogniser does not know or no object in view is taken for.
pub fn grasp_information(
    frame: &DecodedFrame,
    hint: TargetHint,
    support_plane: Option<Plane>,
    models: PerceptionModels<'_>,
    realisable: &[GraspType],
    params: &InformationParams,
) -> Result<GraspInformation, PlanError> {
    let t_start = Instant::now();
    let (w, h) = (frame.width, frame.height);
    if frame.valid_depth == 0 {
        return Err(FieldError::new(
            "rgbd.depth",
            "no pixel has a valid depth (all 0, NaN or infinite)",
        )
        .into());
    }

    let t = Instant::now();
    let saliency = saliency_map(&frame.rgb, w, h, &params.saliency);
    let t_saliency = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let cloud = depth_to_cloud(frame, CloudFrame::World);
    let mut recognised = Vec::new();
    let mut t_recognition = 0.0;
    let seg = match (&hint, models.recogniser) {
        (TargetHint::Object(name), Some(recogniser)) => {
            let (plane, clusters) = segment_objects(&cloud, support_plane, &params.segmentation)?;
            let t = Instant::now();
            recognised = recognise(recogniser, frame, &cloud, &clusters, plane.as_ref())
                .map_err(|e| FieldError::new("hints.object", e.to_string()))?;
            t_recognition = t.elapsed().as_secs_f64();
            let k = find_named(name, recogniser.classes(), &recognised)
                .map_err(|NotFound(e)| PlanError::NotFound(e))?;
            Segmentation::with_target(&cloud, plane, clusters, k, TargetChoice::Object)
        }
        _ => segment(
            &cloud,
            hint.clone(),
            Some(&saliency.data),
            support_plane,
            &params.segmentation,
        )?,
    };
    let t_segmentation = t.elapsed().as_secs_f64();

    let t = Instant::now();
    // Only the regions over the target matter (the ROI is one of them, intersected with it).
    let regions = salient_regions_near(&saliency, &params.regions, mask_box(&seg.mask, w));
    let roi = region_of_interest(&regions, w, h, Some(&seg.mask), &params.regions)
        .unwrap_or_else(|| seg.mask.clone());
    let roi_box = mask_box(&roi, w).unwrap_or([0, 0, 0, 0]);
    let roi_pixels = roi.iter().filter(|m| **m).count();
    let t_roi = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut model_error = None;
    let detection = match models.grasp_type {
        None => None,
        Some(m) => match m.infer(frame) {
            Ok(maps) => {
                let probabilities = type_probabilities(&maps, &roi, w, h);
                choose_type(&probabilities, realisable).map(|s_star| TypeDetection {
                    probabilities,
                    s_star,
                    maps,
                })
            }
            Err(e) => {
                model_error = Some(e.to_string());
                None
            }
        },
    };
    let pixel = match hint {
        TargetHint::Pixel { u, v } => Some((u as f64, v as f64)),
        _ => detection.as_ref().and_then(|d| {
            let side = (roi_box[2] - roi_box[0]).min(roi_box[3] - roi_box[1]) as f64;
            let bandwidth = if params.attention_bandwidth_px > 0.0 {
                params.attention_bandwidth_px
            } else {
                (side / 4.0).max(4.0)
            };
            attention_pixel(&d.maps, d.s_star, &roi, w, h, bandwidth)
        }),
    };
    let attention = pixel.map(|(u, v)| nearest_object_point(&seg, w, u, v));
    let t_type = t.elapsed().as_secs_f64();

    let viewpoint = frame
        .camera_to_world
        .as_ref()
        .map_or(Point3::origin(), |t: &Isometry3<f64>| t * Point3::origin());
    Ok(GraspInformation {
        object: seg.object,
        plane: seg.plane,
        objects: seg.clusters.len(),
        recognised,
        target_choice: seg.choice,
        object_mask: seg.mask,
        roi,
        roi_box,
        roi_pixels,
        detection,
        model_error,
        attention_pixel: attention.map(|(px, _)| px),
        attention_point: attention.map(|(_, p)| p),
        viewpoint,
        timings: PerceptionTimings {
            decode: 0.0,
            saliency: t_saliency,
            segmentation: t_segmentation,
            recognition: t_recognition,
            roi: t_roi,
            grasp_type: t_type,
            total: t_start.elapsed().as_secs_f64(),
        },
    })
}

/// The target's point whose pixel is nearest (u, v), and that pixel: the attention pixel
/// back-projected with the depth image (method.md §4), snapped onto the object so that an
/// attention pixel on the object's rim or on a depth hole still lands on it.
fn nearest_object_point(
    seg: &super::segmentation::Segmentation,
    width: usize,
    u: f64,
    v: f64,
) -> ((f64, f64), Point3<f64>) {
    let (k, _) = seg
        .object_pixels
        .iter()
        .enumerate()
        .map(|(k, &p)| {
            let (pu, pv) = ((p as usize % width) as f64, (p as usize / width) as f64);
            (k, (pu - u).powi(2) + (pv - v).powi(2))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
        .expect("segmentation returns non-empty objects");
    let p = seg.object_pixels[k] as usize;
    (
        ((p % width) as f64, (p / width) as f64),
        seg.object.points[k],
    )
}

/// The six probability maps as returned to a caller: `width × height` values per type, type-major
/// in the order s = 1..6, row-major.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProbabilityMaps {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f32>,
}

/// What perception found, as reported with a plan (RGB-D input).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PerceptionReport {
    /// The frame's size, pixels.
    pub width: usize,
    pub height: usize,
    /// ROI box [u_min, v_min, u_max, v_max) and its pixel count.
    pub roi: [u32; 4],
    pub roi_pixels: usize,
    pub target_source: TargetChoice,
    /// Object clusters in view and the target's points (with those further views added).
    pub objects: usize,
    pub object_points: usize,
    /// Further views fused ([`super::view_fusion`]) and the points they added.
    #[serde(default)]
    pub fused_views: usize,
    #[serde(default)]
    pub fused_points: usize,
    /// What the recogniser took each object in view for (`hints.object`).
    #[serde(default)]
    pub recognised: Vec<RecognisedObject>,
    /// The attention pixel (from the caller's pixel or the model), when there is one.
    pub attention_pixel: Option<[f64; 2]>,
    pub timings: PerceptionTimings,
    /// The model's maps downsampled, when the caller asked for them and a model ran.
    #[serde(default)]
    pub probability_maps: Option<ProbabilityMaps>,
    /// The overlay image (PNG), when the caller asked for it. Not part of the JSON plan: REST
    /// returns it as the body of `?format=png`.
    #[serde(skip)]
    pub overlay_png: Option<Vec<u8>>,
}

impl GraspInformation {
    /// The report of this information; `maps_max_side`: return the model's maps downsampled so
    /// that their longer side is at most this many pixels (0 = do not return them).
    pub fn report(&self, width: usize, height: usize, maps_max_side: usize) -> PerceptionReport {
        PerceptionReport {
            width,
            height,
            roi: self.roi_box,
            roi_pixels: self.roi_pixels,
            target_source: self.target_choice,
            objects: self.objects,
            object_points: self.object.len(),
            fused_views: 0,
            fused_points: 0,
            recognised: self.recognised.clone(),
            attention_pixel: self.attention_pixel.map(|(u, v)| [u, v]),
            timings: self.timings,
            probability_maps: self
                .detection
                .as_ref()
                .filter(|_| maps_max_side > 0)
                .map(|d| {
                    let m = d.maps.downsample(maps_max_side);
                    ProbabilityMaps {
                        width: m.width,
                        height: m.height,
                        values: m.probs,
                    }
                }),
            overlay_png: None,
        }
    }
}
