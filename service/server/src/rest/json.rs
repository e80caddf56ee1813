//! The one place that converts between the REST JSON and domain types. The JSON mirrors the proto
//! in snake_case; where the domain's own serde form is the documented one (hand descriptions,
//! planner options, grasp-type and hand-part names, the numeric report structs) it is used as
//! is, and the DTOs here cover what differs: clouds (arrays or base64), positions as
//! `{x, y, z}` (accepted as `[x, y, z]` too), poses and the response layout.

use super::schemas::{
    CollisionReportDoc, DetectorDoc, ElectrodePolarityDoc, FrameResultDoc, GraspTypeDoc,
    HandDescriptionDoc, HandPartDoc, LayoutDoc, PerceptionTimingsDoc, PidGainsDoc, PlaneSourceDoc,
    PlannerModeDoc, PlannerOptionsDoc, QualityDoc, StageStatsDoc, TargetChoiceDoc, TimingsDoc,
    TypeSourceDoc, Vec3InputDoc, Vec3ListDoc,
};
use crate::facade::RegisteredHand;
use crate::facade::{
    HandChoice, ImageHints, LayoutChoice, Limits, OutputOptions, PlanRequest, PlanSource,
    ServiceError, TactileFingerRequest, TactileSessionRequest,
};
use crate::hand_store::{Asset, HandUpload, ModelFormat, StoredOverrides};
use base64::Engine;
use graspd_core::cloud::{Plane, PointCloud, decode_packed_vec3};
use graspd_core::perception::{
    CameraIntrinsics, PerceptionReport, PerceptionTimings, RgbdFrame, TargetChoice, WireImage,
    camera_pose,
};
use graspd_core::planning::{
    CollisionReport, Contact, GraspCandidate, PlaneSource, PlannerMode, Pose, Quality, StageStats,
    Timings, TypeSource,
};
use graspd_core::tactile::{
    Baseline, DesiredForceLaw, DetectorChoice, ElectrodePolarity, FingerReading, Frame,
    FrameResult, LayoutSpec, ModelFreeThresholds, PidGains, StabilizerConfig, TareConfig,
};
use graspd_core::{
    FieldError, GraspPlan, GraspType, HandDescription, HandPart, PlanHints, PlannerOptions,
};
use nalgebra::{Point3, Quaternion, Vector3};
use serde::de::{self, DeserializeOwned, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};
use std::fmt;
use utoipa::{IntoParams, ToSchema};

// ---------------------------------------------------------------------------------------------
// Parsing with field paths

/// Parses JSON; errors name the field by its path (`hints.grasp_type`, `options.foo`), or
/// `root` (e.g. `body`) when the JSON itself is malformed.
/// The JSON must be an object (serde would also read a struct from an array).
pub fn parse<T: DeserializeOwned>(bytes: &[u8], root: &str) -> Result<T, FieldError> {
    match bytes.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => {}
        Some(_) => return Err(FieldError::new(root, "must be a JSON object")),
        None => return Err(FieldError::new(root, "is empty; expected a JSON object")),
    }
    let de = &mut serde_json::Deserializer::from_slice(bytes);
    let value = serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let top = path == "." || path == "?" || path.is_empty();
        // Truncated JSON is the body's fault, not the field's where it stopped.
        let syntax = e.inner().classify() == serde_json::error::Category::Eof;
        let message = e.inner().to_string();
        let mut field = if top || syntax {
            root.to_string()
        } else {
            path
        };
        // serde reports an unknown field at its parent; name the field itself.
        if let Some(rest) = message.strip_prefix("unknown field `")
            && let Some(name) = rest.split('`').next()
            && !field.ends_with(name)
        {
            field = if top {
                name.to_string()
            } else {
                format!("{field}.{name}")
            };
        }
        FieldError::new(field, message)
    })?;
    Ok(value)
}

// ---------------------------------------------------------------------------------------------
// Value types

/// A 3-D point or vector: written as `{x, y, z}`, read from that or from `[x, y, z]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct Vec3Json {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl From<&Point3<f64>> for Vec3Json {
    fn from(p: &Point3<f64>) -> Self {
        Self {
            x: p.x,
            y: p.y,
            z: p.z,
        }
    }
}

impl From<&Vector3<f64>> for Vec3Json {
    fn from(v: &Vector3<f64>) -> Self {
        Self {
            x: v.x,
            y: v.y,
            z: v.z,
        }
    }
}

