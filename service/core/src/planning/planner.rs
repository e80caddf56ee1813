//! The planning pipeline (Algorithm 4): support plane, normals, grasp type and attention point,
//! stage 1 (pregrasping opposition), stage 2 (final contacts), hand pose and checks.

use super::dual_stage::{self, SearchOutcome};
use super::ferrari_canny::{WrenchModel, ferrari_canny};
use super::joint_configuration::{Effort, FingerTarget, KinematicModel, REACH_TOLERANCE};
use super::object_shape::ObjectShape;
use super::quality::ContactPoint;
use super::search_context::SearchContext;
use super::type_rule;
use super::types::*;
use crate::cloud::{
    CloudIndex, LazyNormals, MIN_POINTS, Orientation, Plane, PointCloud, RansacParams,
    detect_support_plane,
};
use crate::error::{FieldError, PlanError};
use crate::grasp_type::{GraspType, HandPart};
use crate::hand::{HandDescription, PALM};
use nalgebra::{Point3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::sync::Arc;
use std::time::Instant;

/// One planning request in domain terms (already validated at the edge).
#[derive(Debug, Clone)]
pub struct PlanInput {
    pub cloud: PointCloud,
    pub hand: HandDescription,
    pub hints: PlanHints,
    pub options: PlannerOptions,
    /// The hand's kinematics, when known (a hand imported from MJCF or URDF): the final contacts
    /// then become joints, and IK reachability is a hard constraint.
    pub kinematics: Option<Arc<KinematicModel>>,
}

/// Points closer than this to the support plane belong to the table (sensor noise band), m.
const PLANE_BAND: f64 = 0.004;
/// A caller's attention point must lie this close to the cloud, m.
const MAX_ATTENTION_DISTANCE: f64 = 0.02;

fn check_range(field: &str, v: f64, lo: f64, hi: f64) -> Result<(), FieldError> {
    if !v.is_finite() || v < lo || v > hi {
        return Err(FieldError::new(
            format!("options.{field}"),
            format!("must be within [{lo}, {hi}], got {v}"),
        ));
    }
    Ok(())
}

impl PlannerOptions {
    /// Checks every option's range; errors name `options.<field>`.
    pub fn validate(&self) -> Result<(), FieldError> {
        check_range("epsilon", self.epsilon, 0.0, 1.0)?;
        check_range("friction", self.friction, 0.01, 5.0)?;
        check_range("torsion_gamma", self.torsion_gamma, 0.0, 10.0)?;
        for (name, w) in [
            ("stage1_weights", self.stage1_weights),
            ("stage2_weights", self.stage2_weights),
        ] {
            for v in w {
                check_range(name, v, -100.0, 100.0)?;
            }
        }
        check_range("iteration_fraction", self.iteration_fraction, 0.0, 1.0)?;
        let usize_range = |field: &str, v: usize, lo: usize, hi: usize| {
            if v < lo || v > hi {
                Err(FieldError::new(
                    format!("options.{field}"),
                    format!("must be within [{lo}, {hi}], got {v}"),
                ))
            } else {
                Ok(())
            }
        };
        usize_range("max_iterations", self.max_iterations, 1, 10_000_000)?;
        usize_range(
            "min_iterations",
            self.min_iterations,
            0,
            self.max_iterations,
        )?;
        usize_range("patience", self.patience, 1, 10_000_000)?;
        usize_range("restarts", self.restarts, 0, 10)?;
        usize_range("normals_k", self.normals_k, 3, 100)?;
        usize_range(
            "opposition_candidates",
            self.opposition_candidates,
            8,
            100_000,
        )?;
        usize_range("contact_candidates", self.contact_candidates, 2, 100_000)?;
        usize_range("friction_cone_edges", self.friction_cone_edges, 3, 64)?;
        if let Some(l) = self.lambda1 {
            check_range("lambda1", l, 1e-4, 2.0)?;
        }
        if let Some(l) = self.lambda2 {
            check_range("lambda2", l, 1e-4, 2.0)?;
        }
        check_range("pregrasp_distance", self.pregrasp_distance, 0.0, 1.0)?;
        check_range("max_center_offset", self.max_center_offset, 0.0, 10.0)?;
        Ok(())
    }
}

/// The support plane and the object's points above it.
struct Scene {
    plane: Option<Plane>,
    source: PlaneSource,
    points: Vec<Point3<f64>>,
    normals: Option<Vec<Vector3<f64>>>,
    /// Index of each kept point in the request's cloud.
    original: Vec<usize>,
}

fn separate_support_plane(
    cloud: &PointCloud,
    hints: &PlanHints,
    options: &PlannerOptions,
) -> Result<Scene, FieldError> {
    let (plane, source, keep): (Option<Plane>, PlaneSource, Vec<bool>) =
        if let Some(pl) = hints.support_plane {
            let keep = cloud
                .points
                .iter()
                .map(|p| pl.distance(p) >= PLANE_BAND)
                .collect();
            (Some(pl), PlaneSource::Request, keep)
        } else if let Some(fit) = options
            .detect_support_plane
            .then(|| {
                detect_support_plane(
                    &cloud.points,
                    RansacParams::default(),
                    options.seed,
                    MIN_POINTS,
                )
            })
            .flatten()
        {
            let keep = fit.removed.iter().map(|r| !r).collect();
            (Some(fit.plane), PlaneSource::Detected, keep)
        } else {
            (None, PlaneSource::None, vec![true; cloud.points.len()])
        };
    // Exact duplicates carry no information (and a k-d tree cannot split a bucket of identical
    // points): keep the first of each.
    let mut seen = std::collections::HashSet::with_capacity(cloud.points.len());
    let original: Vec<usize> = (0..cloud.points.len())
        .filter(|&i| keep[i] && seen.insert(cloud.points[i].coords.map(f64::to_bits)))
        .collect();
    if original.len() < MIN_POINTS {
        return Err(FieldError::new(
            if source == PlaneSource::Request {
                "hints.support_plane"
            } else {
                "cloud"
            },
            format!(
                "only {} of {} points are distinct and above the support plane; the planner needs at least {MIN_POINTS} object points",
                original.len(),
                cloud.points.len()
            ),
        ));
    }
    Ok(Scene {
        plane,
        source,
        points: original.iter().map(|&i| cloud.points[i]).collect(),
        normals: cloud
            .normals
            .as_ref()
            .map(|n| original.iter().map(|&i| n[i]).collect()),
        original,
    })
}

/// The most probable of `among` under `p` (ties: the first in the dissertation's order).
fn argmax_type(p: &[f64; 6], among: &[GraspType]) -> GraspType {
    among
        .iter()
        .copied()
        .fold(None::<GraspType>, |best, t| match best {
            Some(b) if p[b.index()] >= p[t.index()] => Some(b),
            _ => Some(t),
        })
        .unwrap_or(GraspType::Pinch)
}

/// Plans a grasp (Algorithm 4). Deterministic for a given input and seed.
pub fn plan(input: PlanInput) -> Result<GraspPlan, PlanError> {
    let t_start = Instant::now();
    let PlanInput {
        cloud,
        hand,
        hints,
        options,
        kinematics,
    } = input;
    options.validate()?;
    hand.validate()?;
    let mut warnings = Vec::new();

    let scene = separate_support_plane(&cloud, &hints, &options)?;
    if scene.source == PlaneSource::None {
        warnings.push(
            "no support plane given or found: the hand is not checked against a table".into(),
        );
    }
    let up = scene
        .plane
        .map(|p| p.normal)
        .or(hints.up.and_then(|u| u.try_normalize(1e-9)));
    let points = &scene.points;
    let t_pre = t_start.elapsed().as_secs_f64();

    let t = Instant::now();
    let index = CloudIndex::new(points);
    let orient = match hints.viewpoint {
        Some(v) => Orientation::TowardViewpoint(v),
        None => Orientation::AwayFromCentroid,
    };
    let normals = LazyNormals::new(
        points,
        &index,
        options.normals_k,
        orient,
        scene.normals.clone(),
    );
    let t_normals = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let shape = ObjectShape::of(points);
    let mut type_scores = [0.0; 6];
    let (requested, type_source) = match (hints.grasp_type, hints.detected_types) {
        (Some(t), _) => (t, TypeSource::Request),
        (None, Some(p)) => {
            type_scores = p;
            (argmax_type(&p, &GraspType::ALL), TypeSource::Model)
        }
        (None, None) => (
            type_rule::grasp_type_by_rule(&shape),
            TypeSource::GeometricRule,
        ),
    };
    let grasp = if type_source == TypeSource::Model {
        // s* = argmax over the types the hand realises (method.md §4).
        hand.resolve_forced(argmax_type(&type_scores, &hand.realisable_types()))
            .map(|mut g| {
                g.requested = requested;
                g
            })
            .unwrap_or_else(|| hand.resolve_detected(requested))
    } else if type_source == TypeSource::Request {
        hand.resolve_forced(requested).ok_or_else(|| {
            FieldError::new(
                "hints.grasp_type",
                format!(
                    "hand '{}' cannot realise {requested} (it realises: {})",
                    hand.name,
                    hand.realisable_types()
                        .iter()
                        .map(|t| t.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })?
    } else {
        hand.resolve_detected(requested)
    };
    if grasp.grasp_type != requested {
        warnings.push(format!(
            "{requested} mapped to {} for hand '{}'",
            grasp.grasp_type, hand.name
        ));
    }
    let rule_approach = type_rule::approach_by_rule(
        &shape,
        grasp.grasp_type,
        points,
        up.as_ref(),
        hints.viewpoint.as_ref(),
    );
    let att = match hints.attention_point {
        Some(p) => {
            let (i, d) = index.nearest_one(&p);
            if d > MAX_ATTENTION_DISTANCE {
                return Err(FieldError::new(
                    "hints.attention_point",
                    format!(
                        "lies {:.1} mm from the nearest object point; it must be on the object (≤ {:.0} mm)",
                        d * 1e3,
                        MAX_ATTENTION_DISTANCE * 1e3
                    ),
                )
                .into());
            }
            i
        }
        None => type_rule::attention_point_by_rule(&shape, points, &rule_approach),
    };
    let (p_att, n_att) = (points[att], normals.get(att));
    if type_source != TypeSource::Model {
        type_scores[requested.index()] = 1.0;
    }
    let t_type = t.elapsed().as_secs_f64();

    let mut approach_prefs = vec![-n_att, rule_approach];
    if let Some(u) = up {
        approach_prefs.push(-u);
    }
    approach_prefs.push(-Vector3::z());
    let ctx = SearchContext {
        points,
        normals: &normals,
        index: &index,
        shape: &shape,
        hand: &hand,
        grasp: &grasp,
        p_att,
        n_att,
        approach_prefs,
        plane: scene.plane,
        options: &options,
        cos_friction: options.friction.atan().cos(),
        kinematics: kinematics.as_deref(),
        kinematic_checks: std::cell::Cell::new(0),
    };
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let outcome = dual_stage::search(&ctx, &mut rng).ok_or_else(|| {
        FieldError::new("cloud", "no candidate contacts near the attention point")
    })?;

    let t = Instant::now();
    let mut plan = match kinematics.as_deref() {
        None => assemble(&ctx, &outcome, &outcome.contacts, &scene, &options)?,
        Some(model) => with_joints(&ctx, &outcome, &scene, &options, model)?,
    };
    plan.grasp_type = grasp.grasp_type;
    plan.requested_type = requested;
    plan.type_source = type_source;
    plan.type_scores = type_scores;
    plan.attention_point = p_att;
    plan.attention_normal = n_att;
    plan.warnings.extend(warnings);
    plan.timings = Timings {
        preprocess: t_pre,
        normals: t_normals,
        grasp_type: t_type,
        stage1: outcome.stage1.seconds,
        stage2: outcome.stage2.seconds,
        finalize: t.elapsed().as_secs_f64(),
        total: t_start.elapsed().as_secs_f64(),
    };
    Ok(plan)
}

/// Builds the response from the search outcome: contacts with fingers, poses, quality figures and
/// the collision report.
fn assemble(
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
        });
    }
    let cps: Vec<ContactPoint> = chosen.iter().map(|&i| ctx.contact(i)).collect();
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
        opposition: Opposition {
            h1: ctx.grasp.h1_part,
            h2: ctx.grasp.h2_part,
            points: [ctx.points[oc1], ctx.points[oc2]],
            normals: [ctx.normals.get(oc1), ctx.normals.get(oc2)],
        },
        contacts,
        hand_pose,
        pregrasp_pose,
        joints: Vec::new(),
        root_pose: None,
        quality: Quality {
            gii: s,
            reachability: assessment.r,
            attention: assessment.g,
            objective: assessment.q,
            epsilon,
            aperture_or_area: assessment.a,
            palm_height: assessment.h,
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
    })
}

