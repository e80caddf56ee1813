//! PlanGrasp requests (options, hints, RGB-D frames, packed clouds) and responses (contacts,
//! joints, quality, candidates, the plan).

use super::hands::*;
use super::perception::*;
use super::ros::*;
use super::values::*;
use crate::error::ServiceError;
use crate::limits::Limits;
use crate::request::{HandChoice, ImageHints, OutputOptions, PlanRequest, PlanSource};
use graspd_core::cloud::{PointCloud, decode_packed_vec3, decode_packed_xyz, encode_packed_xyz};
use graspd_core::perception::{CameraIntrinsics, RgbdFrame, WireImage, camera_pose};
use graspd_core::planning::parallel_grasp::ParallelGrasp;
use graspd_core::planning::{
    CollisionReport, Contact, GraspCandidate, LearnedQuality, Opposition, Pose, Quality,
    StageStats, Timings,
};
use graspd_core::{FieldError, GraspPlan, PlanHints, PlannerOptions};
use graspd_proto::v1 as pb;
use graspd_proto::v1::plan_grasp_request::{Hand, Input};
use nalgebra::{Point3, Quaternion, Vector3};

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
        parallel_grasp: h.parallel_grasp.as_ref().map(|g| ParallelGrasp {
            centre: g.centre.as_ref().map_or(Point3::origin(), point_from_proto),
            axis: g.axis.as_ref().map_or(Vector3::zeros(), vec3_from_proto),
        }),
    };
    let image = ImageHints {
        attention_pixel: h.attention_pixel.map(|p| (p.u, p.v)),
        region: h.region.map(|r| [r.u_min, r.v_min, r.u_max, r.v_max]),
        object: h.object.clone(),
        most_salient: h.most_salient,
    };
    Ok((hints, image))
}

/// The RGB-D frame as received (`field` names it: `rgbd`, `extra_views[i]`); sizes and
/// encodings are checked here, pixels by the facade.
pub(crate) fn rgbd_from_proto(f: pb::RgbdFrame, field: &str) -> Result<RgbdFrame, FieldError> {
    let wire = |i: Option<pb::Image>| {
        let i = i.unwrap_or_default();
        WireImage {
            width: i.width,
            height: i.height,
            encoding: i.encoding,
            is_bigendian: i.is_bigendian,
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
        CameraIntrinsics::from_wire(k.fx, k.fy, k.cx, k.cy, &k.k, &format!("{field}.intrinsics"))?,
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
        is_bigendian: false,
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
            k: Vec::new(),
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
        object: image.object.clone(),
        most_salient: image.most_salient,
        parallel_grasp: h.parallel_grasp.as_ref().map(|g| pb::ParallelGrasp {
            centre: Some(point_to_proto(&g.centre)),
            axis: Some(vec3_to_proto(&g.axis)),
        }),
    }
}

/// Decodes the packed cloud, refusing more points than the limit before allocating them.
fn cloud_from_proto(c: pb::PointCloud, limits: &Limits) -> Result<PointCloud, ServiceError> {
    limits.check_points((c.points.len() / 12) as u64, "cloud.points")?;
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
    let input_frame = match &r.input {
        Some(Input::Cloud(c)) => c.frame_id.clone(),
        Some(Input::Cloud2(c)) => c.frame_id.clone(),
        _ => String::new(),
    };
    let source = match r.input {
        Some(Input::Cloud(c)) => PlanSource::Cloud(cloud_from_proto(c, limits)?),
        Some(Input::Cloud2(c)) => PlanSource::Cloud(cloud2_from_proto(&c, "cloud2", limits)?),
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
            moveit_grasps: o.moveit_grasps,
            frame_id: o.frame_id,
            scene_glb: o.scene_glb,
        }
        .in_frame(&input_frame),
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
            moveit_grasps: r.output.moveit_grasps,
            frame_id: r.output.frame_id.clone(),
            scene_glb: r.output.scene_glb,
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
        moveit_grasps: p.moveit_grasps.iter().map(moveit_grasp_to_proto).collect(),
        scene_glb: p.scene_glb.clone().unwrap_or_default(),
        learned_quality: p.learned_quality.as_ref().map(|l| pb::LearnedQuality {
            probability: l.probability,
            posterior_mean: l.posterior_mean,
            posterior_std: l.posterior_std,
            network_calls: l.network_calls as u32,
            candidates: l.candidates as u32,
        }),
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
    let moveit_grasps = p
        .moveit_grasps
        .into_iter()
        .enumerate()
        .map(|(i, g)| moveit_grasp_from_proto(g, &format!("moveit_grasps[{i}]")))
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
        moveit_grasps,
        scene_glb: (!p.scene_glb.is_empty()).then_some(p.scene_glb),
        learned_quality: p.learned_quality.map(|l| LearnedQuality {
            probability: l.probability,
            posterior_mean: l.posterior_mean,
            posterior_std: l.posterior_std,
            network_calls: l.network_calls as usize,
            candidates: l.candidates as usize,
        }),
    })
}
