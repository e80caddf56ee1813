//! `POST /v1/plan`: the request (cloud or RGB-D, hints, options, output) and the response.

use super::perception::*;
use super::ros::*;
use super::values::*;
use crate::error::ServiceError;
use crate::limits::Limits;
use crate::request::{HandChoice, ImageHints, OutputOptions, PlanRequest, PlanSource};
use crate::schemas::{
    CollisionReportDoc, GraspTypeDoc, HandDescriptionDoc, HandPartDoc, LearnedQualityDoc,
    PlaneSourceDoc, PlannerModeDoc, PlannerOptionsDoc, QualityDoc, StageStatsDoc, TimingsDoc,
    TypeSourceDoc, Vec3InputDoc, Vec3ListDoc,
};
use base64::Engine;
use graspd_core::cloud::{Plane, PointCloud, decode_packed_vec3};
use graspd_core::perception::{CameraIntrinsics, RgbdFrame, WireImage, camera_pose};
use graspd_core::planning::parallel_grasp::ParallelGrasp;
use graspd_core::planning::{
    CollisionReport, Contact, GraspCandidate, LearnedQuality, PlaneSource, PlannerMode, Quality,
    StageStats, Timings, TypeSource,
};
use graspd_core::{
    FieldError, GraspPlan, GraspType, HandDescription, HandPart, PlanHints, PlannerOptions,
};
use nalgebra::{Point3, Quaternion, Vector3};
use serde::de::{self, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};
use std::fmt;
use utoipa::ToSchema;

/// Points as `[[x, y, z], …]` or as a base64 string of packed little-endian float32 triples.
#[derive(Debug, Clone, PartialEq)]
pub enum Vec3List {
    Values(Vec<[f64; 3]>),
    Packed(Vec<u8>),
}

impl<'de> Deserialize<'de> for Vec3List {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Vec3List;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an array of [x, y, z] or a base64 string of packed little-endian float32 x, y, z")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<Vec3List, E> {
                base64::engine::general_purpose::STANDARD
                    .decode(s)
                    .map(Vec3List::Packed)
                    .map_err(|e| E::custom(format!("invalid base64: {e}")))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut s: A) -> Result<Vec3List, A::Error> {
                let mut v = Vec::with_capacity(s.size_hint().unwrap_or(0).min(1 << 16));
                while let Some(p) = s.next_element::<[f64; 3]>()? {
                    v.push(p);
                }
                Ok(Vec3List::Values(v))
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct CloudJson {
    #[schema(value_type = Vec3ListDoc)]
    pub points: Vec3List,
    #[serde(default)]
    #[schema(value_type = Option<Vec3ListDoc>)]
    pub normals: Option<Vec3List>,
    /// Echoed by nobody yet; accepted for parity with the proto.
    #[serde(default)]
    pub frame_id: String,
}

#[derive(Debug, Clone, Default, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct HintsJson {
    #[serde(default)]
    #[schema(value_type = Option<GraspTypeDoc>)]
    pub grasp_type: Option<GraspType>,
    #[serde(default)]
    #[schema(value_type = Option<Vec3InputDoc>)]
    pub attention_point: Option<Vec3Json>,
    #[serde(default)]
    pub support_plane: Option<PlaneJson>,
    #[serde(default)]
    #[schema(value_type = Option<Vec3InputDoc>)]
    pub viewpoint: Option<Vec3Json>,
    #[serde(default)]
    #[schema(value_type = Option<Vec3InputDoc>)]
    pub up: Option<Vec3Json>,
    /// Image hints (RGB-D input only).
    #[serde(default)]
    pub attention_pixel: Option<PixelJson>,
    #[serde(default)]
    pub region: Option<RegionJson>,
    /// The object the recogniser takes for this name is the target (`"apple"`); not found:
    /// 404 naming the objects found.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub object: String,
    #[serde(default)]
    pub most_salient: bool,
    /// Realise this two-jaw grasp straight down instead of searching (ch. 3, g = {x, y, z, θ}).
    #[serde(default)]
    pub parallel_grasp: Option<ParallelGraspJson>,
}

