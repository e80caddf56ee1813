//! Reaching trajectories (dissertation §3.3, Algorithm 2): the hand's way from where it is to a
//! grasp, shaped like a human reach and kept clear of the other objects and the table.
//!
//! 1. **Forward model** ([`impedance`], Eq 3.7–3.10): the impedance model with the
//!    dissertation's M, C, K, its attractor on the pre-grasp point, driven by the virtual human
//!    control f learned from demonstrations ([`forcing_term`], Eq 3.9; the built-in
//!    demonstration is a synthesised minimum-jerk reach) — alone it retraces the demonstrated
//!    reach, scaled and turned onto this one.
//! 2. **Inverse model by MPC** ([`ilqr`], Eq 3.13–3.18): at every step an H-step iLQR finds the
//!    robot control u that keeps the hand's sphere `min_clearance` + a margin from each
//!    obstacle box and above the table with the least control, and, once the horizon reaches
//!    the end, brings it to rest on the pre-grasp point; the first control is applied.
//! 3. **Approach**: from the pre-grasp point along the plan's approach to the grasp pose, a
//!    straight minimum-jerk stretch (the planner cleared it of the object).
//!
//! The orientation turns from the start's to the grasp's with the reach's progress along its
//! line. The result is time-parameterised (poses, velocities, times); its clearances are
//! measured on the samples, and a reach that cannot keep `min_clearance` from an obstacle is
//! refused naming that obstacle. Deterministic: nothing is random.

pub mod forcing_term;
pub mod ilqr;
pub mod impedance;
pub mod obstacles;
pub mod scene_boxes;

use crate::error::FieldError;
use forcing_term::{Demonstration, ForcingTerm, phase, reach_frame};
use ilqr::{ReachCost, optimise};
use impedance::{ImpedanceModel, State, StepInput};
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
pub use obstacles::{Obstacle, Scene};

/// Settings of a reach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReachOptions {
    /// Duration of the reach to the pre-grasp point, s.
    pub reach_duration: f64,
    /// Duration of the approach from the pre-grasp point to the grasp, s.
    pub approach_duration: f64,
    /// Time between samples (and the model's step), s.
    pub time_step: f64,
    /// MPC horizon, steps.
    pub horizon: usize,
    /// Least clearance between the hand's sphere and any obstacle, m.
    pub min_clearance: f64,
}

impl Default for ReachOptions {
    fn default() -> Self {
        Self {
            reach_duration: 1.5,
            approach_duration: 0.6,
            time_step: 0.01,
            horizon: 30,
            min_clearance: 0.01,
        }
    }
}

/// A reach to plan: from the hand's `start` pose to the grasp pose `goal` (both the hand frame
/// in the world), the last `pregrasp_distance` m along `approach` (the direction the hand moves
/// in, toward the object).
#[derive(Debug, Clone)]
pub struct ReachRequest {
    pub start: Isometry3<f64>,
    pub goal: Isometry3<f64>,
    pub approach: Vector3<f64>,
    pub pregrasp_distance: f64,
    pub scene: Scene,
    /// Empty: the built-in demonstration.
    pub demonstrations: Vec<Demonstration>,
    pub options: ReachOptions,
}

/// One sample of the trajectory: its time from the start (s), the hand pose and its linear
/// velocity (m/s, world).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReachSample {
    pub time: f64,
    pub pose: Isometry3<f64>,
    pub velocity: Vector3<f64>,
}

/// A planned reach.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    pub samples: Vec<ReachSample>,
    /// Least clearance of the hand's sphere to an obstacle over the samples, m, and which
    /// obstacle (None without obstacles).
    pub obstacle_clearance: Option<(f64, usize)>,
    /// Least height of the hand frame's origin above the table over the samples, m.
    pub table_clearance: Option<f64>,
    /// How far the reach ends from the pre-grasp point, m (the approach starts where it ends).
    pub reach_error: f64,
}

/// Most obstacles a reach keeps clear of (each costs every MPC step).
pub const MAX_OBSTACLES: usize = 64;
/// Most demonstrations, and most samples in one.
pub const MAX_DEMONSTRATIONS: usize = 16;
pub const MAX_DEMONSTRATION_SAMPLES: usize = 10_000;
/// Most model steps of a reach (`reach_duration / time_step`) and longest MPC horizon: with
/// [`MAX_OBSTACLES`] they bound one request's CPU (at all three bounds, 64 boxes off the path:
/// 1.5 s on one core of the 2-core machine; the defaults take 2–5 ms).
pub const MAX_REACH_STEPS: usize = 2000;
pub const MAX_HORIZON: usize = 100;
/// Defaults of a request's optional fields: the approach's length (m) and the hand's radius (m).
pub const DEFAULT_PREGRASP_DISTANCE: f64 = 0.1;
pub const DEFAULT_HAND_RADIUS: f64 = 0.05;

/// How far past `min_clearance` the obstacle penalty reaches, m.
const SAFETY_MARGIN: f64 = 0.02;

