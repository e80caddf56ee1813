//! The one place that converts between `graspd.v1` proto messages and domain types, both ways
//! (the server decodes requests and encodes plans; clients do the reverse). Decoding treats the
//! message as untrusted: every error names the offending field by its proto path.

use crate::facade::RegisteredHand;
use crate::facade::{
    HandChoice, ImageHints, LayoutChoice, Limits, OutputOptions, PlanRequest, PlanSource,
    ServiceError, TactileFingerRequest, TactileSessionRequest,
};
use crate::hand_store::{Asset, HandUpload, ModelFormat, StoredOverrides};
use graspd_core::cloud::{
    Plane, PointCloud, decode_packed_vec3, decode_packed_xyz, encode_packed_xyz,
};
use graspd_core::hand::{Finger, GraspRealisation, HandGeometry, TypeEquivalence};
use graspd_core::perception::{
    CameraIntrinsics, PerceptionReport, PerceptionTimings, ProbabilityMaps, RgbdFrame,
    TargetChoice, WireImage, camera_pose,
};
use graspd_core::planning::{
    CollisionReport, Contact, GraspCandidate, Opposition, PlaneSource, PlannerMode, Pose, Quality,
    StageStats, Timings, TypeSource,
};
use graspd_core::tactile::{
    Baseline, ContactEvent, ControlMode, DesiredForceLaw, DetectorChoice, ElectrodePolarity,
    FingerReading, FingerResult, ForceUnit, Frame, FrameResult, LayoutSpec, Material,
    ModelFreeThresholds, PidGains, StabilizerConfig, TareConfig,
};
use graspd_core::{
    FieldError, GraspPlan, GraspType, HandDescription, HandPart, PlanHints, PlannerOptions,
};
use graspd_proto::v1 as pb;
use graspd_proto::v1::plan_grasp_request::{Hand, Input};
use graspd_proto::v1::stabilize_request::Kind;
use graspd_proto::v1::tactile_detector::Kind as DetectorKind;
use graspd_proto::v1::tactile_finger::Layout as FingerLayout;
use nalgebra::{Point3, Quaternion, UnitQuaternion, Vector3};

// ---------------------------------------------------------------------------------------------
// Value types

pub fn vec3_to_proto(v: &Vector3<f64>) -> pb::Vec3 {
    pb::Vec3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

pub fn point_to_proto(p: &Point3<f64>) -> pb::Vec3 {
    vec3_to_proto(&p.coords)
}

pub fn vec3_from_proto(v: &pb::Vec3) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

fn point_from_proto(v: &pb::Vec3) -> Point3<f64> {
    Point3::new(v.x, v.y, v.z)
}

fn required<'a, T>(v: &'a Option<T>, field: &str) -> Result<&'a T, FieldError> {
    v.as_ref()
        .ok_or_else(|| FieldError::new(field, "is required"))
}

pub fn pose_to_proto(p: &Pose) -> pb::Pose {
    let q = p.orientation;
    pb::Pose {
        position: Some(point_to_proto(&p.position)),
        orientation: Some(pb::Quaternion {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        }),
    }
}

/// Reads a pose as sent by the server (the quaternion is taken as unit, unchanged).
pub fn pose_from_proto(p: &Option<pb::Pose>, field: &str) -> Result<Pose, FieldError> {
    let p = required(p, field)?;
    let position = point_from_proto(required(&p.position, &format!("{field}.position"))?);
    let q = required(&p.orientation, &format!("{field}.orientation"))?;
    Ok(Pose {
        position,
        orientation: UnitQuaternion::new_unchecked(Quaternion::new(q.w, q.x, q.y, q.z)),
    })
}

fn plane_to_proto(p: &Plane) -> pb::Plane {
    pb::Plane {
        normal: Some(vec3_to_proto(&p.normal)),
        offset: p.offset,
    }
}

fn plane_from_proto(p: &pb::Plane, field: &str) -> Result<Plane, FieldError> {
    let normal = required(&p.normal, &format!("{field}.normal"))?;
    Ok(Plane {
        normal: vec3_from_proto(normal),
        offset: p.offset,
    })
}

// ---------------------------------------------------------------------------------------------
// Enums

pub fn grasp_type_to_proto(t: GraspType) -> pb::GraspType {
    match t {
        GraspType::LargeWrap => pb::GraspType::LargeWrap,
        GraspType::SmallWrap => pb::GraspType::SmallWrap,
        GraspType::Power => pb::GraspType::Power,
        GraspType::Pinch => pb::GraspType::Pinch,
        GraspType::Precision => pb::GraspType::Precision,
        GraspType::Tripod => pb::GraspType::Tripod,
    }
}

/// `None` for GRASP_TYPE_UNSPECIFIED; an error for a value outside the enum.
pub fn grasp_type_from_proto(v: i32, field: &str) -> Result<Option<GraspType>, FieldError> {
    let t = pb::GraspType::try_from(v)
        .map_err(|_| FieldError::new(field, format!("unknown grasp type value {v}")))?;
    Ok(match t {
        pb::GraspType::Unspecified => None,
        pb::GraspType::LargeWrap => Some(GraspType::LargeWrap),
        pb::GraspType::SmallWrap => Some(GraspType::SmallWrap),
        pb::GraspType::Power => Some(GraspType::Power),
        pb::GraspType::Pinch => Some(GraspType::Pinch),
        pb::GraspType::Precision => Some(GraspType::Precision),
        pb::GraspType::Tripod => Some(GraspType::Tripod),
    })
}

fn required_grasp_type(v: i32, field: &str) -> Result<GraspType, FieldError> {
    grasp_type_from_proto(v, field)?.ok_or_else(|| FieldError::new(field, "must be set"))
}

pub fn hand_part_to_proto(p: HandPart) -> pb::HandPart {
    match p {
        HandPart::ThumbTip => pb::HandPart::Tt,
        HandPart::ThumbSurface => pb::HandPart::Ts,
        HandPart::FingerTip => pb::HandPart::Ft,
        HandPart::FingerSurface => pb::HandPart::Fs,
        HandPart::Palm => pb::HandPart::P,
    }
}

pub fn hand_part_from_proto(v: i32, field: &str) -> Result<HandPart, FieldError> {
    match pb::HandPart::try_from(v) {
        Ok(pb::HandPart::Tt) => Ok(HandPart::ThumbTip),
        Ok(pb::HandPart::Ts) => Ok(HandPart::ThumbSurface),
        Ok(pb::HandPart::Ft) => Ok(HandPart::FingerTip),
        Ok(pb::HandPart::Fs) => Ok(HandPart::FingerSurface),
        Ok(pb::HandPart::P) => Ok(HandPart::Palm),
        Ok(pb::HandPart::Unspecified) => Err(FieldError::new(field, "must be set")),
        Err(_) => Err(FieldError::new(
            field,
            format!("unknown hand part value {v}"),
        )),
    }
}

fn mode_to_proto(m: PlannerMode) -> pb::PlannerMode {
    match m {
        PlannerMode::DualStage => pb::PlannerMode::DualStage,
        PlannerMode::WithoutOpposition => pb::PlannerMode::WithoutOpposition,
    }
}