/// A parallel-jaw grasp straight down: the jaws' centre and the direction they close along
/// (made horizontal).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ParallelGraspJson {
    #[schema(value_type = Vec3InputDoc)]
    pub centre: Vec3Json,
    #[schema(value_type = Vec3InputDoc)]
    pub axis: Vec3Json,
}

/// `POST /v1/plan`: the PlanGraspRequest in JSON. In a multipart upload the `request` part has
/// the same shape without `cloud`.
#[derive(Debug, Clone, Default, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct PlanRequestJson {
    #[serde(default)]
    pub cloud: Option<CloudJson>,
    /// A ROS `sensor_msgs/PointCloud2` as rosbridge writes it (`data` base64).
    #[serde(default)]
    pub cloud2: Option<PointCloud2Json>,
    /// RGB-D input (images as base64, or as the multipart parts `color` and `depth`).
    #[serde(default)]
    pub rgbd: Option<RgbdJson>,
    /// Further views of the scene, each with `camera_to_world` (images as base64): what they see
    /// of the target is added to the first view's points.
    #[serde(default)]
    pub extra_views: Vec<RgbdJson>,
    #[serde(default)]
    pub hand_name: Option<String>,
    #[serde(default)]
    #[schema(value_type = Option<HandDescriptionDoc>)]
    pub hand_description: Option<Box<HandDescription>>,
    #[serde(default)]
    #[schema(value_type = Option<PlannerOptionsDoc>)]
    pub options: Option<PlannerOptions>,
    #[serde(default)]
    pub hints: Option<HintsJson>,
    #[serde(default)]
    pub output: Option<OutputJson>,
}

/// What to return besides the plan.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputJson {
    #[serde(default)]
    pub probability_maps_max_side: u32,
    #[serde(default)]
    pub overlay: bool,
    /// Return the candidates also in the layout of `moveit_msgs/Grasp` (`moveit_grasps`).
    #[serde(default)]
    pub moveit_grasps: bool,
    /// The frame the plan is in, for the MoveIt grasps' headers; empty = the input cloud's.
    #[serde(default)]
    pub frame_id: String,
}

/// One image of an RGB-D frame: `data` base64 (absent when a multipart part carries it).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ImageJson {
    #[serde(default)]
    pub width: u32,
    #[serde(default)]
    pub height: u32,
    /// rgb8, bgr8, rgba8, bgra8, png, jpeg (colour); 16UC1, 32FC1, png (depth). May be left
    /// out for a multipart PNG / JPEG part.
    #[serde(default)]
    pub encoding: String,
    /// Multi-byte raw pixels (16UC1, 32FC1) are big-endian (ROS `is_bigendian`).
    #[serde(default)]
    pub is_bigendian: bool,
    #[serde(default)]
    pub step: u32,
    #[serde(default)]
    pub data: Option<String>,
}

/// fx, fy, cx, cy, or ROS `CameraInfo.K` as it is (`k`: 9 values, row-major), or both when
/// they agree.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct IntrinsicsJson {
    #[serde(default)]
    pub fx: f64,
    #[serde(default)]
    pub fy: f64,
    #[serde(default)]
    pub cx: f64,
    #[serde(default)]
    pub cy: f64,
    #[serde(default)]
    pub k: Vec<f64>,
}

/// The RgbdFrame in JSON.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct RgbdJson {
    #[serde(default)]
    pub color: ImageJson,
    #[serde(default)]
    pub depth: ImageJson,
    pub intrinsics: Option<IntrinsicsJson>,
    #[serde(default)]
    pub depth_scale: Option<f64>,
    #[serde(default)]
    pub camera_to_world: Option<PoseJson>,
}

/// Bytes of a multipart image part, which stand in for the JSON's base64 `data`.
#[derive(Debug, Clone, Default)]
pub struct ImageParts {
    pub color: Option<Vec<u8>>,
    pub depth: Option<Vec<u8>>,
}

