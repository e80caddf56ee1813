//! The perception report of a PlanGrasp response (RGB-D input).

use graspd_core::FieldError;
use graspd_core::perception::{
    PerceptionReport, PerceptionTimings, ProbabilityMaps, RecognisedObject, TargetChoice,
};
use graspd_proto::v1 as pb;

pub fn perception_to_proto(r: &PerceptionReport) -> pb::Perception {
    let t = &r.timings;
    let [u_min, v_min, u_max, v_max] = r.roi;
    pb::Perception {
        width: r.width as u32,
        height: r.height as u32,
        roi: Some(pb::RegionBox {
            u_min,
            v_min,
            u_max,
            v_max,
        }),
        roi_pixels: r.roi_pixels as u64,
        target_source: r.target_source.name().into(),
        objects: r.objects as u32,
        object_points: r.object_points as u64,
        fused_views: r.fused_views as u32,
        fused_points: r.fused_points as u64,
        recognised: r
            .recognised
            .iter()
            .map(|o| pb::RecognisedObject {
                class_name: o.class.clone(),
                probability: o.probability,
                u: o.pixel_centroid[0],
                v: o.pixel_centroid[1],
                points: o.points as u64,
            })
            .collect(),
        timings: Some(pb::PerceptionTimings {
            decode: t.decode,
            saliency: t.saliency,
            segmentation: t.segmentation,
            recognition: t.recognition,
            roi: t.roi,
            grasp_type: t.grasp_type,
            total: t.total,
        }),
        probability_maps: r.probability_maps.as_ref().map(|m| pb::ProbabilityMaps {
            width: m.width as u32,
            height: m.height as u32,
            values: m.values.iter().flat_map(|v| v.to_le_bytes()).collect(),
        }),
    }
}

pub fn perception_from_proto(
    r: pb::Perception,
    overlay_png: Vec<u8>,
    attention_pixel: Option<[f64; 2]>,
) -> Result<PerceptionReport, FieldError> {
    let roi = r.roi.unwrap_or_default();
    let t = r.timings.unwrap_or_default();
    let maps = match r.probability_maps {
        None => None,
        Some(m) => {
            let n = 6 * m.width as usize * m.height as usize;
            if m.values.len() != 4 * n {
                return Err(FieldError::new(
                    "perception.probability_maps.values",
                    format!(
                        "{} bytes, expected {} for 6 × {}×{} float32",
                        m.values.len(),
                        4 * n,
                        m.width,
                        m.height
                    ),
                ));
            }
            Some(ProbabilityMaps {
                width: m.width as usize,
                height: m.height as usize,
                values: m
                    .values
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect(),
            })
        }
    };
    Ok(PerceptionReport {
        width: r.width as usize,
        height: r.height as usize,
        roi: [roi.u_min, roi.v_min, roi.u_max, roi.v_max],
        roi_pixels: r.roi_pixels as usize,
        target_source: TargetChoice::from_name(&r.target_source).ok_or_else(|| {
            FieldError::new(
                "perception.target_source",
                format!("unknown source '{}'", r.target_source),
            )
        })?,
        objects: r.objects as usize,
        object_points: r.object_points as usize,
        fused_views: r.fused_views as usize,
        fused_points: r.fused_points as usize,
        recognised: r
            .recognised
            .into_iter()
            .map(|o| RecognisedObject {
                class: o.class_name,
                probability: o.probability,
                pixel_centroid: [o.u, o.v],
                points: o.points as usize,
                probabilities: Vec::new(),
            })
            .collect(),
        attention_pixel,
        timings: PerceptionTimings {
            decode: t.decode,
            saliency: t.saliency,
            segmentation: t.segmentation,
            recognition: t.recognition,
            roi: t.roi,
            grasp_type: t.grasp_type,
            total: t.total,
        },
        probability_maps: maps,
        overlay_png: (!overlay_png.is_empty()).then_some(overlay_png),
    })
}