impl Vec3Json {
    pub fn point(&self) -> Point3<f64> {
        Point3::new(self.x, self.y, self.z)
    }

    pub fn vector(&self) -> Vector3<f64> {
        Vector3::new(self.x, self.y, self.z)
    }
}

impl<'de> Deserialize<'de> for Vec3Json {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Vec3Json;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("[x, y, z] or {\"x\": .., \"y\": .., \"z\": ..}")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut s: A) -> Result<Vec3Json, A::Error> {
                let mut v = [0.0; 3];
                for (i, slot) in v.iter_mut().enumerate() {
                    *slot = s
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if s.next_element::<IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &self));
                }
                Ok(Vec3Json {
                    x: v[0],
                    y: v[1],
                    z: v[2],
                })
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Vec3Json, A::Error> {
                let mut v = [None; 3];
                while let Some(key) = m.next_key::<String>()? {
                    let i = match key.as_str() {
                        "x" => 0,
                        "y" => 1,
                        "z" => 2,
                        other => return Err(de::Error::unknown_field(other, &["x", "y", "z"])),
                    };
                    v[i] = Some(m.next_value()?);
                }
                let get =
                    |i: usize, n: &'static str| v[i].ok_or_else(|| de::Error::missing_field(n));
                Ok(Vec3Json {
                    x: get(0, "x")?,
                    y: get(1, "y")?,
                    z: get(2, "z")?,
                })
            }
        }
        d.deserialize_any(V)
    }
}

/// A rotation as a unit quaternion (x, y, z, w).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct QuaternionJson {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct PoseJson {
    #[schema(value_type = Vec3InputDoc)]
    pub position: Vec3Json,
    pub orientation: QuaternionJson,
}

impl From<&Pose> for PoseJson {
    fn from(p: &Pose) -> Self {
        let q = p.orientation;
        Self {
            position: (&p.position).into(),
            orientation: QuaternionJson {
                x: q.i,
                y: q.j,
                z: q.k,
                w: q.w,
            },
        }
    }
}

/// The plane n·x + offset = 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct PlaneJson {
    #[schema(value_type = Vec3InputDoc)]
    pub normal: Vec3Json,
    pub offset: f64,
}

impl From<&Plane> for PlaneJson {
    fn from(p: &Plane) -> Self {
        Self {
            normal: (&p.normal).into(),
            offset: p.offset,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Request

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
    #[serde(default)]
    pub most_salient: bool,
}

/// `POST /v1/plan`: the PlanGraspRequest in JSON. In a multipart upload the `request` part has
/// the same shape without `cloud`.
#[derive(Debug, Clone, Default, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct PlanRequestJson {
    #[serde(default)]
    pub cloud: Option<CloudJson>,
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

/// A box in image pixels, [u_min, u_max) × [v_min, v_max).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct RegionJson {
    pub u_min: u32,
    pub v_min: u32,
    pub u_max: u32,
    pub v_max: u32,
}

/// What to return besides the plan.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputJson {
    #[serde(default)]
    pub probability_maps_max_side: u32,
    #[serde(default)]
    pub overlay: bool,
}

/// One image of an RGB-D frame: `data` base64 (absent when a multipart part carries it).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ImageJson {
    #[serde(default)]
    pub width: u32,
    #[serde(default)]
    pub height: u32,
    /// rgb8, bgr8, png, jpeg (colour); 16UC1, 32FC1, png (depth). May be left out for a
    /// multipart PNG / JPEG part.
    #[serde(default)]
    pub encoding: String,
    #[serde(default)]
    pub step: u32,
    #[serde(default)]
    pub data: Option<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct IntrinsicsJson {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
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
        step: img.step,
        data,
    })
}

