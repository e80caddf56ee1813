//! The response of the planner (docs/final-configuration.md): a plan assembled from the search's
//! contacts — fingers, poses, quality figures, the collision report — or, for a hand with
//! kinematics, from its final configurations, the best becoming the plan and all of them its
//! ranked `candidates`.

use super::dual_stage::SearchOutcome;
use super::evaluation::SearchContext;
use super::ferrari_canny::{WrenchModel, ferrari_canny};
use super::final_configuration::FinalConfiguration;
use super::grasp_plan::*;
use super::kinematic_model::KinematicModel;
use super::quality::ContactPoint;
use super::request::*;
use super::scene::Scene;
use crate::error::{FieldError, PlanError};
use crate::grasp_type::{GraspType, HandPart};
use crate::hand::PALM;
use nalgebra::{Point3, Vector3};

/// Builds the response from the search outcome: contacts with fingers, poses, quality figures and
/// the collision report.
pub(super) fn assemble(
    ctx: &SearchContext,
    out: &SearchOutcome,
    chosen: &[usize],
    scene: &Scene,
    options: &PlannerOptions,
) -> Result<GraspPlan, PlanError> {
    let (h1, h2) = chosen.split_at(out.k1);
    let assessment = ctx.assess(h1, h2, out.final_weights);
    let (hand_pose, pregrasp_pose, frame) = ctx.poses(&assessment).ok_or_else(|| {
        FieldError::new(
            "cloud",
            "the planned contacts coincide; no hand pose exists",
        )
    })?;
    let s = ctx.stability(chosen);
    let mut contacts = Vec::with_capacity(out.contacts.len());
    if ctx.palm_opposition() {
        let i = h1[0];
        contacts.push(Contact {
            position: ctx.points[i],
            normal: ctx.normals.get(i),
            finger: PALM.into(),
            part: HandPart::Palm,
            point_index: scene.original[i],
            ik_residual: None,
            inferred: i >= scene.visible,
            link: None,
        });
    }
    for fc in ctx.finger_contacts(h1, h2, &frame) {
        let finger = &ctx.hand.fingers[fc.finger];
        let part = if finger.thumb {
            ctx.grasp.h1_part
        } else {
            ctx.grasp.h2_part
        };
        contacts.push(Contact {
            position: fc.position,
            normal: fc.normal,
            finger: finger.name.clone(),
            part,
            point_index: scene.original[fc.point],
            ik_residual: None,
            inferred: fc.point >= scene.visible,
            link: None,
        });
    }
    let cps: Vec<ContactPoint> = chosen.iter().map(|&i| ctx.contact(i)).collect();
    let rob = ctx.robustness(&cps, true);
    let epsilon = ferrari_canny(
        &cps,
        &ctx.shape.center,
        ctx.shape.radius,
        WrenchModel {
            friction: options.friction,
            edges: options.friction_cone_edges,
            patch_radius: 0.01,
        },
    );
    let collision = match ctx.collisions(h1, h2, &assessment) {
        Some(c) => CollisionReport {
            checked: options.check_collisions,
            clear: c.clear(),
            final_points_in_collision: c.final_points,
            pregrasp_points_in_collision: c.pregrasp_points,
            approach_points_in_collision: c.approach_points,
            min_plane_clearance: c.plane_clearance,
            final_plane_clearance: None,
        },
        None => CollisionReport::default(),
    };
    // For a pinch the opposition is the grasp: a runner-up carries its own.
    let (oc1, oc2) = if chosen.len() == 2 && chosen != out.contacts.as_slice() {
        (chosen[0], chosen[1])
    } else {
        out.opposition
    };
    let mut warnings = Vec::new();
    if out.feasible && !options.check_collisions && !collision.clear {
        warnings.push("collision checks are off and the posed hand collides".into());
    }
    Ok(GraspPlan {
        hand: ctx.hand.name.clone(),
        grasp_type: GraspType::Pinch,
        requested_type: GraspType::Pinch,
        type_source: TypeSource::GeometricRule,
        type_scores: [0.0; 6],
        attention_point: ctx.p_att,
        attention_normal: ctx.n_att,
        opposition: pregrasping_opposition(ctx, oc1, oc2),
        contacts,
        hand_pose,
        pregrasp_pose,
        joints: Vec::new(),
        root_pose: None,
        pregrasp_joints: Vec::new(),
        squeeze_joints: Vec::new(),
        approach: Some(frame.z),
        candidates: Vec::new(),
        quality: Quality {
            gii: s,
            reachability: assessment.r,
            attention: assessment.g,
            objective: assessment.q,
            epsilon,
            aperture_or_area: assessment.a,
            palm_height: assessment.h,
            robustness: rob.weakest,
            gravity_resistance: rob.gravity,
        },
        feasible: out.feasible,
        infeasible_reason: out.reason.clone(),
        stage1: out.stage1,
        stage2: out.stage2,
        timings: Timings::default(),
        collision,
        support_plane: scene.plane,
        plane_source: scene.source,
        points_used: scene.points.len(),
        mode: options.mode,
        seed: options.seed,
        warnings,
        perception: None,
        moveit_grasps: Vec::new(),
        scene_glb: None,
        learned_quality: None,
    })
}

