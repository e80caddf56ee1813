//! Value types and enums: vectors, points, poses, planes, grasp types, hand parts, planner
//! modes and the API names of the type and plane sources.

use graspd_core::cloud::Plane;
use graspd_core::planning::{PlaneSource, PlannerMode, Pose, TypeSource};
use graspd_core::{FieldError, GraspType, HandPart};
use graspd_proto::v1 as pb;
use nalgebra::{Point3, Quaternion, UnitQuaternion, Vector3};

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

pub fn point_from_proto(v: &pb::Vec3) -> Point3<f64> {
    Point3::new(v.x, v.y, v.z)
}

pub fn required<'a, T>(v: &'a Option<T>, field: &str) -> Result<&'a T, FieldError> {
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

pub fn plane_to_proto(p: &Plane) -> pb::Plane {
    pb::Plane {
        normal: Some(vec3_to_proto(&p.normal)),
        offset: p.offset,
    }
}

pub fn plane_from_proto(p: &pb::Plane, field: &str) -> Result<Plane, FieldError> {
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

pub fn required_grasp_type(v: i32, field: &str) -> Result<GraspType, FieldError> {
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

pub fn mode_to_proto(m: PlannerMode) -> pb::PlannerMode {
    match m {
        PlannerMode::DualStage => pb::PlannerMode::DualStage,
        PlannerMode::WithoutOpposition => pb::PlannerMode::WithoutOpposition,
        PlannerMode::LearnedQuality => pb::PlannerMode::LearnedQuality,
    }
}

pub fn mode_from_proto(v: i32, field: &str) -> Result<PlannerMode, FieldError> {
    match pb::PlannerMode::try_from(v) {
        Ok(pb::PlannerMode::DualStage) => Ok(PlannerMode::DualStage),
        Ok(pb::PlannerMode::WithoutOpposition) => Ok(PlannerMode::WithoutOpposition),
        Ok(pb::PlannerMode::LearnedQuality) => Ok(PlannerMode::LearnedQuality),
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

pub fn type_source_from_name(s: &str) -> Result<TypeSource, FieldError> {
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

pub fn plane_source_from_name(s: &str) -> Result<PlaneSource, FieldError> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_grasp_type_and_hand_part_survives_the_wire() {
        for t in GraspType::ALL {
            let v = grasp_type_to_proto(t) as i32;
            assert_eq!(grasp_type_from_proto(v, "t").unwrap(), Some(t));
            assert_eq!(required_grasp_type(v, "t").unwrap(), t);
        }
        assert_eq!(grasp_type_from_proto(0, "t").unwrap(), None);
        let e = grasp_type_from_proto(99, "hints.grasp_type").unwrap_err();
        assert_eq!(e.field, "hints.grasp_type");
        for p in [
            HandPart::ThumbTip,
            HandPart::ThumbSurface,
            HandPart::FingerTip,
            HandPart::FingerSurface,
            HandPart::Palm,
        ] {
            let v = hand_part_to_proto(p) as i32;
            assert_eq!(hand_part_from_proto(v, "p").unwrap(), p);
        }
        assert_eq!(
            hand_part_from_proto(0, "contacts[0].part")
                .unwrap_err()
                .field,
            "contacts[0].part"
        );
    }

    #[test]
    fn a_pose_survives_the_wire_and_a_missing_part_is_named() {
        let pose = Pose {
            position: Point3::new(0.1, -0.2, 0.3),
            orientation: UnitQuaternion::from_euler_angles(0.3, -0.5, 1.2),
        };
        let back = pose_from_proto(&Some(pose_to_proto(&pose)), "hand_pose").unwrap();
        assert_eq!(back.position, pose.position);
        assert!(back.orientation.angle_to(&pose.orientation) < 1e-12);
        let mut wire = pose_to_proto(&pose);
        wire.orientation = None;
        let e = pose_from_proto(&Some(wire), "hand_pose").unwrap_err();
        assert_eq!(e.field, "hand_pose.orientation");
        assert_eq!(
            pose_from_proto(&None, "root_pose").unwrap_err().field,
            "root_pose"
        );
    }
}
