//! `graspd-sim label-grasps`: physics labels for the learned parallel-jaw quality (issue 18
//! part 2, dissertation §3.2.2) — sampled 2F-85 grasps executed in MuJoCo, each with the
//! network's view of it.
//!
//! Label protocol, per scene (seed s): one object — a shared YCB object or a generated
//! primitive (`object::primitive`), alternately — placed as the standard run places it
//! (±`place_range`, any yaw); one RGB-D frame from the standard camera; the object's visible
//! points (the pixels whose geom is the object's) with the table (z = 0) and the camera's
//! position are what graspd's planner would see (`grasp_quality::candidates::object_from_view`).
//! `per_scene` grasps g are sampled on it (`sample_candidates`), each realised by graspd-core's
//! planner straight down (`hints.parallel_grasp`, the hand's MJCF kinematics) and executed from
//! a fresh copy of the scene as a trial executes a plan: approach, guarded close, squeeze,
//! lift 10 cm, hold 2 s, shake (no gravity test). The label is the trial's success. A grasp the
//! planner cannot realise (an error: no section between the jaws) is dropped; one it realises
//! but marks infeasible is executed all the same (the label is physics', not graspd's).
//!
//! Writes `crop.npy` (float32 [N, 2, 32, 32]), `configuration.npy` (float32 [N, 1]),
//! `label.npy` (uint8 [N]), `meta.jsonl` (scene, object, g, feasibility, outcome per sample)
//! and `summary.json` (counts and the time it took) to `out`.

use crate::SimError;
use crate::bench::{in_parallel, trials_bar};
use crate::hand::SimHand;
use crate::object::{SimObject, primitive};
use crate::record::{Outcome, TrialRecord};
use crate::scene::{Scene, on_table};
use crate::service::PlanResult;
use crate::trial::{Trial, TrialOptions, execute, placement};
use graspd_core::cloud::{CloudIndex, Plane, PointCloud};
use graspd_core::hand::kinematics::KinematicHand;
use graspd_core::planning::grasp_quality::candidates::{object_from_view, sample_candidates};
use graspd_core::planning::grasp_quality::crop::{CHANNELS, CROP, grasp_view};
use graspd_core::planning::parallel_grasp::{ParallelGrasp, TableFrame};
use graspd_core::planning::{KinematicModel, PlanHints, PlanInput, PlannerOptions, plan};
use nalgebra::{Point3, Vector3};
use rand::SeedableRng;
use serde::Serialize;
use std::io::Write;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// What to label.
#[derive(Debug, Clone)]
pub struct LabelConfig {
    /// The parallel gripper (an MJCF hand whose pinch is between two single jaws).
    pub hand: String,
    /// YCB objects the scenes alternate with primitives.
    pub objects: Vec<String>,
    pub scenes: usize,
    pub per_scene: usize,
    /// Seed of the first scene (scene i uses seed + i).
    pub seed: u64,
    pub jobs: usize,
    pub out: PathBuf,
    pub hands_dir: PathBuf,
    pub objects_dir: PathBuf,
    pub options: TrialOptions,
}

/// One labelled grasp.
#[derive(Debug, Clone, Serialize)]
pub struct LabelRecord {
    pub scene_seed: u64,
    pub object: String,
    /// g = {x, y, z, θ} in the world (the table at z = 0), m and rad.
    pub g: [f64; 4],
    pub feasible: bool,
    pub robustness: f64,
    pub outcome: &'static str,
    pub label: u8,
    pub plan_ms: f64,
    pub sim_ms: f64,
    /// The network's view of the grasp (`grasp_view`).
    #[serde(skip)]
    pub crop: Vec<f32>,
    #[serde(skip)]
    pub configuration: [f32; 1],
}

/// What a run did.
#[derive(Debug, Serialize)]
pub struct LabelSummary {
    pub hand: String,
    pub scenes: usize,
    pub samples: usize,
    pub positives: usize,
    /// Sampled grasps the planner could not realise (dropped).
    pub dropped: usize,
    pub jobs: usize,
    pub wall_s: f64,
    /// Seconds per label on one core (wall × jobs / samples).
    pub core_s_per_label: f64,
}

