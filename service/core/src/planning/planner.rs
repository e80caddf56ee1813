//! The planning pipeline (Algorithm 4): support plane, normals, grasp type and attention point,
//! stage 1 (pregrasping opposition), stage 2 (final contacts), hand pose and checks.

use super::dual_stage;
use super::evaluation::SearchContext;
use super::final_configuration;
use super::grasp_plan::*;
use super::grasp_quality::GraspQualityModel;
use super::kinematic_model::KinematicModel;
use super::learned_planner;
use super::object_shape::ObjectShape;
use super::plan_assembly::{assemble, final_plan};
use super::request::*;
use super::scene::{complete_unseen, separate_support_plane};
use super::type_choice::{self, TypeAttempt, plausible_types};
use super::type_rule;
use crate::cloud::{CloudIndex, LazyNormals, PointCloud};
use crate::error::{FieldError, PlanError};
use crate::grasp_type::GraspType;
use crate::hand::{HandDescription, ResolvedGrasp};
use nalgebra::Vector3;
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
    /// The learned parallel-jaw quality network (`options.mode = learned_quality`, ch. 3).
    pub grasp_quality: Option<Arc<GraspQualityModel>>,
}

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

fn check_count(field: &str, v: usize, lo: usize, hi: usize) -> Result<(), FieldError> {
    if v < lo || v > hi {
        return Err(FieldError::new(
            format!("options.{field}"),
            format!("must be within [{lo}, {hi}], got {v}"),
        ));
    }
    Ok(())
}

/// Most stage-1 iterations an options set may ask for (a server caps it lower, per its
/// configured limits).
pub const MAX_ITERATIONS: usize = 10_000_000;

impl PlannerOptions {
    /// Checks every option's range — the one home of the option bounds: the service's edge
    /// and the planner both call it; errors name `options.<field>`.
    pub fn validate(&self) -> Result<(), FieldError> {
        check_range("epsilon", self.epsilon, 0.0, 1.0)?;
        check_range("friction", self.friction, 0.01, 5.0)?;
        check_range("torsion_gamma", self.torsion_gamma, 0.0, 10.0)?;
        for (name, w) in [
            ("stage1_weights", self.stage1_weights),
            ("stage2_weights", self.stage2_weights),
        ] {
            // Both terms of the objective count for or against nothing when negative, and
            // all-zero weights leave nothing to maximise.
            if !w.iter().all(|v| v.is_finite() && (0.0..=100.0).contains(v))
                || w.iter().sum::<f64>() <= 0.0
            {
                return Err(FieldError::new(
                    format!("options.{name}"),
                    format!("must be two weights within [0, 100], not both zero, got {w:?}"),
                ));
            }
        }
        if !(self.iteration_fraction.is_finite()
            && self.iteration_fraction > 0.0
            && self.iteration_fraction <= 1.0)
        {
            return Err(FieldError::new(
                "options.iteration_fraction",
                format!("must be within (0, 1], got {}", self.iteration_fraction),
            ));
        }
        check_count("max_iterations", self.max_iterations, 1, MAX_ITERATIONS)?;
        check_count(
            "min_iterations",
            self.min_iterations,
            0,
            self.max_iterations,
        )?;
        check_count("patience", self.patience, 1, MAX_ITERATIONS)?;
        check_count("restarts", self.restarts, 0, 10)?;
        check_count("normals_k", self.normals_k, 3, 100)?;
        check_count(
            "opposition_candidates",
            self.opposition_candidates,
            8,
            100_000,
        )?;
        check_count("contact_candidates", self.contact_candidates, 2, 100_000)?;
        check_count("friction_cone_edges", self.friction_cone_edges, 3, 64)?;
        if let Some(l) = self.lambda1 {
            check_range("lambda1", l, 1e-4, 2.0)?;
        }
        if let Some(l) = self.lambda2 {
            check_range("lambda2", l, 1e-4, 2.0)?;
        }
        check_range("pregrasp_distance", self.pregrasp_distance, 0.0, 1.0)?;
        check_range("max_center_offset", self.max_center_offset, 0.0, 10.0)?;
        check_count("candidates", self.candidates, 1, 16)?;
        check_range("squeeze_depth", self.squeeze_depth, 0.0, 0.05)?;
        check_count("final_candidates", self.final_candidates, 1, 200)?;
        Ok(())
    }
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
        grasp_quality,
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
    let mut scene = scene;
    let orient = complete_unseen(
        &mut scene,
        hints.viewpoint,
        &hints.seen_from,
        up,
        options.complete_unseen,
    );
    let points = &scene.points;
    let t_pre = t_start.elapsed().as_secs_f64();