/// Plans the reach (module doc). Bad input and reaches that cannot keep clear are refused
/// naming the field.
pub fn plan_reach(req: &ReachRequest) -> Result<Trajectory, FieldError> {
    validate(req)?;
    let o = req.options;
    let model = ImpedanceModel::default();
    let up = req.scene.table.map_or(Vector3::z(), |t| t.normal);
    // The built-in demonstration's weights are learned once per process, a request's own
    // demonstrations with each request.
    static BUILT_IN: std::sync::OnceLock<ForcingTerm> = std::sync::OnceLock::new();
    let learned;
    let forcing = if req.demonstrations.is_empty() {
        BUILT_IN.get_or_init(|| {
            ForcingTerm::learn(&model, &[Demonstration::minimum_jerk()], &Vector3::z())
                .expect("the built-in demonstration is valid")
        })
    } else {
        learned = ForcingTerm::learn(&model, &req.demonstrations, &up)?;
        &learned
    };
    let start = req.start.translation.vector;
    let grasp = req.goal.translation.vector;
    let approach = req.approach.normalize();
    let pre = grasp - approach * req.pregrasp_distance;
    let line = pre - start;
    let length = line.norm();
    let frame = reach_frame(&line, &up);
    let dt = o.time_step;
    let n = (o.reach_duration / dt).round().max(1.0) as usize;
    let tau = o.reach_duration / forcing.duration;
    let steps: Vec<StepInput> = (0..n)
        .map(|k| StepInput {
            u: Vector3::zeros(),
            f: length * (frame * forcing.at_phase(phase(k as f64 * dt, forcing.duration, tau))),
            goal: pre,
            tau,
            dt,
        })
        .collect();
    let cost = ReachCost {
        scene: &req.scene,
        control: 1e-4,
        penalty: 1e5,
        safe_distance: o.min_clearance + SAFETY_MARGIN,
        table_margin: o.min_clearance,
        end: Point3::from(pre),
        end_position: 1e5,
        end_velocity: 1e2,
    };
    let turn = |p: &Vector3<f64>| -> UnitQuaternion<f64> {
        let progress = if length > 1e-9 {
            ((p - start).dot(&line) / (length * length)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        req.start.rotation.slerp(&req.goal.rotation, progress)
    };
    let sample =
        |time: f64, p: Vector3<f64>, v: Vector3<f64>, r: UnitQuaternion<f64>| ReachSample {
            time,
            pose: Isometry3::from_parts(p.into(), r),
            velocity: v,
        };
    let mut samples = vec![sample(0.0, start, Vector3::zeros(), req.start.rotation)];
    // Algorithm 2, lines 6–11: the MPC loop, warm-started from the last horizon's controls.
    let mut z = State::zeros();
    z.fixed_rows_mut::<3>(0).copy_from(&start);
    let mut u = vec![Vector3::zeros(); n];
    if length > 1e-6 {
        for k in 0..n {
            let end = (k + o.horizon).min(n);
            let best = optimise(
                &model,
                &steps[k..end],
                &z,
                u[k..end].to_vec(),
                &cost,
                end == n,
            );
            u[k..end].copy_from_slice(&best);
            z = model.step(
                &z,
                &StepInput {
                    u: u[k],
                    ..steps[k]
                },
            );
            let p = z.fixed_rows::<3>(0).into_owned();
            samples.push(sample(
                (k + 1) as f64 * dt,
                p,
                z.fixed_rows::<3>(3).into_owned(),
                turn(&p),
            ));
        }
    }
    let reached = samples.last().expect("the start").pose.translation.vector;
    let reach_error = (reached - pre).norm();
    append_approach(
        &mut samples,
        &grasp,
        &req.goal.rotation,
        o.approach_duration,
        dt,
    );
    measured(samples, &req.scene, o.min_clearance, reach_error)
}

/// The approach: from where the reach ended, a straight minimum-jerk stretch of `duration` s
/// onto the grasp at `grasp`, turned as the grasp.
fn append_approach(
    samples: &mut Vec<ReachSample>,
    grasp: &Vector3<f64>,
    rotation: &UnitQuaternion<f64>,
    duration: f64,
    dt: f64,
) {
    let last = *samples.last().expect("the start");
    let from = last.pose.translation.vector;
    let travel = grasp - from;
    let m = (duration / dt).round().max(1.0) as usize;
    for k in 1..=m {
        let s = k as f64 / m as f64;
        let along = 10.0 * s.powi(3) - 15.0 * s.powi(4) + 6.0 * s.powi(5);
        let speed = (30.0 * s * s - 60.0 * s.powi(3) + 30.0 * s.powi(4)) / duration;
        samples.push(ReachSample {
            time: last.time + k as f64 * dt,
            pose: Isometry3::from_parts((from + along * travel).into(), *rotation),
            velocity: speed * travel,
        });
    }
}

/// The trajectory with its clearances measured on its samples; refused naming the obstacle it
/// comes closer to than `min_clearance`, or the table it passes under.
fn measured(
    samples: Vec<ReachSample>,
    scene: &Scene,
    min_clearance: f64,
    reach_error: f64,
) -> Result<Trajectory, FieldError> {
    let points: Vec<Point3<f64>> = samples
        .iter()
        .map(|s| Point3::from(s.pose.translation.vector))
        .collect();
    let obstacle_clearance = points
        .iter()
        .filter_map(|p| scene.obstacle_clearance(p).map(|(c, i, _)| (c, i)))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    let table_clearance = points
        .iter()
        .filter_map(|p| scene.table_height(p))
        .min_by(f64::total_cmp);
    if let Some((c, i)) = obstacle_clearance
        && c < min_clearance - 1e-6
    {
        return Err(FieldError::new(
            format!("obstacles[{i}]"),
            format!(
                "no reach found that keeps {:.0} mm from it (closest {:.1} mm): it blocks the \
                 way to the goal",
                min_clearance * 1e3,
                c * 1e3
            ),
        ));
    }
    if let Some(h) = table_clearance
        && h < -1e-6
    {
        return Err(FieldError::new(
            "support_plane",
            format!(
                "the reach passes {:.1} mm below the table on its way",
                -h * 1e3
            ),
        ));
    }
    Ok(Trajectory {
        samples,
        obstacle_clearance,
        table_clearance,
        reach_error,
    })
}

/// Every rule of a reach request, naming the field.
fn validate(req: &ReachRequest) -> Result<(), FieldError> {
    let finite_pose = |p: &Isometry3<f64>| {
        p.translation.vector.iter().all(|c| c.is_finite())
            && p.rotation.coords.iter().all(|c| c.is_finite())
    };
    if !finite_pose(&req.start) {
        return Err(FieldError::new("start", "must be finite"));
    }
    if !finite_pose(&req.goal) {
        return Err(FieldError::new("goal", "must be finite"));
    }
    let a = req.approach;
    if !a.iter().all(|c| c.is_finite()) || a.norm() < 1e-9 {
        return Err(FieldError::new(
            "approach",
            "must be a finite non-zero vector",
        ));
    }
    if !(req.pregrasp_distance.is_finite() && (0.0..=1.0).contains(&req.pregrasp_distance)) {
        return Err(FieldError::new(
            "pregrasp_distance",
            "must be within [0, 1] m",
        ));
    }
    let o = &req.options;
    let range = |v: f64, lo: f64, hi: f64, field: &str| {
        if v.is_finite() && (lo..=hi).contains(&v) {
            Ok(())
        } else {
            Err(FieldError::new(
                format!("options.{field}"),
                format!("must be within [{lo}, {hi}], got {v}"),
            ))
        }
    };
    range(o.time_step, 0.001, 0.05, "time_step")?;
    range(o.reach_duration, 0.1, 20.0, "reach_duration")?;
    range(o.approach_duration, 0.05, 10.0, "approach_duration")?;
    range(o.min_clearance, 0.0, 0.5, "min_clearance")?;
    range(o.horizon as f64, 1.0, MAX_HORIZON as f64, "horizon")?;
    let steps = o.reach_duration / o.time_step;
    if steps > MAX_REACH_STEPS as f64 + 0.5 {
        return Err(FieldError::new(
            "options.time_step",
            format!(
                "reach_duration / time_step = {steps:.0} steps, more than {MAX_REACH_STEPS}: \
                 take a longer step"
            ),
        ));
    }
    range(req.scene.hand_radius, 0.0, 0.5, "hand_radius")?;
    if req.scene.obstacles.len() > MAX_OBSTACLES {
        return Err(FieldError::new(
            "obstacles",
            format!(
                "{} obstacles, more than {MAX_OBSTACLES}",
                req.scene.obstacles.len()
            ),
        ));
    }
    if req.demonstrations.len() > MAX_DEMONSTRATIONS {
        return Err(FieldError::new(
            "demonstrations",
            format!(
                "{} demonstrations, more than {MAX_DEMONSTRATIONS}",
                req.demonstrations.len()
            ),
        ));
    }
    if let Some(i) = req
        .demonstrations
        .iter()
        .position(|d| d.positions.len() > MAX_DEMONSTRATION_SAMPLES)
    {
        return Err(FieldError::new(
            format!("demonstrations[{i}].positions"),
            format!("more than {MAX_DEMONSTRATION_SAMPLES} samples"),
        ));
    }
    for (i, ob) in req.scene.obstacles.iter().enumerate() {
        ob.validate(&format!("obstacles[{i}]"))?;
    }
    let pre = req.goal.translation.vector - a.normalize() * req.pregrasp_distance;
    for (field, p) in [
        ("start", req.start.translation.vector),
        ("goal", req.goal.translation.vector),
        ("approach", pre),
    ] {
        let at = Point3::from(p);
        let what = if field == "approach" {
            "the pre-grasp point (the goal backed off along the approach)"
        } else {
            "the hand"
        };
        if let Some((c, i, _)) = req.scene.obstacle_clearance(&at)
            && c < 0.0
        {
            return Err(FieldError::new(
                field,
                format!("{what} reaches {:.1} mm into obstacles[{i}]", -c * 1e3),
            ));
        }
        if let Some(h) = req.scene.table_height(&at)
            && h < 0.0
        {
            return Err(FieldError::new(
                field,
                format!("{what} lies {:.1} mm below the table", -h * 1e3),
            ));
        }
    }
    Ok(())
}