/// How many of the search's configurations (the best, then its runners-up) are tried against
/// the IK before the plan is declared unreachable.
const IK_CANDIDATES: usize = 1 + super::dual_stage::MAX_ALTERNATIVES;

/// The plan for a hand with known kinematics: the best configuration of the search whose
/// contacts the fingers reach (IK residuals ≤ [`REACH_TOLERANCE`], jointly with a bounded palm
/// correction) and whose posed hand is clear of the support plane and the cloud; else the first
/// reachable one (reported as colliding); else the best, infeasible with the IK's reason. The
/// joints, per-contact residuals, corrected hand pose and the kinematic collision figures of the
/// final configuration go into the plan.
fn with_joints(
    ctx: &SearchContext,
    out: &SearchOutcome,
    scene: &Scene,
    options: &PlannerOptions,
    model: &KinematicModel,
) -> Result<GraspPlan, PlanError> {
    let candidates: Vec<&Vec<usize>> = std::iter::once(&out.contacts)
        .chain(&out.alternatives)
        .take(IK_CANDIDATES)
        .collect();
    let mut tried: Vec<(GraspPlan, super::JointConfiguration)> = Vec::new();
    for chosen in candidates {
        let plan = assemble(ctx, out, chosen, scene, options)?;
        let targets: Vec<FingerTarget> = plan
            .contacts
            .iter()
            .filter(|c| c.part != HandPart::Palm)
            .map(|c| FingerTarget {
                finger: c.finger.clone(),
                position: c.position,
                normal: c.normal,
            })
            .collect();
        let joints = model.solve(
            &targets,
            &plan.hand_pose,
            scene.plane.as_ref(),
            ctx.points,
            Effort::Final,
            options.pregrasp_distance,
        )?;
        let done = joints.reachable && joints.clear();
        tried.push((plan, joints));
        if done || !out.feasible {
            break;
        }
    }
    let pick = tried
        .iter()
        .position(|(_, j)| j.reachable && j.clear())
        .or_else(|| tried.iter().position(|(_, j)| j.reachable))
        .unwrap_or(0);
    let n_tried = tried.len();
    let (mut plan, joints) = tried.swap_remove(pick);
    let mut residuals = joints.residuals.iter();
    for c in plan
        .contacts
        .iter_mut()
        .filter(|c| c.part != HandPart::Palm)
    {
        c.ik_residual = residuals.next().copied();
    }
    let approach = joints.hand_pose.orientation * Vector3::z();
    plan.pregrasp_pose = Pose {
        position: joints.hand_pose.position - approach * options.pregrasp_distance,
        orientation: joints.hand_pose.orientation,
    };
    plan.hand_pose = joints.hand_pose;
    plan.joints = joints.joints.clone();
    plan.root_pose = Some(joints.root_pose);
    let col = &mut plan.collision;
    col.checked = options.check_collisions;
    // The hand's own geometry replaces the parametric model's at every pose.
    col.final_points_in_collision = joints.points_in_collision;
    col.pregrasp_points_in_collision = joints.pregrasp_points_in_collision;
    col.approach_points_in_collision = joints.approach_points_in_collision;
    col.final_plane_clearance = joints.plane_clearance;
    col.min_plane_clearance = match (joints.plane_clearance, joints.approach_plane_clearance) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    };
    col.clear = col.final_points_in_collision < super::collision::DEFAULT_MIN_POINTS
        && col.pregrasp_points_in_collision < super::collision::DEFAULT_MIN_POINTS
        && col.approach_points_in_collision < super::collision::DEFAULT_MIN_POINTS
        && col
            .min_plane_clearance
            .is_none_or(|c| c >= -super::search_context::PLANE_TOLERANCE);
    if plan.feasible && !joints.reachable {
        plan.feasible = false;
        plan.infeasible_reason = Some(format!(
            "IK: the fingers reach the contacts only within {:.1} mm (tolerance {:.0} mm) for the best {} configurations",
            joints.worst_residual * 1e3,
            REACH_TOLERANCE * 1e3,
            n_tried
        ));
    } else if plan.feasible && options.check_collisions && !joints.clear() {
        plan.feasible = false;
        plan.infeasible_reason = Some(format!(
            "the hand posed at the planned joints collides: {}",
            joints.describe_collision()
        ));
    } else if !joints.approach_clear() {
        plan.warnings.push(format!(
            "the hand shaped as planned collides on its way in: {}",
            joints.describe_collision()
        ));
    }
    if pick > 0 {
        plan.warnings.push(format!(
            "the search's best {pick} configuration(s) were not reachable by the hand's kinematics; runner-up {pick} was taken"
        ));
    }
    Ok(plan)
}