/// An image of the JSON with its bytes: base64 `data` or the multipart part (one of them).
fn wire_image(img: ImageJson, part: Option<Vec<u8>>, field: &str) -> Result<WireImage, FieldError> {
    let data = match (img.data, part) {
        (Some(_), Some(_)) => {
            return Err(FieldError::new(
                format!("{field}.data"),
                "give the image either as base64 data or as a multipart part, not both",
            ));
        }
        (Some(b64), None) => base64::engine::general_purpose::STANDARD
            .decode(b64.as_bytes())
            .map_err(|e| FieldError::new(format!("{field}.data"), format!("not base64: {e}")))?,
        (None, Some(bytes)) => bytes,
        (None, None) => {
            return Err(FieldError::new(
                format!("{field}.data"),
                "is required (base64, or a multipart part)",
            ));
        }
    };
    Ok(WireImage {
        width: img.width,
        height: img.height,
        encoding: img.encoding,
        is_bigendian: img.is_bigendian,
        step: img.step,
        data,
    })
}

/// The frame as received (`field` names it: `rgbd`, `extra_views[i]`); sizes and encodings are
/// checked here, pixels by the facade.
pub(crate) fn rgbd_from_json(
    f: RgbdJson,
    parts: ImageParts,
    field: &str,
) -> Result<RgbdFrame, FieldError> {
    let color = wire_image(f.color, parts.color, &format!("{field}.color"))?;
    let depth = wire_image(f.depth, parts.depth, &format!("{field}.depth"))?;
    let k = f.intrinsics.ok_or_else(|| {
        FieldError::new(
            format!("{field}.intrinsics"),
            "is required (fx, fy, cx, cy, or k)",
        )
    })?;
    let camera_to_world = f
        .camera_to_world
        .map(|p| {
            let q = p.orientation;
            camera_pose(
                p.position.point(),
                Quaternion::new(q.w, q.x, q.y, q.z),
                &format!("{field}.camera_to_world"),
            )
        })
        .transpose()?;
    RgbdFrame::from_wire(
        color,
        depth,
        CameraIntrinsics::from_wire(k.fx, k.fy, k.cx, k.cy, &k.k, &format!("{field}.intrinsics"))?,
        f.depth_scale,
        camera_to_world,
        field,
    )
}

fn points_from_json(
    list: Vec3List,
    field: &str,
    limits: &Limits,
) -> Result<Vec<Vector3<f64>>, ServiceError> {
    let n = match &list {
        Vec3List::Values(v) => v.len(),
        Vec3List::Packed(b) => b.len() / 12,
    };
    limits.check_points(n as u64, field)?;
    Ok(match list {
        Vec3List::Values(v) => v
            .into_iter()
            .map(|p| Vector3::new(p[0], p[1], p[2]))
            .collect(),
        Vec3List::Packed(b) => decode_packed_vec3(&b, field)?,
    })
}

fn cloud_from_json(c: CloudJson, limits: &Limits) -> Result<PointCloud, ServiceError> {
    let points = points_from_json(c.points, "cloud.points", limits)?
        .into_iter()
        .map(Point3::from)
        .collect();
    let normals = c
        .normals
        .map(|n| points_from_json(n, "cloud.normals", limits))
        .transpose()?;
    Ok(PointCloud { points, normals })
}

