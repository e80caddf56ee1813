//! Plans of a two-jaw gripper coming straight down (dissertation ch. 3): a grasp the caller
//! gives (`hints.parallel_grasp`), or the one the learned quality network rates best, found by
//! Bayesian search (`options.mode = learned_quality`, §3.2.2–3.2.3, Algorithm 1 lines 5–11).
//! Either is realised with the hand's kinematics (`final_configuration::realise`).

use super::bayesian_search::{SearchOptions, bayesian_search};
use super::evaluation::SearchContext;
use super::final_configuration;
use super::grasp_plan::*;
use super::grasp_quality::GraspQualityModel;
use super::grasp_quality::candidates::{features, sample_candidates};
use super::grasp_quality::crop::grasp_view;
use super::kinematic_model::KinematicModel;
use super::parallel_grasp::{ParallelGrasp, TableFrame};
use super::plan_assembly::final_plan;
use super::scene::Scene;
use crate::cloud::CloudIndex;
use crate::error::{FieldError, PlanError};
use crate::grasp_type::GraspType;
use crate::hand::{HandDescription, ResolvedGrasp};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

/// Candidate grasps the search chooses among (the domain G of Eq 3.2).
pub const POOL: usize = 300;
/// The best-rated grasps realised, in order, while the hand's kinematics find none feasible.
const REALISE_TRIES: usize = 5;

/// What both paths need of the request.
pub(super) struct Request<'a> {
    pub base: &'a SearchContext<'a>,
    pub scene: &'a Scene,
    pub index: &'a CloudIndex,
    pub model: &'a KinematicModel,
    pub hand: &'a HandDescription,
    pub up: Option<Vector3<f64>>,
}

/// A plan, when its finalisation started, and the grasp it realises.
type Planned = (GraspPlan, Instant, ResolvedGrasp);

/// The plan of the caller's grasp `g` (`hints.parallel_grasp`).
pub(super) fn given_grasp(r: &Request, g: &ParallelGrasp) -> Result<Planned, PlanError> {
    let field = "hints.parallel_grasp";
    let up = up_of(r, field)?;
    let g = g.checked(&up, field)?;
    let pinch = pinch_of(r.hand, field)?;
    let opposition = g
        .opposition(&r.scene.points, r.index, r.hand.geometry.max_aperture / 2.0)
        .ok_or_else(|| {
            FieldError::new(
                field,
                format!(
                    "the jaws' line meets no object section within the hand's opening \
                     ({:.0} mm) about the centre, or the object goes on past a jaw",
                    r.hand.geometry.max_aperture * 1e3
                ),
            )
        })?;
    let t = Instant::now();
    let plan = realise(r, &pinch, &up, &[opposition])?;
    Ok((plan, t, pinch))
}