fn mode_from_proto(v: i32, field: &str) -> Result<PlannerMode, FieldError> {
    match pb::PlannerMode::try_from(v) {
        Ok(pb::PlannerMode::DualStage) => Ok(PlannerMode::DualStage),
        Ok(pb::PlannerMode::WithoutOpposition) => Ok(PlannerMode::WithoutOpposition),
        Err(_) => Err(FieldError::new(
            field,
            format!("unknown planner mode value {v}"),
        )),
    }
}

/// The API names of the type and plane sources ("request", "geometric_rule", …).
pub fn type_source_name(s: TypeSource) -> &'static str {
    match s {
        TypeSource::Request => "request",
        TypeSource::GeometricRule => "geometric_rule",
        TypeSource::Model => "model",
    }
}

fn type_source_from_name(s: &str) -> Result<TypeSource, FieldError> {
    match s {
        "request" => Ok(TypeSource::Request),
        "geometric_rule" => Ok(TypeSource::GeometricRule),
        "model" => Ok(TypeSource::Model),
        _ => Err(FieldError::new(
            "type_source",
            format!("unknown source '{s}'"),
        )),
    }
}

pub fn plane_source_name(s: PlaneSource) -> &'static str {
    match s {
        PlaneSource::Request => "request",
        PlaneSource::Detected => "detected",
        PlaneSource::None => "none",
    }
}

fn plane_source_from_name(s: &str) -> Result<PlaneSource, FieldError> {
    match s {
        "request" => Ok(PlaneSource::Request),
        "detected" => Ok(PlaneSource::Detected),
        "none" => Ok(PlaneSource::None),
        _ => Err(FieldError::new(
            "plane_source",
            format!("unknown source '{s}'"),
        )),
    }
}

// ---------------------------------------------------------------------------------------------
// Hands

pub fn hand_to_proto(h: &HandDescription) -> pb::HandDescription {
    let g = &h.geometry;
    pb::HandDescription {
        name: h.name.clone(),
        description: h.description.clone(),
        geometry: Some(pb::HandGeometry {
            palm_width: g.palm_width,
            palm_length: g.palm_length,
            palm_thickness: g.palm_thickness,
            max_aperture: g.max_aperture,
            min_aperture: g.min_aperture,
            max_height: g.max_height,
            finger_width: g.finger_width,
            max_polygon_area: g.max_polygon_area,
            max_finger_spread: g.max_finger_spread,
        }),
        fingers: h
            .fingers
            .iter()
            .map(|f| pb::Finger {
                name: f.name.clone(),
                thumb: f.thumb,
                parts: f
                    .parts
                    .iter()
                    .map(|p| hand_part_to_proto(*p) as i32)
                    .collect(),
                length: f.length,
                base: Some(pb::Vec3 {
                    x: f.base[0],
                    y: f.base[1],
                    z: f.base[2],
                }),
            })
            .collect(),
        grasp_types: h
            .grasp_types
            .iter()
            .map(|r| pb::GraspRealisation {
                r#type: grasp_type_to_proto(r.grasp_type) as i32,
                h1: r.h1.clone(),
                h2: r.h2.clone(),
            })
            .collect(),
        equivalent_types: h
            .equivalent_types
            .iter()
            .map(|e| pb::TypeEquivalence {
                r#type: grasp_type_to_proto(e.grasp_type) as i32,
                same_as: grasp_type_to_proto(e.same_as) as i32,
            })
            .collect(),
    }
}

/// Decodes a hand; `field` prefixes the error paths (e.g. `hand_description`). The facade
/// validates the values.
/// Decodes a RegisterHand request: the name, the model document and its assets, the
/// overrides; `replace`. Errors name the field.
pub fn register_request_from_proto(
    r: pb::RegisterHandRequest,
) -> Result<(HandUpload, bool), FieldError> {
    let model = match r.model {
        Some(m) => Some((
            ModelFormat::parse(&m.format, "model.format")?,
            m.text,
            m.assets
                .into_iter()
                .map(|a| Asset {
                    path: a.path,
                    data: a.data,
                })
                .collect(),
            StoredOverrides::requested(m.palm, m.fingertips, m.thumb),
        )),
        None => None,
    };
    let upload = HandUpload::from_request(r.name, r.hand.is_some(), model)?;
    Ok((upload, r.replace))
}

pub fn registered_to_proto(r: &RegisteredHand) -> pb::RegisterHandResponse {
    pb::RegisterHandResponse {
        hand: Some(hand_to_proto(&r.description)),
        joints: r.joints.clone(),
        persisted: r.persisted,
    }
}