/// Turns the JSON into a domain request. `file_cloud` is the cloud of a multipart upload, which
/// excludes one in the JSON.
pub fn plan_request_from_json(
    r: PlanRequestJson,
    file_cloud: Option<PointCloud>,
    image_parts: ImageParts,
    limits: &Limits,
) -> Result<PlanRequest, ServiceError> {
    if (image_parts.color.is_some() || image_parts.depth.is_some()) && r.rgbd.is_none() {
        return Err(FieldError::new(
            "rgbd",
            "the multipart upload has colour or depth parts but the request has no rgbd (give at least rgbd.intrinsics)",
        )
        .into());
    }
    let input_frame = match (&r.cloud, &r.cloud2) {
        (Some(c), _) => c.frame_id.clone(),
        (None, Some(c)) => c.header.frame_id.clone(),
        (None, None) => String::new(),
    };
    let cloud = match (r.cloud, r.cloud2) {
        (Some(_), Some(_)) => {
            return Err(FieldError::new("cloud2", "give either cloud or cloud2, not both").into());
        }
        (Some(c), None) => Some(cloud_from_json(c, limits)?),
        (None, Some(c)) => Some(cloud2_from_json(&c, limits)?),
        (None, None) => None,
    };
    let source = match (cloud, r.rgbd, file_cloud) {
        (Some(_), _, Some(_)) => {
            return Err(FieldError::new(
                "cloud",
                "give the cloud either as the file part or in the request JSON, not both",
            )
            .into());
        }
        (Some(_), Some(_), None) => {
            return Err(FieldError::new("rgbd", "give either cloud or rgbd, not both").into());
        }
        (None, Some(_), Some(_)) => {
            return Err(
                FieldError::new("rgbd", "give either a cloud file or rgbd, not both").into(),
            );
        }
        (None, Some(f), None) => {
            PlanSource::Rgbd(Box::new(rgbd_from_json(f, image_parts, "rgbd")?))
        }
        (Some(c), None, None) => PlanSource::Cloud(c),
        (None, None, Some(c)) => PlanSource::Cloud(c),
        (None, None, None) => {
            return Err(FieldError::new(
                "cloud",
                "give the input: a cloud (JSON or a multipart file part named cloud)",
            )
            .into());
        }
    };
    let hand = match (r.hand_name, r.hand_description) {
        (Some(_), Some(_)) => {
            return Err(FieldError::new(
                "hand_name",
                "give either hand_name or hand_description, not both",
            )
            .into());
        }
        (Some(n), None) => HandChoice::Name(n),
        (None, Some(h)) => HandChoice::Inline(h),
        (None, None) => {
            return Err(FieldError::new("hand_name", "give hand_name or hand_description").into());
        }
    };
    let h = r.hints.unwrap_or_default();
    let hints = PlanHints {
        grasp_type: h.grasp_type,
        attention_point: h.attention_point.map(|p| p.point()),
        support_plane: h.support_plane.map(|p| Plane {
            normal: p.normal.vector(),
            offset: p.offset,
        }),
        viewpoint: h.viewpoint.map(|p| p.point()),
        up: h.up.map(|p| p.vector()),
        detected_attention: None,
        detected_types: None,
        seen_from: Vec::new(),
        parallel_grasp: h.parallel_grasp.map(|g| ParallelGrasp {
            centre: g.centre.point(),
            axis: g.axis.vector(),
        }),
    };
    let image_hints = ImageHints {
        attention_pixel: h.attention_pixel.map(|p| (p.u, p.v)),
        region: h.region.map(|r| [r.u_min, r.v_min, r.u_max, r.v_max]),
        object: h.object.clone(),
        most_salient: h.most_salient,
    };
    let o = r.output.unwrap_or_default();
    // Further views carry their images as base64 (the multipart parts are the first view's).
    let extra_views = r
        .extra_views
        .into_iter()
        .enumerate()
        .map(|(i, f)| rgbd_from_json(f, ImageParts::default(), &format!("extra_views[{i}]")))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(PlanRequest {
        source,
        extra_views,
        hand,
        options: r.options.unwrap_or_default(),
        hints,
        image_hints,
        output: OutputOptions {
            probability_maps_max_side: o.probability_maps_max_side,
            overlay: o.overlay,
            moveit_grasps: o.moveit_grasps,
            frame_id: o.frame_id,
            scene_glb: false,
        }
        .in_frame(&input_frame),
    })
}