/// Runs the labelling and writes its files (module docs).
pub fn label_grasps(config: &LabelConfig) -> Result<LabelSummary, SimError> {
    std::fs::create_dir_all(&config.out)
        .map_err(|e| SimError::Input(format!("--out {}: {e}", config.out.display())))?;
    let (records, summary) = label_scenes(config)?;
    write_samples(&config.out, &records)?;
    let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
    std::fs::write(config.out.join("summary.json"), json)
        .map_err(|e| SimError::Input(format!("--out: {e}")))?;
    Ok(summary)
}

/// The labelled grasps of `config`'s scenes, in scene order, and what the run did.
pub fn label_scenes(config: &LabelConfig) -> Result<(Vec<LabelRecord>, LabelSummary), SimError> {
    let hand = SimHand::load(&config.hand, &config.hands_dir)?;
    let kinematic = KinematicHand::from_mjcf_file(&hand.model)
        .map_err(|e| SimError::Input(format!("--hand {}: {e}", config.hand)))?;
    let model = Arc::new(
        KinematicModel::new(kinematic)
            .map_err(|e| SimError::Input(format!("--hand {}: {e}", config.hand)))?,
    );
    let description = model
        .describe()
        .map_err(|e| SimError::Input(format!("--hand {}: {e}", config.hand)))?;
    let ycb: Vec<SimObject> = config
        .objects
        .iter()
        .map(|o| SimObject::load(&config.objects_dir, o))
        .collect::<Result<_, _>>()?;
    let scenes: Vec<u64> = (0..config.scenes as u64).map(|i| config.seed + i).collect();
    let bar = trials_bar((config.scenes * config.per_scene) as u64);
    let records: Mutex<Vec<LabelRecord>> = Mutex::new(Vec::new());
    let dropped = Mutex::new(0usize);
    let errors: Mutex<Vec<SimError>> = Mutex::new(Vec::new());
    let t0 = std::time::Instant::now();
    in_parallel(config.jobs, &scenes, |&seed| {
        // Even scenes a YCB object in turn, odd ones a primitive.
        let object = if seed % 2 == 0 && !ycb.is_empty() {
            ycb[(seed / 2) as usize % ycb.len()].clone()
        } else {
            primitive(seed)
        };
        match label_scene(config, &hand, &model, &description, &object, seed) {
            Ok((mut recs, d)) => {
                bar.inc(config.per_scene as u64);
                *dropped.lock().expect("dropped") += d;
                records.lock().expect("records").append(&mut recs);
            }
            Err(e) => errors.lock().expect("errors").push(e),
        }
    });
    bar.finish_and_clear();
    if let Some(e) = errors.into_inner().expect("errors").into_iter().next() {
        return Err(e);
    }
    let mut records = records.into_inner().expect("records");
    records.sort_by(|a, b| {
        (a.scene_seed, a.g.map(f64::to_bits)).cmp(&(b.scene_seed, b.g.map(f64::to_bits)))
    });
    let wall_s = t0.elapsed().as_secs_f64();
    let summary = LabelSummary {
        hand: hand.name.clone(),
        scenes: config.scenes,
        samples: records.len(),
        positives: records.iter().filter(|r| r.label == 1).count(),
        dropped: dropped.into_inner().expect("dropped"),
        jobs: config.jobs,
        wall_s,
        core_s_per_label: wall_s * config.jobs.max(1) as f64 / records.len().max(1) as f64,
    };
    Ok((records, summary))
}