pub fn hand_from_proto(h: pb::HandDescription, field: &str) -> Result<HandDescription, FieldError> {
    let g = required(&h.geometry, &format!("{field}.geometry"))?;
    let mut fingers = Vec::with_capacity(h.fingers.len());
    for (i, f) in h.fingers.into_iter().enumerate() {
        let at = format!("{field}.fingers[{i}]");
        let base = required(&f.base, &format!("{at}.base"))?;
        let parts = f
            .parts
            .iter()
            .map(|p| hand_part_from_proto(*p, &format!("{at}.parts")))
            .collect::<Result<_, _>>()?;
        fingers.push(Finger {
            name: f.name,
            thumb: f.thumb,
            parts,
            length: f.length,
            base: [base.x, base.y, base.z],
        });
    }
    let mut grasp_types = Vec::with_capacity(h.grasp_types.len());
    for (i, r) in h.grasp_types.into_iter().enumerate() {
        grasp_types.push(GraspRealisation {
            grasp_type: required_grasp_type(r.r#type, &format!("{field}.grasp_types[{i}].type"))?,
            h1: r.h1,
            h2: r.h2,
        });
    }
    let mut equivalent_types = Vec::with_capacity(h.equivalent_types.len());
    for (i, e) in h.equivalent_types.into_iter().enumerate() {
        let at = format!("{field}.equivalent_types[{i}]");
        equivalent_types.push(TypeEquivalence {
            grasp_type: required_grasp_type(e.r#type, &format!("{at}.type"))?,
            same_as: required_grasp_type(e.same_as, &format!("{at}.same_as"))?,
        });
    }
    Ok(HandDescription {
        name: h.name,
        description: h.description,
        geometry: HandGeometry {
            palm_width: g.palm_width,
            palm_length: g.palm_length,
            palm_thickness: g.palm_thickness,
            max_aperture: g.max_aperture,
            min_aperture: g.min_aperture,
            max_height: g.max_height,
            finger_width: g.finger_width,
            max_polygon_area: g.max_polygon_area,
            max_finger_spread: g.max_finger_spread,
        },
        fingers,
        grasp_types,
        equivalent_types,
    })
}

// ---------------------------------------------------------------------------------------------
// PlanGrasp request

fn count(v: Option<u32>, default: usize) -> usize {
    v.map_or(default, |v| v as usize)
}

fn weights(w: &Option<pb::ObjectiveWeights>, default: [f64; 2]) -> [f64; 2] {
    w.as_ref()
        .map_or(default, |w| [w.reachability, w.attention])
}

/// Unset fields take the planner's defaults.
pub fn options_from_proto(o: Option<pb::PlannerOptions>) -> Result<PlannerOptions, FieldError> {
    let d = PlannerOptions::default();
    let Some(o) = o else { return Ok(d) };
    Ok(PlannerOptions {
        seed: o.seed.unwrap_or(d.seed),
        mode: match o.mode {
            Some(m) => mode_from_proto(m, "options.mode")?,
            None => d.mode,
        },
        epsilon: o.epsilon.unwrap_or(d.epsilon),
        friction: o.friction.unwrap_or(d.friction),
        torsion_gamma: o.torsion_gamma.unwrap_or(d.torsion_gamma),
        stage1_weights: weights(&o.stage1_weights, d.stage1_weights),
        stage2_weights: weights(&o.stage2_weights, d.stage2_weights),
        iteration_fraction: o.iteration_fraction.unwrap_or(d.iteration_fraction),
        min_iterations: count(o.min_iterations, d.min_iterations),
        max_iterations: count(o.max_iterations, d.max_iterations),
        patience: count(o.patience, d.patience),
        restarts: count(o.restarts, d.restarts),
        lambda1: o.lambda1.or(d.lambda1),
        lambda2: o.lambda2.or(d.lambda2),
        opposition_candidates: count(o.opposition_candidates, d.opposition_candidates),
        contact_candidates: count(o.contact_candidates, d.contact_candidates),
        normals_k: count(o.normals_k, d.normals_k),
        pregrasp_distance: o.pregrasp_distance.unwrap_or(d.pregrasp_distance),
        friction_cone_edges: count(o.friction_cone_edges, d.friction_cone_edges),
        check_collisions: o.check_collisions.unwrap_or(d.check_collisions),
        detect_support_plane: o.detect_support_plane.unwrap_or(d.detect_support_plane),
        max_center_offset: o.max_center_offset.unwrap_or(d.max_center_offset),
        complete_unseen: o.complete_unseen.unwrap_or(d.complete_unseen),
        candidates: count(o.candidates, d.candidates),
        squeeze_depth: o.squeeze_depth.unwrap_or(d.squeeze_depth),
        final_candidates: count(o.final_candidates, d.final_candidates),
    })
}

fn saturate(v: usize) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

/// Sets only the fields that differ from the defaults, so the server's defaults apply to the rest.
pub fn options_to_proto(o: &PlannerOptions) -> pb::PlannerOptions {
    let d = PlannerOptions::default();
    fn diff<T: PartialEq + Copy>(v: T, d: T) -> Option<T> {
        (v != d).then_some(v)
    }
    let w = |v: [f64; 2], d: [f64; 2]| {
        (v != d).then_some(pb::ObjectiveWeights {
            reachability: v[0],
            attention: v[1],
        })
    };
    pb::PlannerOptions {
        seed: Some(o.seed),
        mode: diff(o.mode, d.mode).map(|m| mode_to_proto(m) as i32),
        epsilon: diff(o.epsilon, d.epsilon),
        friction: diff(o.friction, d.friction),
        torsion_gamma: diff(o.torsion_gamma, d.torsion_gamma),
        stage1_weights: w(o.stage1_weights, d.stage1_weights),
        stage2_weights: w(o.stage2_weights, d.stage2_weights),
        iteration_fraction: diff(o.iteration_fraction, d.iteration_fraction),
        min_iterations: diff(o.min_iterations, d.min_iterations).map(saturate),
        max_iterations: diff(o.max_iterations, d.max_iterations).map(saturate),
        patience: diff(o.patience, d.patience).map(saturate),
        restarts: diff(o.restarts, d.restarts).map(saturate),
        lambda1: o.lambda1,
        lambda2: o.lambda2,
        opposition_candidates: diff(o.opposition_candidates, d.opposition_candidates).map(saturate),
        contact_candidates: diff(o.contact_candidates, d.contact_candidates).map(saturate),
        normals_k: diff(o.normals_k, d.normals_k).map(saturate),
        pregrasp_distance: diff(o.pregrasp_distance, d.pregrasp_distance),
        friction_cone_edges: diff(o.friction_cone_edges, d.friction_cone_edges).map(saturate),
        check_collisions: diff(o.check_collisions, d.check_collisions),
        detect_support_plane: diff(o.detect_support_plane, d.detect_support_plane),
        max_center_offset: diff(o.max_center_offset, d.max_center_offset),
        complete_unseen: diff(o.complete_unseen, d.complete_unseen),
        candidates: diff(o.candidates, d.candidates).map(saturate),
        squeeze_depth: diff(o.squeeze_depth, d.squeeze_depth),
        final_candidates: diff(o.final_candidates, d.final_candidates).map(saturate),
    }
}

fn hints_from_proto(h: Option<pb::PlanHints>) -> Result<(PlanHints, ImageHints), FieldError> {
    let Some(h) = h else {
        return Ok(Default::default());
    };
    let hints = PlanHints {
        grasp_type: grasp_type_from_proto(h.grasp_type, "hints.grasp_type")?,
        attention_point: h.attention_point.as_ref().map(point_from_proto),
        support_plane: h
            .support_plane
            .as_ref()
            .map(|p| plane_from_proto(p, "hints.support_plane"))
            .transpose()?,
        viewpoint: h.viewpoint.as_ref().map(point_from_proto),
        up: h.up.as_ref().map(vec3_from_proto),
        detected_attention: None,
        detected_types: None,
        seen_from: Vec::new(),
    };
    let image = ImageHints {
        attention_pixel: h.attention_pixel.map(|p| (p.u, p.v)),
        region: h.region.map(|r| [r.u_min, r.v_min, r.u_max, r.v_max]),
        most_salient: h.most_salient,
    };
    Ok((hints, image))
}

/// The RGB-D frame as received (`field` names it: `rgbd`, `extra_views[i]`); sizes and
/// encodings are checked here, pixels by the facade.
fn rgbd_from_proto(f: pb::RgbdFrame, field: &str) -> Result<RgbdFrame, FieldError> {
    let wire = |i: Option<pb::Image>| {
        let i = i.unwrap_or_default();
        WireImage {
            width: i.width,
            height: i.height,
            encoding: i.encoding,
            step: i.step,
            data: i.data,
        }
    };
    let k = f.intrinsics.unwrap_or_default();
    let camera_to_world = match &f.camera_to_world {
        None => None,
        Some(p) => {
            let field = format!("{field}.camera_to_world");
            let position = point_from_proto(required(&p.position, &format!("{field}.position"))?);
            let q = required(&p.orientation, &format!("{field}.orientation"))?;
            Some(camera_pose(
                position,
                Quaternion::new(q.w, q.x, q.y, q.z),
                &field,
            )?)
        }
    };
    RgbdFrame::from_wire(
        wire(f.color),
        wire(f.depth),
        CameraIntrinsics {
            fx: k.fx,
            fy: k.fy,
            cx: k.cx,
            cy: k.cy,
        },
        Some(f.depth_scale),
        camera_to_world,
        field,
    )
}

/// Encodes a frame for the wire (clients).
fn rgbd_to_proto(f: &RgbdFrame) -> pb::RgbdFrame {
    let image = |encoding: String, data: &[u8], step: usize| pb::Image {
        width: f.width as u32,
        height: f.height as u32,
        encoding,
        step: step as u32,
        data: data.to_vec(),
    };
    pb::RgbdFrame {
        color: Some(image(
            f.color.encoding.to_string(),
            &f.color.data,
            f.color.step,
        )),
        depth: Some(image(
            f.depth.encoding.to_string(),
            &f.depth.data,
            f.depth.step,
        )),
        intrinsics: Some(pb::CameraIntrinsics {
            fx: f.intrinsics.fx,
            fy: f.intrinsics.fy,
            cx: f.intrinsics.cx,
            cy: f.intrinsics.cy,
        }),
        depth_scale: f.depth_scale.unwrap_or(0.0),
        camera_to_world: f.camera_to_world.as_ref().map(|t| {
            pose_to_proto(&Pose {
                position: Point3::from(t.translation.vector),
                orientation: t.rotation,
            })
        }),
    }
}

fn hints_to_proto(h: &PlanHints, image: &ImageHints) -> pb::PlanHints {
    pb::PlanHints {
        grasp_type: h
            .grasp_type
            .map_or(pb::GraspType::Unspecified, grasp_type_to_proto) as i32,
        attention_point: h.attention_point.as_ref().map(point_to_proto),
        support_plane: h.support_plane.as_ref().map(plane_to_proto),
        viewpoint: h.viewpoint.as_ref().map(point_to_proto),
        up: h.up.as_ref().map(vec3_to_proto),
        attention_pixel: image.attention_pixel.map(|(u, v)| pb::Pixel { u, v }),
        region: image
            .region
            .map(|[u_min, v_min, u_max, v_max]| pb::RegionBox {
                u_min,
                v_min,
                u_max,
                v_max,
            }),
        most_salient: image.most_salient,
    }
}

/// Decodes the packed cloud, refusing more points than the limit before allocating them.
fn cloud_from_proto(c: pb::PointCloud, limits: &Limits) -> Result<PointCloud, ServiceError> {
    let n = c.points.len() / 12;
    if n > limits.max_points {
        return Err(ServiceError::TooLarge(FieldError::new(
            "cloud.points",
            format!(
                "{n} points exceed the configured limit of {} (max_points)",
                limits.max_points
            ),
        )));
    }
    let points = decode_packed_xyz(&c.points, "cloud.points")?;
    let normals = if c.normals.is_empty() {
        None
    } else {
        Some(decode_packed_vec3(&c.normals, "cloud.normals")?)
    };
    Ok(PointCloud { points, normals })
}

/// Decodes a PlanGrasp request at the edge (the facade validates the values).
pub fn plan_request_from_proto(
    r: pb::PlanGraspRequest,
    limits: &Limits,
) -> Result<PlanRequest, ServiceError> {
    let source = match r.input {
        Some(Input::Cloud(c)) => PlanSource::Cloud(cloud_from_proto(c, limits)?),
        Some(Input::Rgbd(f)) => PlanSource::Rgbd(Box::new(rgbd_from_proto(f, "rgbd")?)),
        None => {
            return Err(FieldError::new("cloud", "give the input: a cloud (or rgbd)").into());
        }
    };
    let hand = match r.hand {
        Some(Hand::HandName(name)) => HandChoice::Name(name),
        Some(Hand::HandDescription(h)) => {
            HandChoice::Inline(Box::new(hand_from_proto(h, "hand_description")?))
        }
        None => {
            return Err(FieldError::new("hand_name", "give hand_name or hand_description").into());
        }
    };
    let options = options_from_proto(r.options)?;
    let (hints, image_hints) = hints_from_proto(r.hints)?;
    let o = r.output.unwrap_or_default();
    let extra_views = r
        .extra_views
        .into_iter()
        .enumerate()
        .map(|(i, f)| rgbd_from_proto(f, &format!("extra_views[{i}]")))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(PlanRequest {
        source,
        extra_views,
        hand,
        options,
        hints,
        image_hints,
        output: OutputOptions {
            probability_maps_max_side: o.probability_maps_max_side,
            overlay: o.overlay,
        },
    })
}

/// Encodes a request for the wire (clients).
pub fn plan_request_to_proto(r: &PlanRequest) -> pb::PlanGraspRequest {
    let input = match &r.source {
        PlanSource::Cloud(c) => Input::Cloud(pb::PointCloud {
            points: encode_packed_xyz(&c.points),
            normals: c
                .normals
                .as_ref()
                .map(|n| {
                    let as_points: Vec<Point3<f64>> = n.iter().map(|v| Point3::from(*v)).collect();
                    encode_packed_xyz(&as_points)
                })
                .unwrap_or_default(),
            frame_id: String::new(),
        }),
        PlanSource::Rgbd(f) => Input::Rgbd(rgbd_to_proto(f)),
    };
    let hand = match &r.hand {
        HandChoice::Name(n) => Hand::HandName(n.clone()),
        HandChoice::Inline(h) => Hand::HandDescription(hand_to_proto(h)),
    };
    pb::PlanGraspRequest {
        input: Some(input),
        hand: Some(hand),
        options: Some(options_to_proto(&r.options)),
        hints: Some(hints_to_proto(&r.hints, &r.image_hints)),
        output: Some(pb::OutputOptions {
            probability_maps_max_side: r.output.probability_maps_max_side,
            overlay: r.output.overlay,
        }),
        extra_views: r.extra_views.iter().map(rgbd_to_proto).collect(),
    }
}

// ---------------------------------------------------------------------------------------------
// PlanGrasp response

fn stage_to_proto(s: &StageStats) -> pb::StageStats {
    pb::StageStats {
        solution_space: s.solution_space,
        candidates: s.candidates as u64,
        iterations: s.iterations as u64,
        best_iteration: s.best_iteration as u64,
        evaluations: s.evaluations as u64,
        accepted: s.accepted as u64,
        restarts: s.restarts as u64,
        feasible_found: s.feasible_found,
        seconds: s.seconds,
    }
}

fn stage_from_proto(s: Option<pb::StageStats>) -> StageStats {
    let s = s.unwrap_or_default();
    StageStats {
        solution_space: s.solution_space,
        candidates: s.candidates as usize,
        iterations: s.iterations as usize,
        best_iteration: s.best_iteration as usize,
        evaluations: s.evaluations as usize,
        accepted: s.accepted as usize,
        restarts: s.restarts as usize,
        feasible_found: s.feasible_found,
        seconds: s.seconds,
    }
}

fn contact_to_proto(c: &Contact) -> pb::Contact {
    pb::Contact {
        position: Some(point_to_proto(&c.position)),
        normal: Some(vec3_to_proto(&c.normal)),
        finger: c.finger.clone(),
        part: hand_part_to_proto(c.part) as i32,
        point_index: c.point_index as u64,
        ik_residual: c.ik_residual,
        inferred: c.inferred,
        link: c.link.clone().unwrap_or_default(),
    }
}

fn contact_from_proto(c: &pb::Contact, at: &str) -> Result<Contact, FieldError> {
    Ok(Contact {
        position: point_from_proto(required(&c.position, &format!("{at}.position"))?),
        normal: vec3_from_proto(required(&c.normal, &format!("{at}.normal"))?),
        finger: c.finger.clone(),
        part: hand_part_from_proto(c.part, &format!("{at}.part"))?,
        point_index: c.point_index as usize,
        ik_residual: c.ik_residual,
        inferred: c.inferred,
        link: (!c.link.is_empty()).then(|| c.link.clone()),
    })
}

fn contacts_from_proto(cs: &[pb::Contact], field: &str) -> Result<Vec<Contact>, FieldError> {
    cs.iter()
        .enumerate()
        .map(|(i, c)| contact_from_proto(c, &format!("{field}[{i}]")))
        .collect()
}

fn joints_to_proto(j: &[(String, f64)]) -> Vec<pb::JointAngle> {
    j.iter()
        .map(|(name, angle)| pb::JointAngle {
            name: name.clone(),
            angle: *angle,
        })
        .collect()
}

fn joints_from_proto(j: Vec<pb::JointAngle>) -> Vec<(String, f64)> {
    j.into_iter().map(|j| (j.name, j.angle)).collect()
}

fn quality_to_proto(q: &Quality) -> pb::Quality {
    pb::Quality {
        gii: q.gii,
        reachability: q.reachability,
        attention: q.attention,
        objective: q.objective,
        epsilon: q.epsilon,
        aperture_or_area: q.aperture_or_area,
        palm_height: q.palm_height,
        robustness: q.robustness,
        gravity_resistance: q.gravity_resistance,
    }
}

fn quality_from_proto(q: pb::Quality) -> Quality {
    Quality {
        gii: q.gii,
        reachability: q.reachability,
        attention: q.attention,
        objective: q.objective,
        epsilon: q.epsilon,
        aperture_or_area: q.aperture_or_area,
        palm_height: q.palm_height,
        robustness: q.robustness,
        gravity_resistance: q.gravity_resistance,
    }
}

fn optional_pose_from_proto(p: &Option<pb::Pose>, field: &str) -> Result<Option<Pose>, FieldError> {
    match p {
        Some(_) => pose_from_proto(p, field).map(Some),
        None => Ok(None),
    }
}

fn candidate_to_proto(c: &GraspCandidate) -> pb::GraspCandidate {
    pb::GraspCandidate {
        contacts: c.contacts.iter().map(contact_to_proto).collect(),
        hand_pose: Some(pose_to_proto(&c.hand_pose)),
        pregrasp_pose: Some(pose_to_proto(&c.pregrasp_pose)),
        root_pose: c.root_pose.as_ref().map(pose_to_proto),
        approach: c.approach.as_ref().map(vec3_to_proto),
        joints: joints_to_proto(&c.joints),
        pregrasp_joints: joints_to_proto(&c.pregrasp_joints),
        squeeze_joints: joints_to_proto(&c.squeeze_joints),
        quality: Some(quality_to_proto(&c.quality)),
        feasible: c.feasible,
        infeasible_reason: c.infeasible_reason.clone(),
    }
}

fn candidate_from_proto(c: pb::GraspCandidate, at: &str) -> Result<GraspCandidate, FieldError> {
    Ok(GraspCandidate {
        contacts: contacts_from_proto(&c.contacts, &format!("{at}.contacts"))?,
        hand_pose: pose_from_proto(&c.hand_pose, &format!("{at}.hand_pose"))?,
        pregrasp_pose: pose_from_proto(&c.pregrasp_pose, &format!("{at}.pregrasp_pose"))?,
        root_pose: optional_pose_from_proto(&c.root_pose, &format!("{at}.root_pose"))?,
        approach: c.approach.as_ref().map(vec3_from_proto),
        joints: joints_from_proto(c.joints),
        pregrasp_joints: joints_from_proto(c.pregrasp_joints),
        squeeze_joints: joints_from_proto(c.squeeze_joints),
        quality: quality_from_proto(c.quality.unwrap_or_default()),
        feasible: c.feasible,
        infeasible_reason: c.infeasible_reason,
    })
}

pub fn plan_to_proto(p: &GraspPlan) -> pb::PlanGraspResponse {
    let q = &p.quality;
    let t = &p.timings;
    let c = &p.collision;
    pb::PlanGraspResponse {
        hand: p.hand.clone(),
        grasp_type: grasp_type_to_proto(p.grasp_type) as i32,
        requested_type: grasp_type_to_proto(p.requested_type) as i32,
        type_source: type_source_name(p.type_source).into(),
        type_probabilities: p.type_scores.to_vec(),
        attention: Some(pb::AttentionPoint {
            position: Some(point_to_proto(&p.attention_point)),
            normal: Some(vec3_to_proto(&p.attention_normal)),
            pixel: p
                .perception
                .as_ref()
                .and_then(|r| r.attention_pixel)
                .map(|[u, v]| pb::Pixel {
                    u: u.round().max(0.0) as u32,
                    v: v.round().max(0.0) as u32,
                }),
        }),
        opposition: Some(pb::Opposition {
            h1: hand_part_to_proto(p.opposition.h1) as i32,
            h2: hand_part_to_proto(p.opposition.h2) as i32,
            points: p.opposition.points.iter().map(point_to_proto).collect(),
            normals: p.opposition.normals.iter().map(vec3_to_proto).collect(),
        }),
        contacts: p.contacts.iter().map(contact_to_proto).collect(),
        hand_pose: Some(pose_to_proto(&p.hand_pose)),
        pregrasp_pose: Some(pose_to_proto(&p.pregrasp_pose)),
        root_pose: p.root_pose.as_ref().map(pose_to_proto),
        joints: joints_to_proto(&p.joints),
        pregrasp_joints: joints_to_proto(&p.pregrasp_joints),
        squeeze_joints: joints_to_proto(&p.squeeze_joints),
        approach: p.approach.as_ref().map(vec3_to_proto),
        candidates: p.candidates.iter().map(candidate_to_proto).collect(),
        quality: Some(quality_to_proto(q)),
        feasible: p.feasible,
        infeasible_reason: p.infeasible_reason.clone(),
        stage1: Some(stage_to_proto(&p.stage1)),
        stage2: Some(stage_to_proto(&p.stage2)),
        timings: Some(pb::Timings {
            preprocess: t.preprocess,
            normals: t.normals,
            grasp_type: t.grasp_type,
            stage1: t.stage1,
            stage2: t.stage2,
            finalize: t.finalize,
            total: t.total,
        }),
        collision: Some(pb::CollisionReport {
            checked: c.checked,
            clear: c.clear,
            final_points_in_collision: c.final_points_in_collision as u64,
            pregrasp_points_in_collision: c.pregrasp_points_in_collision as u64,
            approach_points_in_collision: c.approach_points_in_collision as u64,
            min_plane_clearance: c.min_plane_clearance,
            final_plane_clearance: c.final_plane_clearance,
        }),
        support_plane: p.support_plane.as_ref().map(plane_to_proto),
        plane_source: plane_source_name(p.plane_source).into(),
        points_used: p.points_used as u64,
        mode: mode_to_proto(p.mode) as i32,
        seed: p.seed,
        warnings: p.warnings.clone(),
        perception: p.perception.as_ref().map(perception_to_proto),
        overlay_png: p
            .perception
            .as_ref()
            .and_then(|r| r.overlay_png.clone())
            .unwrap_or_default(),
    }
}

fn pair<T: Copy>(v: Vec<T>, field: &str) -> Result<[T; 2], FieldError> {
    <[T; 2]>::try_from(v)
        .map_err(|v| FieldError::new(field, format!("expected 2 values, got {}", v.len())))
}

/// Decodes a plan as the server sent it (clients).
pub fn plan_from_proto(p: pb::PlanGraspResponse) -> Result<GraspPlan, FieldError> {
    let attention = required(&p.attention, "attention")?;
    let attention_pixel = attention.pixel.map(|px| [px.u as f64, px.v as f64]);
    let opp = required(&p.opposition, "opposition")?;
    let q = p.quality.unwrap_or_default();
    let t = p.timings.unwrap_or_default();
    let c = p.collision.unwrap_or_default();
    let type_scores: [f64; 6] =
        p.type_probabilities
            .clone()
            .try_into()
            .map_err(|v: Vec<f64>| {
                FieldError::new(
                    "type_probabilities",
                    format!("expected 6 values, got {}", v.len()),
                )
            })?;
    let contacts = contacts_from_proto(&p.contacts, "contacts")?;
    let candidates = p
        .candidates
        .into_iter()
        .enumerate()
        .map(|(i, c)| candidate_from_proto(c, &format!("candidates[{i}]")))
        .collect::<Result<_, _>>()?;
    Ok(GraspPlan {
        hand: p.hand,
        grasp_type: required_grasp_type(p.grasp_type, "grasp_type")?,
        requested_type: required_grasp_type(p.requested_type, "requested_type")?,
        type_source: type_source_from_name(&p.type_source)?,
        type_scores,
        attention_point: point_from_proto(required(&attention.position, "attention.position")?),
        attention_normal: vec3_from_proto(required(&attention.normal, "attention.normal")?),
        opposition: Opposition {
            h1: hand_part_from_proto(opp.h1, "opposition.h1")?,
            h2: hand_part_from_proto(opp.h2, "opposition.h2")?,
            points: pair(
                opp.points.iter().map(point_from_proto).collect(),
                "opposition.points",
            )?,
            normals: pair(
                opp.normals.iter().map(vec3_from_proto).collect(),
                "opposition.normals",
            )?,
        },
        contacts,
        hand_pose: pose_from_proto(&p.hand_pose, "hand_pose")?,
        pregrasp_pose: pose_from_proto(&p.pregrasp_pose, "pregrasp_pose")?,
        joints: joints_from_proto(p.joints),
        root_pose: optional_pose_from_proto(&p.root_pose, "root_pose")?,
        pregrasp_joints: joints_from_proto(p.pregrasp_joints),
        squeeze_joints: joints_from_proto(p.squeeze_joints),
        approach: p.approach.as_ref().map(vec3_from_proto),
        candidates,
        quality: quality_from_proto(q),
        feasible: p.feasible,
        infeasible_reason: p.infeasible_reason,
        stage1: stage_from_proto(p.stage1),
        stage2: stage_from_proto(p.stage2),
        timings: Timings {
            preprocess: t.preprocess,
            normals: t.normals,
            grasp_type: t.grasp_type,
            stage1: t.stage1,
            stage2: t.stage2,
            finalize: t.finalize,
            total: t.total,
        },
        collision: CollisionReport {
            checked: c.checked,
            clear: c.clear,
            final_points_in_collision: c.final_points_in_collision as usize,
            pregrasp_points_in_collision: c.pregrasp_points_in_collision as usize,
            approach_points_in_collision: c.approach_points_in_collision as usize,
            min_plane_clearance: c.min_plane_clearance,
            final_plane_clearance: c.final_plane_clearance,
        },
        support_plane: p
            .support_plane
            .as_ref()
            .map(|s| plane_from_proto(s, "support_plane"))
            .transpose()?,
        plane_source: plane_source_from_name(&p.plane_source)?,
        points_used: p.points_used as usize,
        mode: mode_from_proto(p.mode, "mode")?,
        seed: p.seed,
        warnings: p.warnings,
        perception: p
            .perception
            .map(|r| perception_from_proto(r, p.overlay_png, attention_pixel))
            .transpose()?,
    })
}

fn perception_to_proto(r: &PerceptionReport) -> pb::Perception {
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
        timings: Some(pb::PerceptionTimings {
            decode: t.decode,
            saliency: t.saliency,
            segmentation: t.segmentation,
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

fn perception_from_proto(
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
        attention_pixel,
        timings: PerceptionTimings {
            decode: t.decode,
            saliency: t.saliency,
            segmentation: t.segmentation,
            roi: t.roi,
            grasp_type: t.grasp_type,
            total: t.total,
        },
        probability_maps: maps,
        overlay_png: (!overlay_png.is_empty()).then_some(overlay_png),
    })
}

// ---------------------------------------------------------------------------------------------
// Tactile stabilization

/// The first message of a `Stabilize` stream: it must open the session.
pub fn stabilize_session_from_proto(
    m: pb::StabilizeRequest,
) -> Result<TactileSessionRequest, FieldError> {
    match m.kind {
        Some(Kind::Session(s)) => tactile_session_from_proto(s),
        Some(Kind::Frame(_)) => Err(FieldError::new(
            "session",
            "the first message must open the session (set `session`); frames follow it",
        )),
        None => Err(FieldError::new(
            "session",
            "is required in the first message",
        )),
    }
}

/// A later message of a `Stabilize` stream: it must carry a frame.
pub fn stabilize_frame_from_proto(m: pb::StabilizeRequest) -> Result<Frame, FieldError> {
    match m.kind {
        Some(Kind::Frame(f)) => Ok(tactile_frame_from_proto(f)),
        Some(Kind::Session(_)) => Err(FieldError::new(
            "session",
            "the session is already open; every later message carries a `frame`",
        )),
        None => Err(FieldError::new("frame", "is required")),
    }
}

fn usize_or(v: Option<u32>, default: usize) -> usize {
    v.map_or(default, |v| v as usize)
}

pub fn tactile_session_from_proto(
    s: pb::TactileSession,
) -> Result<TactileSessionRequest, FieldError> {
    let d = StabilizerConfig::default();
    let fingers = s
        .fingers
        .into_iter()
        .enumerate()
        .map(|(i, f)| {
            let layout = match f.layout {
                Some(FingerLayout::LayoutName(n)) => LayoutChoice::Name(n),
                Some(FingerLayout::CustomLayout(c)) => LayoutChoice::Custom(LayoutSpec {
                    name: c.name,
                    description: String::new(),
                    electrodes: c.electrodes.iter().map(|e| [e.x_mm, e.y_mm]).collect(),
                }),
                None => {
                    return Err(FieldError::new(
                        format!("session.fingers[{i}].layout"),
                        "is required: a layout_name (biotac, biotac_sp) or a custom_layout",
                    ));
                }
            };
            let tare = tare_from_proto(f.tare, &format!("session.fingers[{i}].tare"))?;
            Ok(TactileFingerRequest {
                name: f.name,
                layout,
                tare,
            })
        })
        .collect::<Result<Vec<_>, FieldError>>()?;
    let p = s.pid.unwrap_or_default();
    let pd = d.pid;
    let detector = match s.detector.and_then(|d| d.kind) {
        None => d.detector.clone(),
        Some(DetectorKind::Model(name)) => DetectorChoice::Model(name),
        Some(DetectorKind::ModelFree(t)) => {
            let td = ModelFreeThresholds::default();
            DetectorChoice::ModelFree(ModelFreeThresholds {
                pdc_contact: t.pdc_contact.unwrap_or(td.pdc_contact),
                electrode_contact: t.electrode_contact.unwrap_or(td.electrode_contact),
                slip_vibration: t.slip_vibration.unwrap_or(td.slip_vibration),
                steepness: t.steepness.unwrap_or(td.steepness),
            })
        }
    };
    Ok(TactileSessionRequest {
        fingers,
        config: StabilizerConfig {
            fingers: Vec::new(),
            window_length: usize_or(s.window_length, d.window_length),
            stride: usize_or(s.stride, d.stride),
            law: DesiredForceLaw {
                f0: s.f0.unwrap_or(d.law.f0),
                delta_material: s.delta_material.unwrap_or(d.law.delta_material),
                delta_slip: s.delta_slip.unwrap_or(d.law.delta_slip),
                f_min: s.f_min.unwrap_or(d.law.f_min),
                f_max: s.f_max.unwrap_or(d.law.f_max),
            },
            pid: PidGains {
                kp: p.kp.unwrap_or(pd.kp),
                ki: p.ki.unwrap_or(pd.ki),
                kd: p.kd.unwrap_or(pd.kd),
                output_min: p.output_min.unwrap_or(pd.output_min),
                output_max: p.output_max.unwrap_or(pd.output_max),
                derivative_filter_s: p.derivative_filter_s.unwrap_or(pd.derivative_filter_s),
            },
            alpha: s.alpha.unwrap_or(d.alpha),
            calibration_gain: s.calibration_gain,
            detector,
        },
    })
}

fn tare_from_proto(t: Option<pb::TareSettings>, field: &str) -> Result<TareConfig, FieldError> {
    let Some(t) = t else {
        return Ok(TareConfig::default());
    };
    let polarity = pb::ElectrodePolarity::try_from(t.electrode_polarity).map_err(|_| {
        FieldError::new(
            format!("{field}.electrode_polarity"),
            format!("unknown value {}", t.electrode_polarity),
        )
    })?;
    let electrode_polarity = match polarity {
        pb::ElectrodePolarity::Falling => ElectrodePolarity::Falling,
        pb::ElectrodePolarity::Rising => ElectrodePolarity::Rising,
        pb::ElectrodePolarity::Unspecified if t.pretared => ElectrodePolarity::Rising,
        pb::ElectrodePolarity::Unspecified => ElectrodePolarity::Falling,
    };
    let baseline = if t.pretared {
        Baseline::None
    } else {
        match TareConfig::default().baseline {
            Baseline::FirstFrames(n) => Baseline::FirstFrames(usize_or(t.baseline_frames, n)),
            Baseline::None => Baseline::None,
        }
    };
    Ok(TareConfig {
        baseline,
        electrode_polarity,
    })
}

/// The client's side: a session request as the proto message.
pub fn tactile_session_to_proto(r: &TactileSessionRequest) -> pb::TactileSession {
    let c = &r.config;
    pb::TactileSession {
        fingers: r
            .fingers
            .iter()
            .map(|f| pb::TactileFinger {
                name: f.name.clone(),
                layout: Some(match &f.layout {
                    LayoutChoice::Name(n) => FingerLayout::LayoutName(n.clone()),
                    LayoutChoice::Custom(spec) => FingerLayout::CustomLayout(pb::CustomLayout {
                        name: spec.name.clone(),
                        electrodes: spec
                            .electrodes
                            .iter()
                            .map(|e| pb::Electrode {
                                x_mm: e[0],
                                y_mm: e[1],
                            })
                            .collect(),
                    }),
                }),
                tare: Some(pb::TareSettings {
                    baseline_frames: match f.tare.baseline {
                        Baseline::FirstFrames(n) => Some(n.min(u32::MAX as usize) as u32),
                        Baseline::None => None,
                    },
                    pretared: f.tare.baseline == Baseline::None,
                    electrode_polarity: match f.tare.electrode_polarity {
                        ElectrodePolarity::Falling => pb::ElectrodePolarity::Falling,
                        ElectrodePolarity::Rising => pb::ElectrodePolarity::Rising,
                    } as i32,
                }),
            })
            .collect(),
        window_length: Some(c.window_length.min(u32::MAX as usize) as u32),
        stride: Some(c.stride.min(u32::MAX as usize) as u32),
        f0: Some(c.law.f0),
        delta_material: Some(c.law.delta_material),
        delta_slip: Some(c.law.delta_slip),
        f_min: Some(c.law.f_min),
        f_max: Some(c.law.f_max),
        pid: Some(pb::PidGains {
            kp: Some(c.pid.kp),
            ki: Some(c.pid.ki),
            kd: Some(c.pid.kd),
            output_min: Some(c.pid.output_min),
            output_max: Some(c.pid.output_max),
            derivative_filter_s: Some(c.pid.derivative_filter_s),
        }),
        alpha: Some(c.alpha),
        calibration_gain: c.calibration_gain,
        // Default: unset, so that the server chooses (its model when one is loaded).
        detector: match &c.detector {
            DetectorChoice::Default => None,
            DetectorChoice::Model(n) => Some(pb::TactileDetector {
                kind: Some(DetectorKind::Model(n.clone())),
            }),
            DetectorChoice::ModelFree(t) => Some(pb::TactileDetector {
                kind: Some(DetectorKind::ModelFree(pb::ModelFreeThresholds {
                    pdc_contact: Some(t.pdc_contact),
                    electrode_contact: Some(t.electrode_contact),
                    slip_vibration: Some(t.slip_vibration),
                    steepness: Some(t.steepness),
                })),
            }),
        },
    }
}

/// A frame as received; the session validates it (counts, order, finite values).
pub fn tactile_frame_from_proto(f: pb::TactileFrame) -> Frame {
    Frame {
        timestamp: f.timestamp,
        fingers: f
            .fingers
            .into_iter()
            .map(|r| FingerReading {
                pdc: r.pdc,
                pac: r.pac,
                tdc: r.tdc,
                tac: r.tac,
                electrodes: r.electrodes,
            })
            .collect(),
    }
}

pub fn tactile_frame_to_proto(f: &Frame) -> pb::TactileFrame {
    pb::TactileFrame {
        timestamp: f.timestamp,
        fingers: f
            .fingers
            .iter()
            .map(|r| pb::FingerReading {
                pdc: r.pdc,
                pac: r.pac.clone(),
                tdc: r.tdc,
                tac: r.tac,
                electrodes: r.electrodes.clone(),
            })
            .collect(),
    }
}

/// The answer to frame number `index` (0-based) of a session.
pub fn setpoint_to_proto(r: &FrameResult, index: u64) -> pb::StabilizationSetpoint {
    pb::StabilizationSetpoint {
        timestamp: r.timestamp,
        frame_index: index,
        fingers: r
            .fingers
            .iter()
            .map(|f| pb::FingerSetpoint {
                finger: f.finger.clone(),
                tared: f.tared,
                event: match f.event {
                    ContactEvent::NonContact => pb::ContactEvent::NonContact,
                    ContactEvent::Contact => pb::ContactEvent::Contact,
                    ContactEvent::Slip => pb::ContactEvent::Slip,
                } as i32,
                event_probabilities: f.event_probabilities.to_vec(),
                material: match f.material {
                    Material::Unknown => pb::Material::Unknown,
                    Material::Paper => pb::Material::Paper,
                    Material::Foam => pb::Material::Foam,
                    Material::Plastic => pb::Material::Plastic,
                    Material::Metal => pb::Material::Metal,
                } as i32,
                material_probabilities: f
                    .material_probabilities
                    .map(|p| p.to_vec())
                    .unwrap_or_default(),
                force: f.force,
                force_unit: match f.force_unit {
                    ForceUnit::Raw => pb::ForceUnit::Raw,
                    ForceUnit::Newton => pb::ForceUnit::Newton,
                } as i32,
                contact_location: f.contact_location.map(|l| pb::ImageLocation {
                    row: l[0],
                    col: l[1],
                }),
                contact_area_pixels: f.contact_area_pixels.min(u32::MAX as usize) as u32,
                contact_area_mm2: f.contact_area_mm2,
                desired_force: f.desired_force,
                mode: match f.mode {
                    ControlMode::Position => pb::ControlMode::Position,
                    ControlMode::Force => pb::ControlMode::Force,
                } as i32,
                setpoint: f.setpoint,
            })
            .collect(),
    }
}

/// The client's side: a setpoint message as the domain result (errors name the field).
pub fn setpoint_from_proto(m: pb::StabilizationSetpoint) -> Result<FrameResult, FieldError> {
    let fingers = m
        .fingers
        .into_iter()
        .enumerate()
        .map(|(i, f)| {
            let field = |name: &str| format!("fingers[{i}].{name}");
            let event = match pb::ContactEvent::try_from(f.event) {
                Ok(pb::ContactEvent::NonContact) => ContactEvent::NonContact,
                Ok(pb::ContactEvent::Contact) => ContactEvent::Contact,
                Ok(pb::ContactEvent::Slip) => ContactEvent::Slip,
                _ => {
                    return Err(FieldError::new(
                        field("event"),
                        format!("unknown value {}", f.event),
                    ));
                }
            };
            let material = match pb::Material::try_from(f.material) {
                Ok(pb::Material::Unknown) => Material::Unknown,
                Ok(pb::Material::Paper) => Material::Paper,
                Ok(pb::Material::Foam) => Material::Foam,
                Ok(pb::Material::Plastic) => Material::Plastic,
                Ok(pb::Material::Metal) => Material::Metal,
                _ => {
                    return Err(FieldError::new(
                        field("material"),
                        format!("unknown value {}", f.material),
                    ));
                }
            };
            let mode = match pb::ControlMode::try_from(f.mode) {
                Ok(pb::ControlMode::Position) => ControlMode::Position,
                Ok(pb::ControlMode::Force) => ControlMode::Force,
                _ => {
                    return Err(FieldError::new(
                        field("mode"),
                        format!("unknown value {}", f.mode),
                    ));
                }
            };
            let force_unit = match pb::ForceUnit::try_from(f.force_unit) {
                Ok(pb::ForceUnit::Newton) => ForceUnit::Newton,
                Ok(pb::ForceUnit::Raw) => ForceUnit::Raw,
                _ => {
                    return Err(FieldError::new(
                        field("force_unit"),
                        format!("unknown value {}", f.force_unit),
                    ));
                }
            };
            let event_probabilities: [f64; 3] =
                f.event_probabilities.try_into().map_err(|v: Vec<f64>| {
                    FieldError::new(
                        field("event_probabilities"),
                        format!("{} values, expected 3", v.len()),
                    )
                })?;
            let material_probabilities = if f.material_probabilities.is_empty() {
                None
            } else {
                Some(
                    <[f64; 4]>::try_from(f.material_probabilities).map_err(|v: Vec<f64>| {
                        FieldError::new(
                            field("material_probabilities"),
                            format!("{} values, expected 0 or 4", v.len()),
                        )
                    })?,
                )
            };
            Ok(FingerResult {
                finger: f.finger,
                tared: f.tared,
                event,
                event_probabilities,
                material,
                material_probabilities,
                force: f.force,
                force_unit,
                contact_location: f.contact_location.map(|l| [l.row, l.col]),
                contact_area_pixels: f.contact_area_pixels as usize,
                contact_area_mm2: f.contact_area_mm2,
                desired_force: f.desired_force,
                mode,
                setpoint: f.setpoint,
            })
        })
        .collect::<Result<Vec<_>, FieldError>>()?;
    Ok(FrameResult {
        timestamp: m.timestamp,
        fingers,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use graspd_core::HandCatalog;

    #[test]
    fn hands_round_trip() {
        for h in HandCatalog::builtin().list() {
            assert_eq!(&hand_from_proto(hand_to_proto(h), "hand").unwrap(), h);
        }
    }

    #[test]
    fn options_round_trip_and_unset_means_default() {
        assert_eq!(options_from_proto(None).unwrap(), PlannerOptions::default());
        let o = PlannerOptions {
            seed: 7,
            mode: PlannerMode::WithoutOpposition,
            epsilon: 0.5,
            stage2_weights: [0.1, 0.9],
            lambda1: Some(0.03),
            check_collisions: false,
            ..PlannerOptions::default()
        };
        assert_eq!(options_from_proto(Some(options_to_proto(&o))).unwrap(), o);
    }

    #[test]
    fn bad_cloud_bytes_name_the_field() {
        let r = pb::PlanGraspRequest {
            input: Some(Input::Cloud(pb::PointCloud {
                points: vec![0; 13],
                ..Default::default()
            })),
            hand: Some(Hand::HandName("shadow".into())),
            ..Default::default()
        };
        let e = plan_request_from_proto(r, &Limits::default()).unwrap_err();
        assert_eq!(e.field(), Some("cloud.points"));
        assert!(
            e.to_string()
                .contains("byte length 13 is not a multiple of 12")
        );
    }

    #[test]
    fn bad_enum_values_name_the_field() {
        let r = pb::PlanGraspRequest {
            input: Some(Input::Cloud(pb::PointCloud::default())),
            hand: Some(Hand::HandName("shadow".into())),
            hints: Some(pb::PlanHints {
                grasp_type: 42,
                ..Default::default()
            }),
            ..Default::default()
        };
        let e = plan_request_from_proto(r, &Limits::default()).unwrap_err();
        assert_eq!(e.field(), Some("hints.grasp_type"));
    }
}