/// The plan of the grasp the network rates best (Algorithm 1): candidates sampled on the
/// completed object, the Bayesian search over them with the network as the quality, the best
/// rated realised (the next best while the kinematics find it infeasible).
pub(super) fn learned_quality(
    r: &Request,
    network: &GraspQualityModel,
) -> Result<Planned, PlanError> {
    let field = "options.mode";
    let up = up_of(r, field)?;
    let pinch = pinch_of(r.hand, field)?;
    let options = r.base.options;
    let points = &r.scene.points;
    let visible = &points[..r.scene.visible];
    let lowest = points
        .iter()
        .min_by(|a, b| a.coords.dot(&up).total_cmp(&b.coords.dot(&up)))
        .ok_or_else(|| FieldError::new("cloud", "no object points"))?;
    let height = r.scene.plane.map_or(0.0, |pl| pl.distance(lowest));
    let table = TableFrame::under(lowest, &up, height);
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let opening = r.hand.geometry.max_aperture;
    let pool = sample_candidates(points, r.index, &table, opening, POOL, &mut rng);
    if pool.is_empty() {
        return Err(FieldError::new(
            "cloud",
            format!(
                "no grasp straight down encloses a section of the object within the hand's \
                 {:.0} mm opening",
                opening * 1e3
            ),
        )
        .into());
    }
    let feats: Vec<Vec<f64>> = pool.iter().map(|g| features(g, &table)).collect();
    let mut rated: Vec<(usize, f64)> = Vec::new();
    let search = bayesian_search(
        &feats,
        |idx| {
            let views: Vec<_> = idx
                .iter()
                .map(|&i| grasp_view(visible, &table, &pool[i]))
                .collect();
            let q = network.quality(&views)?;
            rated.extend(idx.iter().copied().zip(q.iter().copied()));
            Ok::<_, crate::perception::grasp_type::ModelError>(q)
        },
        &SearchOptions {
            seed: options.seed,
            ..Default::default()
        },
    )
    .map_err(|e| PlanError::Model(format!("the grasp-quality network: {e}")))?
    .expect("a non-empty pool");
    rated.sort_by(|a, b| b.1.total_cmp(&a.1));
    let t = Instant::now();
    // The best rated first; a plan the hand can start (with joints) beats one it cannot, a
    // feasible one ends the tries.
    let mut chosen: Option<(GraspPlan, f64)> = None;
    for &(i, q) in rated.iter().take(REALISE_TRIES) {
        let Some((_, opposition)) = pool[i].centred(points, r.index, opening / 2.0) else {
            continue;
        };
        let plan = realise(r, &pinch, &up, &[opposition])?;
        let rank = |p: &GraspPlan| (p.feasible, !p.joints.is_empty());
        if chosen.as_ref().is_none_or(|(c, _)| rank(&plan) > rank(c)) {
            chosen = Some((plan, q));
        }
        if chosen.as_ref().is_some_and(|(c, _)| c.feasible) {
            break;
        }
    }
    let Some((mut plan, probability)) = chosen else {
        return Err(
            FieldError::new("cloud", "no rated grasp encloses a section of the object").into(),
        );
    };
    plan.learned_quality = Some(LearnedQuality {
        probability,
        posterior_mean: search.posterior_mean,
        posterior_std: search.posterior_std,
        network_calls: search.calls,
        candidates: pool.len(),
    });
    Ok((plan, t, pinch))
}

/// Which way is up: the support plane's normal, or the caller's `up`.
fn up_of(r: &Request, field: &str) -> Result<Vector3<f64>, FieldError> {
    r.up.ok_or_else(|| {
        FieldError::new(
            field,
            "needs a support plane or hints.up: the gripper comes straight down",
        )
    })
}

/// The pinch of a two-jaw gripper (a hand of two fingers, one each side).
fn pinch_of(hand: &HandDescription, field: &str) -> Result<ResolvedGrasp, FieldError> {
    hand.resolve_forced(GraspType::Pinch)
        .filter(|p| hand.fingers.len() == 2 && p.h1_fingers.len() == 1 && p.h2_fingers.len() == 1)
        .ok_or_else(|| {
            FieldError::new(
                field,
                format!(
                    "hand '{}' is not a two-jaw gripper (it has {} fingers): this is a two-jaw \
                     gripper's grasp",
                    hand.name,
                    hand.fingers.len()
                ),
            )
        })
}

/// The plan of the first of `oppositions` realised straight down (`-up`).
fn realise(
    r: &Request,
    pinch: &ResolvedGrasp,
    up: &Vector3<f64>,
    oppositions: &[(usize, usize)],
) -> Result<GraspPlan, PlanError> {
    let ctx = r.base.for_grasp(pinch, vec![-up]);
    let t = Instant::now();
    let finals: Vec<_> = final_configuration::realise(&ctx, r.model, oppositions[0], &-up)?
        .into_iter()
        .collect();
    let s2 = final_configuration::stage_stats(&finals, t.elapsed().as_secs_f64());
    final_plan(
        &ctx,
        &finals,
        r.scene,
        r.model,
        (StageStats::default(), s2, true, None),
        oppositions,
    )
}