/// The frame as received (`field` names it: `rgbd`, `extra_views[i]`); sizes and encodings are
/// checked here, pixels by the facade.
fn rgbd_from_json(f: RgbdJson, parts: ImageParts, field: &str) -> Result<RgbdFrame, FieldError> {
    let color = wire_image(f.color, parts.color, &format!("{field}.color"))?;
    let depth = wire_image(f.depth, parts.depth, &format!("{field}.depth"))?;
    let k = f.intrinsics.ok_or_else(|| {
        FieldError::new(
            format!("{field}.intrinsics"),
            "is required (fx, fy, cx, cy)",
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
        CameraIntrinsics {
            fx: k.fx,
            fy: k.fy,
            cx: k.cx,
            cy: k.cy,
        },
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
    if n > limits.max_points {
        return Err(ServiceError::TooLarge(FieldError::new(
            field,
            format!(
                "{n} points exceed the configured limit of {} (max_points)",
                limits.max_points
            ),
        )));
    }
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
    let source = match (r.cloud, r.rgbd, file_cloud) {
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
        (Some(c), None, None) => PlanSource::Cloud(cloud_from_json(c, limits)?),
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
    };
    let image_hints = ImageHints {
        attention_pixel: h.attention_pixel.map(|p| (p.u, p.v)),
        region: h.region.map(|r| [r.u_min, r.v_min, r.u_max, r.v_max]),
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
        },
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
}

/// The grasp-type model's maps: `values` is base64 of 6 × height × width little-endian float32
/// (type-major in the order s = 1..6, row-major), as in the proto.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ProbabilityMapsJson {
    pub width: usize,
    pub height: usize,
    pub values: String,
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
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Tactile stabilization

/// A finger's layout: a built-in name (`"biotac"`, `"biotac_sp"`) or
/// `{"name": .., "electrodes": [[x_mm, y_mm], …]}`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum LayoutJson {
    Name(String),
    Custom(LayoutSpec),
}

/// Taring, as in the proto's TareSettings: default the mean of the first 50 frames, falling
/// electrodes; `pretared: true` for already tared data (electrodes rising unless given).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct TareJson {
    #[serde(default)]
    pub baseline_frames: Option<usize>,
    #[serde(default)]
    pub pretared: bool,
    #[serde(default)]
    #[schema(value_type = Option<ElectrodePolarityDoc>)]
    pub electrode_polarity: Option<ElectrodePolarity>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct TactileFingerJson {
    pub name: String,
    #[schema(value_type = LayoutDoc)]
    pub layout: LayoutJson,
    #[serde(default)]
    pub tare: Option<TareJson>,
}

/// `{"model_free": {thresholds…}}` or `{"model": "name"}`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum DetectorJson {
    ModelFree(ModelFreeThresholds),
    Model(String),
}

/// The session-opening message (the proto's TactileSession in JSON); unset fields take the
/// defaults.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct TactileSessionJson {
    pub fingers: Vec<TactileFingerJson>,
    #[serde(default)]
    pub window_length: Option<usize>,
    #[serde(default)]
    pub stride: Option<usize>,
    #[serde(default)]
    pub f0: Option<f64>,
    #[serde(default)]
    pub delta_material: Option<f64>,
    #[serde(default)]
    pub delta_slip: Option<f64>,
    #[serde(default)]
    pub f_min: Option<f64>,
    #[serde(default)]
    pub f_max: Option<f64>,
    /// Unset gains keep their defaults.
    #[serde(default)]
    #[schema(value_type = Option<PidGainsDoc>)]
    pub pid: Option<PidGains>,
    #[serde(default)]
    pub alpha: Option<f64>,
    #[serde(default)]
    pub calibration_gain: Option<f64>,
    #[serde(default)]
    #[schema(value_type = Option<DetectorDoc>)]
    pub detector: Option<DetectorJson>,
}

/// pac as one number or the driver's samples.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(untagged)]
pub enum PacJson {
    One(f64),
    Samples(Vec<f64>),
}

#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct FingerReadingJson {
    pub pdc: f64,
    pub pac: PacJson,
    pub tdc: f64,
    pub tac: f64,
    pub electrodes: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct TactileFrameJson {
    pub timestamp: f64,
    pub fingers: Vec<FingerReadingJson>,
}

/// `POST /v1/tactile/analyze` with a JSON body.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct AnalyzeRequestJson {
    pub session: TactileSessionJson,
    pub frames: Vec<TactileFrameJson>,
}