/// One scene's labels and how many sampled grasps were dropped.
fn label_scene(
    config: &LabelConfig,
    hand: &SimHand,
    model: &Arc<KinematicModel>,
    description: &graspd_core::hand::HandDescription,
    object: &SimObject,
    seed: u64,
) -> Result<(Vec<LabelRecord>, usize), SimError> {
    let scene = Scene::build(hand, &[(object, on_table(0.0, 0.0, 0.0))])?;
    let place = placement(seed, config.options.place_range);
    let mut looked = Trial::new(&scene, place);
    let image = looked.render(config.options.intrinsics, config.options.camera);
    let body = scene.object_bodies[0];
    let seen = image.points_of(|g| scene.model.geom_bodyid()[g] as usize == body);
    let plane = Plane::through(&Point3::origin(), Vector3::z());
    let eye = Point3::from(image.camera_to_world.translation.vector);
    let (visible, completed) = object_from_view(&seen, &plane, &eye);
    if visible.len() < 20 {
        return Ok((Vec::new(), config.per_scene));
    }
    let table = TableFrame::under(&Point3::origin(), &Vector3::z(), 0.0);
    let index = CloudIndex::new(&completed);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x001a_be15);
    let grasps = sample_candidates(
        &completed,
        &index,
        &table,
        description.geometry.max_aperture,
        config.per_scene,
        &mut rng,
    );
    let mut dropped = config.per_scene - grasps.len();
    let mut out = Vec::new();
    for (k, g) in grasps.iter().enumerate() {
        let t_plan = std::time::Instant::now();
        let planned = plan(PlanInput {
            cloud: PointCloud::new(seen.clone()),
            hand: description.clone(),
            hints: PlanHints {
                support_plane: Some(plane),
                viewpoint: Some(eye),
                parallel_grasp: Some(*g),
                ..Default::default()
            },
            options: PlannerOptions {
                seed: seed * 100 + k as u64,
                squeeze_depth: hand.squeeze_depth,
                ..Default::default()
            },
            kinematics: Some(model.clone()),
            grasp_quality: None,
        });
        let plan_ms = t_plan.elapsed().as_secs_f64() * 1e3;
        let Ok(p) = planned else {
            dropped += 1;
            continue;
        };
        let result = PlanResult {
            response: graspd_api::convert::plan::plan_to_proto(&p),
            latency: plan_ms / 1e3,
        };
        let t_sim = std::time::Instant::now();
        let mut trial = Trial::new(&scene, place);
        let start = trial.object_position();
        let mut rec = TrialRecord::empty(hand, &object.name, seed, place);
        let mut opts = config.options;
        opts.gravity_test = false;
        let outcome = execute(&mut trial, &result, start, &opts, &mut rec);
        let view = grasp_view(&visible, &table, g);
        out.push(LabelRecord {
            scene_seed: seed,
            object: object.name.clone(),
            g: configuration_of(g),
            feasible: p.feasible,
            robustness: p.quality.robustness,
            outcome: outcome.name(),
            label: u8::from(outcome == Outcome::Success),
            plan_ms,
            sim_ms: t_sim.elapsed().as_secs_f64() * 1e3,
            crop: view.crop,
            configuration: view.configuration,
        });
    }
    Ok((out, dropped))
}

/// g = {x, y, z, θ} of a grasp on the world's table (z = 0), θ in [0, π).
fn configuration_of(g: &ParallelGrasp) -> [f64; 4] {
    let theta = g.axis.y.atan2(g.axis.x).rem_euclid(std::f64::consts::PI);
    [g.centre.x, g.centre.y, g.centre.z, theta]
}

/// The samples as `.npy` arrays and JSON lines (module docs).
fn write_samples(dir: &std::path::Path, records: &[LabelRecord]) -> Result<(), SimError> {
    let io = |e: std::io::Error| SimError::Input(format!("--out {}: {e}", dir.display()));
    let n = records.len();
    let mut crop = graspd_testkit::npy::npy_header("<f4", &[n, CHANNELS, CROP, CROP]);
    let mut configuration = graspd_testkit::npy::npy_header("<f4", &[n, 1]);
    let mut label = graspd_testkit::npy::npy_header("|u1", &[n]);
    let mut meta = Vec::new();
    for r in records {
        crop.extend(r.crop.iter().flat_map(|v| v.to_le_bytes()));
        configuration.extend(r.configuration.iter().flat_map(|v| v.to_le_bytes()));
        label.push(r.label);
        serde_json::to_writer(&mut meta, r).expect("record serialises");
        meta.push(b'\n');
    }
    for (name, bytes) in [
        ("crop.npy", crop),
        ("configuration.npy", configuration),
        ("label.npy", label),
        ("meta.jsonl", meta),
    ] {
        std::fs::File::create(dir.join(name))
            .and_then(|mut f| f.write_all(&bytes))
            .map_err(io)?;
    }
    Ok(())
}