    let t = Instant::now();
    let index = CloudIndex::new(points);
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
    let rule_approach_for = |t: GraspType| {
        type_rule::approach_by_rule(&shape, t, points, up.as_ref(), hints.viewpoint.as_ref())
    };
    let rule_approach = rule_approach_for(grasp.grasp_type);
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
        None => hints
            .detected_attention
            .map(|p| index.nearest_one(&p))
            .filter(|&(_, d)| d <= MAX_ATTENTION_DISTANCE)
            .map_or_else(
                || type_rule::attention_point_by_rule(&shape, points, &rule_approach),
                |(i, _)| i,
            ),
    };
    let (p_att, n_att) = (points[att], normals.get(att));
    if type_source != TypeSource::Model {
        type_scores[requested.index()] = 1.0;
    }
    let t_type = t.elapsed().as_secs_f64();

    let approach_prefs = |g: &ResolvedGrasp| {
        let mut prefs = vec![-n_att, rule_approach_for(g.grasp_type)];
        if let Some(u) = up {
            prefs.push(-u);
        }
        prefs.push(-Vector3::z());
        prefs
    };
    let base = SearchContext {
        points,
        normals: &normals,
        index: &index,
        shape: &shape,
        hand: &hand,
        grasp: &grasp,
        p_att,
        n_att,
        plane: scene.plane,
        options: &options,
        cos_friction: options.friction.atan().cos(),
        // A hand with kinematics is placed, closed and checked by the final-configuration
        // search; its stage 1 does not pose the parametric hand.
        collision_checks: options.check_collisions && kinematics.is_none(),
        approach_prefs: approach_prefs(&grasp),
    };
    let no_contacts = || FieldError::new("cloud", "no candidate contacts near the attention point");
    let given = if hints.parallel_grasp.is_some() {
        Some("hints.parallel_grasp")
    } else {
        (options.mode == PlannerMode::LearnedQuality).then_some("options.mode")
    };
    if let Some(field) = given
        && kinematics.is_none()
    {
        return Err(FieldError::new(
            field,
            format!(
                "hand '{}' has no kinematic model: a grasp straight down is realised with the \
                 hand's joints",
                hand.name
            ),
        )
        .into());
    }
    let (mut plan, t, grasp) = match kinematics.as_deref() {
        None => {
            let ctx = &base;
            let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
            let outcome = dual_stage::search(ctx, &mut rng).ok_or_else(no_contacts)?;
            let t = Instant::now();
            let mut plan = assemble(ctx, &outcome, &outcome.contacts, &scene, &options)?;
            plan.candidates = std::iter::once(&outcome.contacts)
                .chain(&outcome.alternatives)
                .take(options.candidates)
                .map(|c| {
                    if c == &outcome.contacts {
                        Ok(GraspCandidate::of(&plan))
                    } else {
                        assemble(ctx, &outcome, c, &scene, &options).map(|p| GraspCandidate::of(&p))
                    }
                })
                .collect::<Result<_, PlanError>>()?;
            (plan, t, grasp.clone())
        }
        Some(model)
            if hints.parallel_grasp.is_some() || options.mode == PlannerMode::LearnedQuality =>
        {
            let r = learned_planner::Request {
                base: &base,
                scene: &scene,
                index: &index,
                model,
                hand: &hand,
                up,
            };
            match (&hints.parallel_grasp, &grasp_quality) {
                (Some(g), _) => learned_planner::given_grasp(&r, g)?,
                (None, Some(network)) => learned_planner::learned_quality(&r, network)?,
                (None, None) => {
                    return Err(FieldError::new(
                        "options.mode",
                        "learned_quality needs the grasp-quality network, and graspd runs \
                         without one (--grasp-quality-model none)",
                    )
                    .into());
                }
            }
        }
        Some(model) => {
            // The detected type first, then (unless the caller forced one) the other types the
            // hand realises, most probable first, while none of them gives a firm grasp
            // (`plausible_types`): the hand's own plans decide between them.
            let types = if type_source == TypeSource::Request {
                vec![grasp.clone()]
            } else {
                plausible_types(&hand, &grasp, &type_scores)
            };
            let mut tried: Vec<TypeAttempt> = Vec::new();
            for g in types {
                let ctx = base.for_grasp(&g, approach_prefs(&g));
                // The caller's attention point binds; the detector's is one of two starts.
                let centre = hints.attention_point.is_none().then(|| {
                    let rule = rule_approach_for(g.grasp_type);
                    type_rule::attention_point_by_rule(&shape, points, &rule)
                });
                let (oppositions, ok, s1, reason) =
                    dual_stage::opposition_stage_about(&ctx, centre, options.seed);
                if oppositions.is_empty() {
                    continue;
                }
                let t = Instant::now();
                let finals =
                    final_configuration::search(&ctx, model, &oppositions, options.candidates)?;
                let s2 = final_configuration::stage_stats(&finals, t.elapsed().as_secs_f64());
                let attempt = TypeAttempt {
                    grasp: g,
                    oppositions,
                    finals,
                    stats: (s1, s2, ok, reason),
                    started: t,
                };
                let firm = attempt.firm();
                tried.push(attempt);
                if firm {
                    break;
                }
            }
            let Some(best) = type_choice::best(&tried) else {
                return Err(no_contacts().into());
            };
            let chosen = tried.swap_remove(best);
            let ctx = base.for_grasp(&chosen.grasp, approach_prefs(&chosen.grasp));
            let plan = final_plan(
                &ctx,
                &chosen.finals,
                &scene,
                model,
                chosen.stats,
                &chosen.oppositions,
            )?;
            (plan, chosen.started, chosen.grasp)
        }
    };
    if grasp.grasp_type != requested {
        warnings.push(format!(
            "{requested} mapped to {} for hand '{}'",
            grasp.grasp_type, hand.name
        ));
    }
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
        stage1: plan.stage1.seconds,
        stage2: plan.stage2.seconds,
        finalize: t.elapsed().as_secs_f64(),
        total: t_start.elapsed().as_secs_f64(),
    };
    Ok(plan)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field_of(o: &PlannerOptions) -> Option<String> {
        o.validate().err().map(|e| e.field)
    }

    /// The defaults pass; each bound refuses what is out of it, naming the option.
    #[test]
    fn option_bounds_name_the_option() {
        assert_eq!(field_of(&PlannerOptions::default()), None);
        type Case = (&'static str, fn(&mut PlannerOptions));
        let cases: [Case; 9] = [
            ("options.friction", |o| o.friction = 7.0),
            ("options.friction", |o| o.friction = 0.0),
            ("options.stage1_weights", |o| o.stage1_weights = [-0.5, 1.0]),
            ("options.stage2_weights", |o| o.stage2_weights = [0.0, 0.0]),
            ("options.iteration_fraction", |o| o.iteration_fraction = 0.0),
            ("options.max_iterations", |o| {
                o.max_iterations = MAX_ITERATIONS + 1
            }),
            ("options.min_iterations", |o| {
                o.max_iterations = 10;
                o.min_iterations = 11
            }),
            ("options.opposition_candidates", |o| {
                o.opposition_candidates = 7
            }),
            ("options.squeeze_depth", |o| o.squeeze_depth = f64::NAN),
        ];
        for (field, set) in cases {
            let mut o = PlannerOptions::default();
            set(&mut o);
            assert_eq!(field_of(&o).as_deref(), Some(field), "{o:?}");
        }
    }
}