/// `POST /v1/tactile/analyze` with a CSV body: the session of one finger as query parameters.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, IntoParams)]
#[serde(deny_unknown_fields)]
#[into_params(parameter_in = Query)]
pub struct AnalyzeCsvQuery {
    /// Finger name [finger].
    #[serde(default)]
    pub finger: Option<String>,
    /// Built-in layout [biotac].
    #[serde(default)]
    pub layout: Option<String>,
    #[serde(default)]
    pub pretared: bool,
    #[serde(default)]
    pub baseline_frames: Option<usize>,
    #[serde(default)]
    #[param(value_type = Option<ElectrodePolarityDoc>)]
    pub electrode_polarity: Option<ElectrodePolarity>,
    #[serde(default)]
    pub window_length: Option<usize>,
    #[serde(default)]
    pub stride: Option<usize>,
    #[serde(default)]
    pub f0: Option<f64>,
    #[serde(default)]
    pub delta_material: Option<f64>,
    #[serde(default)]
    pub delta_slip: Option<f64>,
    #[serde(default)]
    pub f_min: Option<f64>,
    #[serde(default)]
    pub f_max: Option<f64>,
    #[serde(default)]
    pub kp: Option<f64>,
    #[serde(default)]
    pub ki: Option<f64>,
    #[serde(default)]
    pub kd: Option<f64>,
    #[serde(default)]
    pub alpha: Option<f64>,
    #[serde(default)]
    pub calibration_gain: Option<f64>,
}

impl AnalyzeCsvQuery {
    pub fn session(self) -> TactileSessionJson {
        let pid = (self.kp.is_some() || self.ki.is_some() || self.kd.is_some()).then(|| {
            let d = PidGains::default();
            PidGains {
                kp: self.kp.unwrap_or(d.kp),
                ki: self.ki.unwrap_or(d.ki),
                kd: self.kd.unwrap_or(d.kd),
                ..d
            }
        });
        TactileSessionJson {
            fingers: vec![TactileFingerJson {
                name: self.finger.unwrap_or_else(|| "finger".into()),
                layout: LayoutJson::Name(self.layout.unwrap_or_else(|| "biotac".into())),
                tare: Some(TareJson {
                    baseline_frames: self.baseline_frames,
                    pretared: self.pretared,
                    electrode_polarity: self.electrode_polarity,
                }),
            }],
            window_length: self.window_length,
            stride: self.stride,
            f0: self.f0,
            delta_material: self.delta_material,
            delta_slip: self.delta_slip,
            f_min: self.f_min,
            f_max: self.f_max,
            pid,
            alpha: self.alpha,
            calibration_gain: self.calibration_gain,
            detector: None,
        }
    }
}

fn tare_from_json(t: Option<TareJson>) -> TareConfig {
    let Some(t) = t else {
        return TareConfig::default();
    };
    let d = TareConfig::default();
    TareConfig {
        baseline: if t.pretared {
            Baseline::None
        } else {
            match d.baseline {
                Baseline::FirstFrames(n) => Baseline::FirstFrames(t.baseline_frames.unwrap_or(n)),
                Baseline::None => Baseline::None,
            }
        },
        electrode_polarity: t.electrode_polarity.unwrap_or(if t.pretared {
            ElectrodePolarity::Rising
        } else {
            ElectrodePolarity::Falling
        }),
    }
}

pub fn tactile_session_from_json(s: TactileSessionJson) -> TactileSessionRequest {
    let d = StabilizerConfig::default();
    TactileSessionRequest {
        fingers: s
            .fingers
            .into_iter()
            .map(|f| TactileFingerRequest {
                name: f.name,
                layout: match f.layout {
                    LayoutJson::Name(n) => LayoutChoice::Name(n),
                    LayoutJson::Custom(spec) => LayoutChoice::Custom(spec),
                },
                tare: tare_from_json(f.tare),
            })
            .collect(),
        config: StabilizerConfig {
            fingers: Vec::new(),
            window_length: s.window_length.unwrap_or(d.window_length),
            stride: s.stride.unwrap_or(d.stride),
            law: DesiredForceLaw {
                f0: s.f0.unwrap_or(d.law.f0),
                delta_material: s.delta_material.unwrap_or(d.law.delta_material),
                delta_slip: s.delta_slip.unwrap_or(d.law.delta_slip),
                f_min: s.f_min.unwrap_or(d.law.f_min),
                f_max: s.f_max.unwrap_or(d.law.f_max),
            },
            pid: s.pid.unwrap_or(d.pid),
            alpha: s.alpha.unwrap_or(d.alpha),
            calibration_gain: s.calibration_gain,
            detector: match s.detector {
                None => d.detector,
                Some(DetectorJson::ModelFree(t)) => DetectorChoice::ModelFree(t),
                Some(DetectorJson::Model(n)) => DetectorChoice::Model(n),
            },
        },
    }
}