// ---------------------------------------------------------------------------------------------
// Response

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct PixelJson {
    pub u: u32,
    pub v: u32,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct AttentionJson {
    pub position: Vec3Json,
    pub normal: Vec3Json,
    /// The pixel, when the input was an image.
    pub pixel: Option<PixelJson>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct OppositionJson {
    #[schema(value_type = HandPartDoc)]
    pub h1: HandPart,
    #[schema(value_type = HandPartDoc)]
    pub h2: HandPart,
    #[schema(value_type = Vec<Vec3Json>, min_items = 2, max_items = 2)]
    pub points: [Vec3Json; 2],
    #[schema(value_type = Vec<Vec3Json>, min_items = 2, max_items = 2)]
    pub normals: [Vec3Json; 2],
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ContactJson {
    pub position: Vec3Json,
    pub normal: Vec3Json,
    pub finger: String,
    #[schema(value_type = HandPartDoc)]
    pub part: HandPart,
    pub point_index: usize,
    /// IK residual (m) for a hand with known kinematics; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ik_residual: Option<f64>,
    /// On the completed, unseen side (`point_index` is the visible point it completes).
    #[serde(default)]
    pub inferred: bool,
    /// Hands with kinematics: the body (link) of the model that touches.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub link: Option<String>,
}

impl From<&Contact> for ContactJson {
    fn from(c: &Contact) -> Self {
        Self {
            position: (&c.position).into(),
            normal: (&c.normal).into(),
            finger: c.finger.clone(),
            part: c.part,
            point_index: c.point_index,
            ik_residual: c.ik_residual,
            inferred: c.inferred,
            link: c.link.clone(),
        }
    }
}

fn joints_json(j: &[(String, f64)]) -> Vec<JointJson> {
    j.iter()
        .map(|(name, angle)| JointJson {
            name: name.clone(),
            angle: *angle,
        })
        .collect()
}

/// One ranked plan of `candidates`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct CandidateJson {
    pub contacts: Vec<ContactJson>,
    pub hand_pose: PoseJson,
    pub pregrasp_pose: PoseJson,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub root_pose: Option<PoseJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub approach: Option<Vec3Json>,
    pub joints: Vec<JointJson>,
    pub pregrasp_joints: Vec<JointJson>,
    pub squeeze_joints: Vec<JointJson>,
    #[schema(value_type = QualityDoc)]
    pub quality: Quality,
    pub feasible: bool,
    pub infeasible_reason: Option<String>,
}

impl From<&GraspCandidate> for CandidateJson {
    fn from(c: &GraspCandidate) -> Self {
        Self {
            contacts: c.contacts.iter().map(Into::into).collect(),
            hand_pose: (&c.hand_pose).into(),
            pregrasp_pose: (&c.pregrasp_pose).into(),
            root_pose: c.root_pose.as_ref().map(Into::into),
            approach: c.approach.as_ref().map(Into::into),
            joints: joints_json(&c.joints),
            pregrasp_joints: joints_json(&c.pregrasp_joints),
            squeeze_joints: joints_json(&c.squeeze_joints),
            quality: c.quality,
            feasible: c.feasible,
            infeasible_reason: c.infeasible_reason.clone(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct JointJson {
    pub name: String,
    pub angle: f64,
}

/// The PlanGraspResponse in JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct PlanResponseJson {
    pub hand: String,
    #[schema(value_type = GraspTypeDoc)]
    pub grasp_type: GraspType,
    #[schema(value_type = GraspTypeDoc)]
    pub requested_type: GraspType,
    #[schema(value_type = TypeSourceDoc)]
    pub type_source: TypeSource,
    /// In the order large_wrap, small_wrap, power, pinch, precision, tripod.
    #[schema(value_type = Vec<f64>, min_items = 6, max_items = 6)]
    pub type_probabilities: [f64; 6],
    pub attention: AttentionJson,
    pub opposition: OppositionJson,
    pub contacts: Vec<ContactJson>,
    pub hand_pose: PoseJson,
    pub pregrasp_pose: PoseJson,
    pub joints: Vec<JointJson>,
    /// The model's root frame at the planned joints (hands with kinematics only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub root_pose: Option<PoseJson>,
    /// Hands with kinematics: the pre-grasp opening and the squeeze (executed pre-grasp →
    /// `joints` → squeeze).
    #[serde(default)]
    pub pregrasp_joints: Vec<JointJson>,
    #[serde(default)]
    pub squeeze_joints: Vec<JointJson>,
    /// Unit direction from `pregrasp_pose` to `hand_pose`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub approach: Option<Vec3Json>,
    /// The best `options.candidates` distinct plans, ranked; the first is this plan.
    #[serde(default)]
    pub candidates: Vec<CandidateJson>,
    #[schema(value_type = QualityDoc)]
    pub quality: Quality,
    pub feasible: bool,
    pub infeasible_reason: Option<String>,
    #[schema(value_type = StageStatsDoc)]
    pub stage1: StageStats,
    #[schema(value_type = StageStatsDoc)]
    pub stage2: StageStats,
    #[schema(value_type = TimingsDoc)]
    pub timings: Timings,
    #[schema(value_type = CollisionReportDoc)]
    pub collision: CollisionReport,
    pub support_plane: Option<PlaneJson>,
    #[schema(value_type = PlaneSourceDoc)]
    pub plane_source: PlaneSource,
    pub points_used: usize,
    #[schema(value_type = PlannerModeDoc)]
    pub mode: PlannerMode,
    pub seed: u64,
    pub warnings: Vec<String>,
    /// Set for RGB-D input.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub perception: Option<PerceptionJson>,
    /// The candidates in the layout of `moveit_msgs/Grasp`, when `output.moveit_grasps` was set.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub moveit_grasps: Vec<MoveItGraspJson>,
    /// What the learned-quality search found (`options.mode = "learned_quality"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<LearnedQualityDoc>)]
    pub learned_quality: Option<LearnedQuality>,
}

impl From<&GraspPlan> for PlanResponseJson {
    fn from(p: &GraspPlan) -> Self {
        let o = &p.opposition;
        Self {
            hand: p.hand.clone(),
            grasp_type: p.grasp_type,
            requested_type: p.requested_type,
            type_source: p.type_source,
            type_probabilities: p.type_scores,
            attention: AttentionJson {
                position: (&p.attention_point).into(),
                normal: (&p.attention_normal).into(),
                pixel: p
                    .perception
                    .as_ref()
                    .and_then(|r| r.attention_pixel)
                    .map(|[u, v]| PixelJson {
                        u: u.round().max(0.0) as u32,
                        v: v.round().max(0.0) as u32,
                    }),
            },
            opposition: OppositionJson {
                h1: o.h1,
                h2: o.h2,
                points: [(&o.points[0]).into(), (&o.points[1]).into()],
                normals: [(&o.normals[0]).into(), (&o.normals[1]).into()],
            },
            contacts: p.contacts.iter().map(Into::into).collect(),
            hand_pose: (&p.hand_pose).into(),
            pregrasp_pose: (&p.pregrasp_pose).into(),
            root_pose: p.root_pose.as_ref().map(Into::into),
            joints: joints_json(&p.joints),
            pregrasp_joints: joints_json(&p.pregrasp_joints),
            squeeze_joints: joints_json(&p.squeeze_joints),
            approach: p.approach.as_ref().map(Into::into),
            candidates: p.candidates.iter().map(Into::into).collect(),
            quality: p.quality,
            feasible: p.feasible,
            infeasible_reason: p.infeasible_reason.clone(),
            stage1: p.stage1,
            stage2: p.stage2,
            timings: p.timings,
            collision: p.collision,
            support_plane: p.support_plane.as_ref().map(PlaneJson::from),
            plane_source: p.plane_source,
            points_used: p.points_used,
            mode: p.mode,
            seed: p.seed,
            warnings: p.warnings.clone(),
            perception: p.perception.as_ref().map(PerceptionJson::from),
            moveit_grasps: p.moveit_grasps.iter().map(MoveItGraspJson::from).collect(),
            learned_quality: p.learned_quality.clone(),
        }
    }
}