/// The plan of a hand with kinematics from its final configurations (best first; see
/// `final_configuration`): the best becomes the plan, all of them its `candidates`. With none
/// (no pre-shape, or no pose clear at the pre-grasp) the opposition is returned as an infeasible
/// plan without joints.
pub(super) fn final_plan(
    ctx: &SearchContext,
    finals: &[FinalConfiguration],
    scene: &Scene,
    model: &KinematicModel,
    (s1, s2, stage1_ok, stage1_reason): (StageStats, StageStats, bool, Option<String>),
    oppositions: &[(usize, usize)],
) -> Result<GraspPlan, PlanError> {
    let options = ctx.options;
    let Some(best) = finals.first() else {
        let (a, b) = oppositions[0];
        let outcome = SearchOutcome {
            contacts: vec![a, b],
            k1: 1,
            opposition: (a, b),
            feasible: false,
            reason: Some(stage1_reason.unwrap_or_else(|| {
                format!(
                    "no pose of the hand's model is clear of the table and the object at the \
                     pre-grasp for {} (tried {} candidates)",
                    ctx.grasp.grasp_type, options.final_candidates
                )
            })),
            stage1: s1,
            stage2: s2,
            final_weights: options.stage2_weights,
            alternatives: Vec::new(),
        };
        let mut plan = assemble(ctx, &outcome, &outcome.contacts, scene, options)?;
        plan.feasible = false;
        plan.candidates = vec![GraspCandidate::of(&plan)];
        return Ok(plan);
    };
    let mut plans: Vec<GraspPlan> = Vec::with_capacity(finals.len());
    for fc in finals {
        plans.push(plan_of_final(ctx, fc, scene, model, s1, s2)?);
    }
    let mut plan = plans[0].clone();
    plan.candidates = plans.iter().map(GraspCandidate::of).collect();
    if !best.feasible
        && !stage1_ok
        && let Some(r) = stage1_reason
    {
        plan.infeasible_reason = Some(format!(
            "{}; {r}",
            plan.infeasible_reason.unwrap_or_default()
        ));
    }
    Ok(plan)
}