pub fn tactile_frame_from_json(f: TactileFrameJson) -> Frame {
    Frame {
        timestamp: f.timestamp,
        fingers: f
            .fingers
            .into_iter()
            .map(|r| FingerReading {
                pdc: r.pdc,
                pac: match r.pac {
                    PacJson::One(v) => vec![v],
                    PacJson::Samples(v) => v,
                },
                tdc: r.tdc,
                tac: r.tac,
                electrodes: r.electrodes,
            })
            .collect(),
    }
}

/// The answer of `POST /v1/tactile/analyze`: one result per frame, in the domain's serde form
/// (the fields of the proto's StabilizationSetpoint / FingerSetpoint; enums as snake_case names,
/// probabilities and locations as arrays, absent values as null).
#[derive(Debug, Clone, Serialize, ToSchema)]
pub struct AnalyzeResponseJson {
    pub frame_count: usize,
    #[schema(value_type = Vec<FrameResultDoc>)]
    pub frames: Vec<FrameResult>,
}

/// One message of the `GET /v1/stabilize` WebSocket (the proto's StabilizeRequest in JSON):
/// `{"session": {…}}` first, then `{"frame": {…}}`.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct StabilizeMessageJson {
    #[serde(default)]
    pub session: Option<TactileSessionJson>,
    #[serde(default)]
    pub frame: Option<TactileFrameJson>,
}

/// The WebSocket's answer to one frame (the proto's StabilizationSetpoint in JSON): the frame's
/// 0-based index and its result, with the fields of an analyze result.
#[derive(Debug, Clone, Serialize)]
pub struct SetpointJson {
    pub frame_index: u64,
    #[serde(flatten)]
    pub result: FrameResult,
}

/// `GET /v1/hands`.
#[derive(Debug, Clone, Serialize, Deserialize, ToSchema)]
pub struct HandsJson {
    #[schema(value_type = Vec<HandDescriptionDoc>)]
    pub hands: Vec<HandDescription>,
}

/// `GET /v1/hands/{name}`.
#[derive(Debug, Clone, Serialize, Deserialize, ToSchema)]
pub struct HandJson {
    #[schema(value_type = HandDescriptionDoc)]
    pub hand: HandDescription,
    #[schema(value_type = Vec<GraspTypeDoc>)]
    pub realisable_types: Vec<GraspType>,
}

impl From<HandDescription> for HandJson {
    fn from(hand: HandDescription) -> Self {
        Self {
            realisable_types: hand.realisable_types(),
            hand,
        }
    }
}

/// The error body of every non-2xx answer.
#[derive(Debug, Clone, Serialize, Deserialize, ToSchema)]
pub struct ErrorJson {
    pub error: ErrorDetailJson,
}

#[derive(Debug, Clone, Serialize, Deserialize, ToSchema)]
pub struct ErrorDetailJson {
    /// invalid_argument, not_found, payload_too_large, resource_exhausted, unimplemented,
    /// unsupported_media_type, websocket_required, internal.
    pub code: String,
    pub field: Option<String>,
    pub message: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> Limits {
        Limits::default()
    }

