//! Hand descriptions, RegisterHand requests and responses, and a hand's posture synergies.

use super::values::*;
use crate::request::{
    Asset, HandSynergies, HandUpload, ModelFormat, RegisteredHand, StoredOverrides,
};
use graspd_core::hand::posture_synergies::{SynergyComponent, TypeCentre};
use graspd_core::hand::{
    Finger, GraspRealisation, HandGeometry, PostureSynergies, TypeEquivalence,
};
use graspd_core::{FieldError, HandDescription};
use graspd_proto::v1 as pb;

/// GetHandSynergies' answer.
pub fn synergies_to_proto(h: &HandSynergies) -> pb::HandSynergies {
    let s = &h.synergies;
    pb::HandSynergies {
        hand: h.hand.clone(),
        joints: s.joints.clone(),
        mean: s.mean.clone(),
        components: s
            .components
            .iter()
            .map(|c| pb::SynergyComponent {
                direction: c.direction.clone(),
                variance: c.variance,
                explained: c.explained,
            })
            .collect(),
        centres: s
            .centres
            .iter()
            .map(|c| pb::SynergyCentre {
                grasp_type: grasp_type_to_proto(c.grasp_type) as i32,
                postures: c.postures as u32,
                amplitudes: c.amplitudes.clone(),
            })
            .collect(),
        postures: s.postures as u32,
        plans: h.plans as u32,
        seed: h.seed,
    }
}

/// GetHandSynergies' answer as a client reads it; `field` names it in errors.
pub fn synergies_from_proto(
    h: pb::HandSynergies,
    field: &str,
) -> Result<HandSynergies, FieldError> {
    let d = h.joints.len();
    let wrong = |what: String| FieldError::new(field, what);
    if h.mean.len() != d {
        return Err(wrong(format!(
            "mean has {} values for {d} joints",
            h.mean.len()
        )));
    }
    let components = h
        .components
        .into_iter()
        .enumerate()
        .map(|(i, c)| {
            if c.direction.len() != d {
                return Err(wrong(format!(
                    "components[{i}].direction has {} values for {d} joints",
                    c.direction.len()
                )));
            }
            Ok(SynergyComponent {
                direction: c.direction,
                variance: c.variance,
                explained: c.explained,
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let centres = h
        .centres
        .into_iter()
        .enumerate()
        .map(|(i, c)| {
            let at = format!("{field}.centres[{i}].grasp_type");
            let grasp_type = grasp_type_from_proto(c.grasp_type, &at)?
                .ok_or_else(|| FieldError::new(at, "missing"))?;
            Ok(TypeCentre {
                grasp_type,
                postures: c.postures as usize,
                amplitudes: c.amplitudes,
            })
        })
        .collect::<Result<Vec<_>, FieldError>>()?;
    Ok(HandSynergies {
        hand: h.hand,
        synergies: PostureSynergies {
            joints: h.joints,
            mean: h.mean,
            components,
            centres,
            postures: h.postures as usize,
        },
        plans: h.plans as usize,
        seed: h.seed,
    })
}

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