/// One final configuration as a plan.
fn plan_of_final(
    ctx: &SearchContext,
    fc: &FinalConfiguration,
    scene: &Scene,
    model: &KinematicModel,
    stage1: StageStats,
    stage2: StageStats,
) -> Result<GraspPlan, PlanError> {
    let options = ctx.options;
    let hand = &model.hand;
    let pose = |iso: &nalgebra::Isometry3<f64>| Pose {
        position: Point3::from(iso.translation.vector),
        orientation: iso.rotation,
    };
    let named = |q: &[f64]| -> Vec<(String, f64)> {
        hand.tree
            .joints
            .iter()
            .zip(q)
            .map(|(j, v)| (j.name.clone(), *v))
            .collect()
    };
    let mut contacts = Vec::with_capacity(fc.contacts.len());
    for c in &fc.contacts {
        let (finger, part) = match c.finger {
            None => (PALM.to_string(), HandPart::Palm),
            Some(f) => {
                let kf = &hand.fingers[f];
                let at_tip = c.body == kf.tip
                    || hand.tree.bodies[kf.tip].parent == Some(c.body)
                        && hand.tree.bodies[kf.tip].joints.is_empty();
                let part = match (f == hand.thumb, at_tip) {
                    (true, true) => HandPart::ThumbTip,
                    (true, false) => HandPart::ThumbSurface,
                    (false, true) => HandPart::FingerTip,
                    (false, false) => HandPart::FingerSurface,
                };
                (kf.name.clone(), part)
            }
        };
        contacts.push(Contact {
            position: c.position,
            normal: c.normal,
            // The link's surface at the planned joints against the contact.
            ik_residual: Some(c.gap),
            finger,
            part,
            point_index: scene.original[c.point],
            inferred: c.point >= scene.visible,
            link: Some(hand.tree.bodies[c.body].name.clone()),
        });
    }
    let cps: Vec<ContactPoint> = fc
        .contacts
        .iter()
        .map(|c| ContactPoint {
            position: c.position,
            normal: c.normal,
        })
        .collect();
    let epsilon = ferrari_canny(
        &cps,
        &ctx.shape.center,
        ctx.shape.radius,
        WrenchModel {
            friction: options.friction,
            edges: options.friction_cone_edges,
            patch_radius: 0.01,
        },
    );
    // R and G of Eq 5.4/5.5 on the configuration the hand takes.
    let m = cps.len();
    let centroid =
        Point3::from(cps.iter().map(|c| c.position.coords).sum::<Vector3<f64>>() / m.max(1) as f64);
    let a = if m <= 2 {
        cps.first()
            .zip(cps.last())
            .map_or(0.0, |(x, y)| (y.position - x.position).norm())
    } else {
        let pts: Vec<Point3<f64>> = cps.iter().map(|c| c.position).collect();
        super::quality::polygon_area(&pts)
    };
    let h = (centroid - Point3::from(fc.hand_pose.translation.vector))
        .dot(&fc.approach)
        .max(0.0);
    let r = super::quality::reachability(a, h, ctx.hand.a_max(m), ctx.hand.geometry.max_height);
    let (oc1, oc2) = fc.opposition;
    let d = ctx.points[oc2] - ctx.points[oc1];
    let g = if ctx.palm_opposition() {
        super::quality::attention_palm(&ctx.n_att, &d)
    } else {
        super::quality::attention(&ctx.n_att, &d)
    };
    let w = options.stage2_weights;
    // Collision counts of the chosen configuration, for the report.
    let count =
        |q: &[f64], at: &nalgebra::Isometry3<f64>| -> Result<(usize, Option<f64>), FieldError> {
            let posed = model.collision.posed(hand, q, at)?;
            Ok((
                posed.points_inside(ctx.points, super::collision::DEFAULT_TOLERANCE, usize::MAX),
                scene.plane.map(|pl| posed.plane_clearance(&pl)),
            ))
        };
    let back = nalgebra::Translation3::from(-fc.approach * options.pregrasp_distance);
    let half = nalgebra::Translation3::from(-fc.approach * options.pregrasp_distance * 0.5);
    let pregrasp_iso = back * fc.hand_pose;
    let (final_points, final_clearance) = count(&fc.grasp, &fc.hand_pose)?;
    let (pre_points, pre_clearance) = count(&fc.pregrasp, &pregrasp_iso)?;
    let (app_points, app_clearance) = count(&fc.pregrasp, &(half * fc.hand_pose))?;
    let min_clearance = [fc.plane_clearance, pre_clearance, app_clearance]
        .into_iter()
        .flatten()
        .reduce(f64::min);
    let n = super::collision::DEFAULT_MIN_POINTS;
    let collision = CollisionReport {
        checked: true,
        clear: final_points < n
            && pre_points < n
            && app_points < n
            && min_clearance.is_none_or(|c| c >= -super::collision::PLANE_TOLERANCE),
        final_points_in_collision: final_points,
        pregrasp_points_in_collision: pre_points,
        approach_points_in_collision: app_points,
        min_plane_clearance: min_clearance,
        final_plane_clearance: final_clearance,
    };
    let mut warnings = Vec::new();
    if let Some(depth) = fc.squeeze_into_table() {
        warnings.push(format!(
            "the squeeze presses the hand {:.0} mm into the table: the table stops the links \
             that reach it, and what they press on it does not press the object",
            depth * 1e3
        ));
    }
    if fc.push > 0.002 {
        warnings.push(format!(
            "the linked fingers push the object {:.0} mm before both touch",
            fc.push * 1e3
        ));
    }
    Ok(GraspPlan {
        hand: ctx.hand.name.clone(),
        grasp_type: GraspType::Pinch,
        requested_type: GraspType::Pinch,
        type_source: TypeSource::GeometricRule,
        type_scores: [0.0; 6],
        attention_point: ctx.p_att,
        attention_normal: ctx.n_att,
        opposition: pregrasping_opposition(ctx, oc1, oc2),
        contacts,
        hand_pose: pose(&fc.hand_pose),
        pregrasp_pose: pose(&pregrasp_iso),
        joints: named(&fc.grasp),
        root_pose: Some(pose(&fc.root_pose)),
        pregrasp_joints: named(&fc.pregrasp),
        squeeze_joints: named(&fc.squeeze),
        approach: Some(fc.approach),
        candidates: Vec::new(),
        quality: Quality {
            gii: fc.gii,
            reachability: r,
            attention: g,
            objective: w[0] * r + w[1] * g,
            epsilon,
            aperture_or_area: a,
            palm_height: h,
            robustness: fc.robustness.weakest,
            gravity_resistance: fc.robustness.gravity,
        },
        feasible: fc.feasible,
        infeasible_reason: fc.reason.clone(),
        stage1,
        stage2,
        timings: Timings::default(),
        collision,
        support_plane: scene.plane,
        plane_source: scene.source,
        points_used: scene.visible,
        mode: options.mode,
        seed: options.seed,
        warnings,
        perception: None,
        moveit_grasps: Vec::new(),
        scene_glb: None,
        learned_quality: None,
    })
}

/// The pregrasping opposition (stage 1's result) between cloud points `oc1` and `oc2`.
fn pregrasping_opposition(ctx: &SearchContext, oc1: usize, oc2: usize) -> Opposition {
    Opposition {
        h1: ctx.grasp.h1_part,
        h2: ctx.grasp.h2_part,
        points: [ctx.points[oc1], ctx.points[oc2]],
        normals: [ctx.normals.get(oc1), ctx.normals.get(oc2)],
    }
}