    #[test]
    fn unknown_fields_are_named_with_their_path() {
        let e =
            parse::<PlanRequestJson>(br#"{"hand_name":"shadow","bogus":1}"#, "body").unwrap_err();
        assert_eq!(e.field, "bogus");
        let e = parse::<PlanRequestJson>(br#"{"options":{"epsilonn":1}}"#, "body").unwrap_err();
        assert_eq!(e.field, "options.epsilonn");
        let e =
            parse::<PlanRequestJson>(br#"{"hints":{"grasp_type":"grab"}}"#, "body").unwrap_err();
        assert_eq!(e.field, "hints.grasp_type");
        let e = parse::<PlanRequestJson>(br#"{"cloud":{"points":[[1,2]]}}"#, "body").unwrap_err();
        assert!(e.field.starts_with("cloud.points"), "{}", e.field);
        let e = parse::<PlanRequestJson>(b"{not json", "body").unwrap_err();
        assert_eq!(e.field, "body");
    }

    #[test]
    fn clouds_as_arrays_or_base64() {
        let r: PlanRequestJson = parse(
            br#"{"cloud":{"points":[[0,0,0],[1,2,3]]},"hand_name":"shadow","hints":{"attention_point":{"x":1,"y":2,"z":3},"viewpoint":[0,0,1]}}"#,
            "body",
        )
        .unwrap();
        let req = plan_request_from_json(r, None, Default::default(), &limits()).unwrap();
        let PlanSource::Cloud(c) = &req.source else {
            panic!()
        };
        assert_eq!(c.points[1], Point3::new(1.0, 2.0, 3.0));
        assert_eq!(req.hints.attention_point, Some(Point3::new(1.0, 2.0, 3.0)));

        let packed = graspd_core::cloud::encode_packed_xyz(&[Point3::new(1.0, 2.0, 3.0)]);
        let b64 = base64::engine::general_purpose::STANDARD.encode(&packed[..11]);
        let body = format!(r#"{{"cloud":{{"points":"{b64}"}},"hand_name":"shadow"}}"#);
        let r: PlanRequestJson = parse(body.as_bytes(), "body").unwrap();
        let e = plan_request_from_json(r, None, Default::default(), &limits()).unwrap_err();
        assert_eq!(e.field(), Some("cloud.points"));
        assert!(e.to_string().contains("byte length 11"));
    }
}

// ---------------------------------------------------------------------------------------------
// Hand registration

/// One uploaded file of `POST /v1/hands` in JSON: its relative path and its bytes in base64.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct HandAssetJson {
    pub path: String,
    /// Standard base64 (proto3 JSON's encoding of bytes).
    pub data: String,
}

/// The robot description of `POST /v1/hands` (proto `HandModel`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct HandModelJson {
    /// "mjcf" or "urdf".
    #[serde(default)]
    pub format: String,
    /// The XML document.
    #[serde(default)]
    pub text: String,
    #[serde(default)]
    pub assets: Vec<HandAssetJson>,
    #[serde(default)]
    pub palm: Option<String>,
    #[serde(default)]
    pub fingertips: Vec<String>,
    #[serde(default)]
    pub thumb: Option<String>,
}

/// `POST /v1/hands` as JSON (proto `RegisterHandRequest`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct RegisterHandJson {
    #[serde(default)]
    pub name: String,
    #[serde(default)]
    pub replace: bool,
    pub model: Option<HandModelJson>,
    /// Parametric descriptions are not registered (answered 400, naming `hand`).
    #[serde(default)]
    #[schema(value_type = Option<Object>)]
    pub hand: Option<serde_json::Value>,
}

/// The answer of `POST /v1/hands` (201).
#[derive(Debug, Clone, Serialize, Deserialize, ToSchema)]
pub struct RegisteredHandJson {
    #[schema(value_type = HandDescriptionDoc)]
    pub hand: HandDescription,
    #[schema(value_type = Vec<GraspTypeDoc>)]
    pub realisable_types: Vec<GraspType>,
    pub joints: Vec<String>,
    pub persisted: bool,
}

impl From<RegisteredHand> for RegisteredHandJson {
    fn from(r: RegisteredHand) -> Self {
        Self {
            realisable_types: r.description.realisable_types(),
            hand: r.description,
            joints: r.joints,
            persisted: r.persisted,
        }
    }
}

/// Decodes the JSON registration; errors name the field.
pub fn register_request_from_json(r: RegisterHandJson) -> Result<(HandUpload, bool), FieldError> {
    let model = match r.model {
        Some(m) => {
            let format = ModelFormat::parse(&m.format, "model.format")?;
            let mut assets = Vec::with_capacity(m.assets.len());
            for (i, a) in m.assets.into_iter().enumerate() {
                let data = base64::engine::general_purpose::STANDARD
                    .decode(a.data.as_bytes())
                    .map_err(|e| {
                        FieldError::new(
                            format!("model.assets[{i}].data"),
                            format!("not base64: {e}"),
                        )
                    })?;
                assets.push(Asset { path: a.path, data });
            }
            let overrides = StoredOverrides::requested(m.palm, m.fingertips, m.thumb);
            Some((format, m.text, assets, overrides))
        }
        None => None,
    };
    let upload = HandUpload::from_request(r.name, r.hand.is_some(), model)?;
    Ok((upload, r.replace))
}
