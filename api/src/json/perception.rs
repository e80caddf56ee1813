//! The perception report of a plan from RGB-D input, and the grasp-type model's maps.

use super::values::RegionJson;
use crate::schemas::{PerceptionTimingsDoc, TargetChoiceDoc};
use base64::Engine;
use graspd_core::perception::{
    PerceptionReport, PerceptionTimings, RecognisedObject, TargetChoice,
};
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// The grasp-type model's maps: `values` is base64 of 6 × height × width little-endian float32
/// (type-major in the order s = 1..6, row-major), as in the proto.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ProbabilityMapsJson {
    pub width: usize,
    pub height: usize,
    pub values: String,
}

/// What the recogniser took one object in view for (`hints.object`), as in the proto.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct RecognisedObjectJson {
    /// The most probable class: a known object's name, or `unknown`.
    pub class_name: String,
    pub probability: f64,
    /// Mean pixel of the object.
    pub u: f64,
    pub v: f64,
    /// Its depth points.
    pub points: usize,
}

impl From<&RecognisedObject> for RecognisedObjectJson {
    fn from(o: &RecognisedObject) -> Self {
        Self {
            class_name: o.class.clone(),
            probability: o.probability,
            u: o.pixel_centroid[0],
            v: o.pixel_centroid[1],
            points: o.points,
        }
    }
}

/// The Perception message in JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct PerceptionJson {
    pub width: usize,
    pub height: usize,
    pub roi: RegionJson,
    pub roi_pixels: usize,
    #[schema(value_type = TargetChoiceDoc)]
    pub target_source: TargetChoice,
    pub objects: usize,
    pub object_points: usize,
    /// Further views fused (`extra_views`) and the object points they added.
    #[serde(default)]
    pub fused_views: usize,
    #[serde(default)]
    pub fused_points: usize,
    /// What the recogniser took each object in view for (with `hints.object`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub recognised: Vec<RecognisedObjectJson>,
    #[schema(value_type = PerceptionTimingsDoc)]
    pub timings: PerceptionTimings,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probability_maps: Option<ProbabilityMapsJson>,
}

impl From<&PerceptionReport> for PerceptionJson {
    fn from(r: &PerceptionReport) -> Self {
        let [u_min, v_min, u_max, v_max] = r.roi;
        Self {
            width: r.width,
            height: r.height,
            roi: RegionJson {
                u_min,
                v_min,
                u_max,
                v_max,
            },
            roi_pixels: r.roi_pixels,
            target_source: r.target_source,
            objects: r.objects,
            object_points: r.object_points,
            fused_views: r.fused_views,
            fused_points: r.fused_points,
            recognised: r
                .recognised
                .iter()
                .map(RecognisedObjectJson::from)
                .collect(),
            timings: r.timings,
            probability_maps: r.probability_maps.as_ref().map(|m| ProbabilityMapsJson {
                width: m.width,
                height: m.height,
                values: base64::engine::general_purpose::STANDARD.encode(
                    m.values
                        .iter()
                        .flat_map(|v| v.to_le_bytes())
                        .collect::<Vec<u8>>(),
                ),
            }),
        }
    }
}
