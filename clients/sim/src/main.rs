//! `graspd-sim`: grasp trials in MuJoCo through a running graspd (see the crate README).

use clap::{Parser, Subcommand};
use graspd_sim::SimError;
use graspd_sim::bench::{BenchConfig, run_bench};
use graspd_sim::camera::{Intrinsics, default_view};
use graspd_sim::hand::SimHand;
use graspd_sim::object::SimObject;
use graspd_sim::scene::Scene;
use graspd_sim::service::Service;
use graspd_sim::trial::{TrialOptions, placement, run_trial};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "graspd-sim",
    version,
    about = "Grasp YCB objects with MuJoCo hand models through graspd"
)]
struct Cli {
    /// graspd's gRPC address.
    #[arg(
        long,
        env = "GRASPD_ADDR",
        default_value = "http://127.0.0.1:50051",
        global = true
    )]
    graspd: String,
    /// Folder with hands/ and objects/ (../shared/testdata in a checkout).
    #[arg(
        long,
        env = "GRASPD_TESTDATA",
        default_value = "../shared/testdata",
        global = true
    )]
    testdata: PathBuf,
    /// Camera image size, WIDTHxHEIGHT (intrinsics scale with the width).
    #[arg(long, default_value = "640x480", global = true)]
    image: String,
    /// Plan on the object's points (a cloud) instead of the RGB-D frame.
    #[arg(long, global = true)]
    cloud: bool,
    /// Extra PlanGrasp calls with other seeds when graspd marks a plan infeasible.
    #[arg(long, default_value_t = 2, global = true)]
    replans: usize,
    /// Close open loop, the commands as planned (default: guarded — each actuator stops where
    /// what it moves touches the object and squeezes from there).
    #[arg(long, global = true)]
    open_loop: bool,
    /// Keep the grip of the close when the object slides in the lift (default: grip harder in
    /// the plan's proportions, as a hand with tactile sensing does; `grip_reflex.rs`).
    #[arg(long, global = true)]
    no_grip_reflex: bool,
    /// Execute the plan ranked this far down graspd's candidates (0: the best), as a robot
    /// stack falling back would.
    #[arg(long, default_value_t = 0, global = true)]
    candidate: usize,
    /// Force a grasp type (large_wrap, small_wrap, power, pinch, precision, tripod) instead of
    /// graspd's detection.
    #[arg(long, global = true, value_parser = parse_grasp_type)]
    grasp_type: Option<graspd_proto::v1::GraspType>,
    /// graspd's planner mode (dual_stage, without_opposition, learned_quality: ch. 3's learned
    /// parallel-jaw quality, for a two-jaw gripper).
    #[arg(long, global = true, value_parser = parse_mode)]
    mode: Option<graspd_proto::v1::PlannerMode>,
    /// Half-width of the square on the table the object is placed in (any yaw), m.
    #[arg(long, default_value_t = graspd_sim::trial::PLACE_RANGE, global = true)]
    place_range: f64,
    /// Views of the scene per PlanGrasp: the benchmark camera and views − 1 more around the
    /// table, fused by graspd (`extra_views`).
    #[arg(long, default_value_t = 1, global = true)]
    views: usize,
    /// Skip the six-direction gravity test after the hold.
    #[arg(long, global = true)]
    skip_gravity_test: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// One trial; prints its record as JSON.
    Trial {
        /// Built-in hand (robotiq_2f85, barrett, shadow, allegro), a hand TOML file or an MJCF
        /// model (.xml, derived).
        #[arg(long)]
        hand: String,
        /// YCB object name, e.g. tomato_soup_can.
        #[arg(long)]
        object: String,
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// The tactile closed loop under a disturbance: each trial once with graspd's Stabilize
    /// setting the grip force and once at constant force; writes stabilize.json and
    /// stabilize.md to --out.
    Stabilize {
        /// A hand with tactile_bodies (built-in: robotiq_2f85).
        #[arg(long, default_value = "robotiq_2f85")]
        hand: String,
        #[command(flatten)]
        runs: Runs,
        /// Static safety factor of the initial grip force.
        #[arg(long, default_value_t = 1.5)]
        safety: f64,
        /// Added load on the object at its full value, in object weights.
        #[arg(long, default_value_t = 1.0)]
        pulse: f64,
        /// Time the load takes to rise to its full value, and then stays, s.
        #[arg(long, default_value_t = 0.5)]
        pulse_s: f64,
        /// δf_s of the stabilized session, in units of f0 (slip raises the force to
        /// (1 + this) · f0).
        #[arg(long, default_value_t = 1.0)]
        slip_gain: f64,
        /// f_max of the stabilized session, in units of f0 (default: 1 + slip_gain).
        #[arg(long)]
        max_force: Option<f64>,
        /// Latch slip in the stabilized session (`latch_slip`, a deviation from Eq 6.9: each
        /// slip episode raises f_d by δf_s until contact is lost).
        #[arg(long)]
        latch_slip: bool,
        /// Slip from the contact centroid's motion in the stabilized session, mm/s
        /// (`centroid_slip_mm_s`; unset: off).
        #[arg(long, value_name = "MM_S")]
        centroid_slip: Option<f64>,
        /// The pads' sensors as electrodes-only fingers: graspd gets no pac, pdc or thermal
        /// channel.
        #[arg(long)]
        electrodes_only: bool,
        #[arg(long, default_value = "sim-results")]
        out: PathBuf,
    },
    /// Trials over hands × objects; writes results.json, table.md and snapshots to --out.
    Bench {
        /// Comma-separated hands: built-in names, hand TOML files or MJCF models.
        #[arg(long, default_value = "robotiq_2f85,barrett,shadow,allegro")]
        hands: String,
        /// More hands as MJCF models (.xml), derived from the model alone (repeatable): score
        /// your own hand.
        #[arg(long = "hand-model")]
        hand_models: Vec<PathBuf>,
        #[command(flatten)]
        runs: Runs,
        /// Worker threads (default: the number of cores).
        #[arg(long)]
        jobs: Option<usize>,
        /// Output folder.
        #[arg(long, default_value = "sim-results")]
        out: PathBuf,
        /// PNG snapshots (after the hold) of the first trial of each hand and object, named
        /// HAND_OBJECT_OUTCOME.png.
        #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
        snapshots: bool,
    },
    /// Reach-to-grasp in clutter (the dissertation's Table 3.1): each target among 3–6 shared
    /// objects, found by name, reached around the others, grasped and lifted; writes
    /// results.json and table.md to --out.
    Clutter {
        /// The hand (built-in name, hand TOML or MJCF model).
        #[arg(long, default_value = "robotiq_2f85")]
        hand: String,
        /// Comma-separated target objects (the others are drawn from them too); default: the
        /// 12 shared YCB objects.
        #[arg(long)]
        objects: Option<String>,
        /// Trials per target.
        #[arg(long, default_value_t = 4)]
        trials: usize,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Worker threads (default: the number of cores).
        #[arg(long)]
        jobs: Option<usize>,
        #[arg(long, default_value = "sim-results/clutter")]
        out: PathBuf,
        /// Radius of the sphere that stands for the hand in PlanReach, m (default: graspd's).
        #[arg(long)]
        hand_radius: Option<f64>,
    },
    /// Two bench runs on the same seeds, trial by trial: per hand the counts with their 95 %
    /// intervals, the trials that flipped and McNemar's exact p-value, then the objects that
    /// changed (markdown). Needs no graspd.
    Compare {
        /// The base run's results.json.
        base: PathBuf,
        /// The new run's results.json.
        new: PathBuf,
    },
    /// Physics labels for the learned parallel-jaw quality (issue 18, ch. 3): sampled grasps
    /// straight down, each realised by graspd-core in-process and executed; writes crop.npy,
    /// configuration.npy, label.npy, meta.jsonl and summary.json to --out. Needs no graspd.
    LabelGrasps {
        /// The parallel gripper (built-in name or MJCF model).
        #[arg(long, default_value = "robotiq_2f85")]
        hand: String,
        /// Comma-separated YCB objects the scenes alternate with generated primitives, or
        /// `all`; default: all.
        #[arg(long, default_value = "all")]
        objects: String,
        /// Scenes (one object each).
        #[arg(long, default_value_t = 100)]
        scenes: usize,
        /// Grasps sampled and executed per scene.
        #[arg(long, default_value_t = 8)]
        per_scene: usize,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Worker threads (default: the number of cores).
        #[arg(long)]
        jobs: Option<usize>,
        #[arg(long, default_value = "sim-results/grasp-labels")]
        out: PathBuf,
    },
    /// The in-hand rotation task of dissertation §7.5 served to a trainer over stdin/stdout
    /// (models/in_hand; protocol in src/in_hand/env_server.rs): the hand's posture synergies
    /// come from graspd (GetHandSynergies) for r_hand (Eq 7.5).
    InHandEnv {
        /// The hand (built-in name, hand TOML or MJCF model); the task is laid out for the
        /// Shadow hand palm up.
        #[arg(long, default_value = "shadow")]
        hand: String,
        #[arg(long, value_enum, default_value = "block")]
        object: graspd_sim::in_hand::env::InHandObject,
        #[arg(long, value_enum, default_value = "z")]
        rotation: graspd_sim::in_hand::env::TargetRotation,
        /// Environments stepped together.
        #[arg(long, default_value_t = 8)]
        envs: usize,
        /// Seed of the first environment (environment k draws from seed + k).
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// How well graspd's completion of a single view guesses the unseen side, against the
    /// object seen from all around the table (markdown, per object). Needs no graspd.
    Completion {
        #[command(flatten)]
        runs: Runs,
    },
}

/// Which objects, how many trials each, from which seed.
#[derive(clap::Args)]
struct Runs {
    /// Comma-separated objects, or `all` (every shared object); default: the eight of the
    /// dissertation's Table 5.2.
    #[arg(long)]
    objects: Option<String>,
    /// Trials per hand and object.
    #[arg(long, default_value_t = 10)]
    trials: usize,
    /// Seed of the first trial (trial i uses seed + i).
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

/// Comma-separated names, trimmed, empty ones dropped.
fn split_names(s: &str) -> Vec<String> {
    s.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect()
}

impl Runs {
    fn objects(&self) -> Vec<String> {
        use graspd_sim::object::{BEYOND_TABLE_5_2, TABLE_5_2};
        let named = |list: &[&str]| list.iter().map(|s| s.to_string()).collect();
        match self.objects.as_deref() {
            None => named(&TABLE_5_2),
            Some("all") => named(&[TABLE_5_2.as_slice(), &BEYOND_TABLE_5_2].concat()),
            Some(s) => split_names(s),
        }
    }
}

fn parse_image(s: &str) -> Result<Intrinsics, SimError> {
    let bad = || SimError::Input(format!("--image: `{s}` is not WIDTHxHEIGHT (e.g. 640x480)"));
    let (w, h) = s.split_once('x').ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if !(32..=4096).contains(&w) || !(32..=4096).contains(&h) {
        return Err(bad());
    }
    Ok(Intrinsics::kinect(w, h))
}

fn main() {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    if let Err(e) = real_main() {
        eprintln!("graspd-sim: {e}");
        std::process::exit(1);
    }
}

fn real_main() -> Result<(), SimError> {
    let cli = Cli::parse();
    if let Command::Compare { base, new } = &cli.command {
        let (b, n) = (
            graspd_sim::compare::read_trials(base)?,
            graspd_sim::compare::read_trials(new)?,
        );
        print!("{}", graspd_sim::compare::compare(&b, &n).markdown());
        return Ok(());
    }
    let intrinsics = parse_image(&cli.image)?;
    let opts = TrialOptions {
        intrinsics,
        camera: default_view(),
        cloud_input: cli.cloud,
        replans: cli.replans,
        snapshot: None,
        guarded_close: !cli.open_loop,
        candidate: cli.candidate,
        grasp_type: cli.grasp_type,
        place_range: cli.place_range,
        views: cli.views,
        gravity_test: !cli.skip_gravity_test,
        grip_reflex: !cli.no_grip_reflex,
        mode: cli.mode,
    };
    if let Command::Completion { runs } = &cli.command {
        let scores = graspd_sim::completion::run_completion(
            &runs.objects(),
            runs.trials,
            runs.seed,
            &cli.testdata,
            &opts,
        )?;
        print!("{}", graspd_sim::completion::markdown(&scores));
        return Ok(());
    }
    if let Command::LabelGrasps {
        hand,
        objects,
        scenes,
        per_scene,
        seed,
        jobs,
        out,
    } = &cli.command
    {
        use graspd_sim::object::{BEYOND_TABLE_5_2, TABLE_5_2, is_shared_ycb};
        let objects = if objects == "all" {
            [TABLE_5_2.as_slice(), &BEYOND_TABLE_5_2]
                .concat()
                .into_iter()
                .filter(|o| is_shared_ycb(o))
                .map(String::from)
                .collect()
        } else {
            split_names(objects)
        };
        let config = graspd_sim::labels::LabelConfig {
            hand: hand.clone(),
            objects,
            scenes: *scenes,
            per_scene: *per_scene,
            seed: *seed,
            jobs: jobs
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
            out: out.clone(),
            hands_dir: cli.testdata.join("hands"),
            objects_dir: cli.testdata.join("objects"),
            options: opts,
        };
        let summary = graspd_sim::labels::label_grasps(&config)?;
        println!(
            "{}",
            serde_json::to_string_pretty(&summary).unwrap_or_default()
        );
        return Ok(());
    }
    let rt = tokio::runtime::Runtime::new()
        .map_err(|e| SimError::Service(format!("tokio runtime: {e}")))?;
    let service = Service::connect(&cli.graspd, rt.handle().clone())?;
    let hands_dir = cli.testdata.join("hands");
    let objects_dir = cli.testdata.join("objects");
    match cli.command {
        Command::Trial { hand, object, seed } => {
            let hand = SimHand::load(&hand, &hands_dir)?;
            service.ensure_hand(&hand)?;
            let obj = SimObject::load(&objects_dir, &object)?;
            let p = placement(seed, opts.place_range);
            let scene = Scene::build(
                &hand,
                &[(&obj, graspd_sim::scene::on_table(p[0], p[1], p[2]))],
            )?;
            let rec = run_trial(&scene, &hand, &object, &service, seed, &opts);
            println!("{}", serde_json::to_string_pretty(&rec).unwrap_or_default());
        }
        Command::InHandEnv {
            hand,
            object,
            rotation,
            envs,
            seed,
        } => {
            use graspd_sim::in_hand::env::{InHandScene, InHandTask};
            if !(1..=256).contains(&envs) {
                return Err(SimError::Input(format!("--envs: 1 to 256, got {envs}")));
            }
            let hand = SimHand::load(&hand, &hands_dir)?;
            service.ensure_hand(&hand)?;
            let scene = InHandScene::build(&hand, InHandTask { object, rotation })?;
            let reward = graspd_sim::in_hand::hand_reward::HandReward::new(
                service.hand_synergies(&hand.graspd_hand)?,
                &scene,
            )?;
            graspd_sim::in_hand::env_server::serve(
                &scene,
                &reward,
                envs,
                seed,
                std::io::stdin().lock(),
                std::io::BufWriter::new(std::io::stdout().lock()),
            )?;
        }
        Command::Stabilize {
            hand,
            runs,
            safety,
            pulse,
            pulse_s,
            slip_gain,
            max_force,
            latch_slip,
            centroid_slip,
            electrodes_only,
            out,
        } => {
            let hand = SimHand::load(&hand, &hands_dir)?;
            service.ensure_hand(&hand)?;
            let dist = graspd_sim::tactile::Disturbance {
                safety,
                pulse,
                pulse_s,
                slip_gain,
                max_force: max_force.unwrap_or(1.0 + slip_gain),
                latch_slip,
                centroid_slip_mm_s: centroid_slip,
                electrodes_only,
            };
            let report = graspd_sim::tactile::run_protocol(
                &hand,
                &runs.objects(),
                runs.trials,
                runs.seed,
                &dist,
                &objects_dir,
                &service,
                &opts,
                &out,
            )?;
            println!("{report}");
        }
        Command::Bench {
            hands,
            hand_models,
            runs,
            jobs,
            out,
            snapshots,
        } => {
            let mut hands = split_names(&hands);
            hands.extend(hand_models.iter().map(|p| p.to_string_lossy().into_owned()));
            let config = BenchConfig {
                hands,
                objects: runs.objects(),
                trials: runs.trials,
                seed: runs.seed,
                jobs: jobs
                    .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
                out,
                snapshots,
                hands_dir,
                objects_dir,
                options: opts,
            };
            let report = run_bench(&config, &service)?;
            println!("{}", report.markdown);
        }
        Command::Clutter {
            hand,
            objects,
            trials,
            seed,
            jobs,
            out,
            hand_radius,
        } => {
            use graspd_sim::object::{BEYOND_TABLE_5_2, TABLE_5_2, is_shared_ycb};
            let objects = match objects {
                Some(s) => split_names(&s),
                None => [TABLE_5_2.as_slice(), &BEYOND_TABLE_5_2]
                    .concat()
                    .into_iter()
                    .filter(|o| is_shared_ycb(o))
                    .map(String::from)
                    .collect(),
            };
            let config = graspd_sim::clutter::ClutterConfig {
                hand,
                objects,
                trials,
                seed,
                jobs: jobs
                    .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
                out,
                hands_dir,
                objects_dir,
                options: graspd_sim::clutter::ClutterOptions {
                    trial: opts,
                    hand_radius,
                },
            };
            let report = graspd_sim::clutter::run_clutter_bench(&config, &service)?;
            println!("{}", report.markdown);
        }
        Command::Compare { .. } | Command::Completion { .. } | Command::LabelGrasps { .. } => {
            unreachable!("answered before graspd is connected")
        }
    }
    Ok(())
}

/// A grasp type by its name (`large_wrap` … `tripod`).
fn parse_mode(name: &str) -> Result<graspd_proto::v1::PlannerMode, String> {
    graspd_proto::v1::PlannerMode::from_str_name(&format!("PLANNER_MODE_{}", name.to_uppercase()))
        .ok_or_else(|| {
            format!(
                "unknown planner mode '{name}' (dual_stage, without_opposition, learned_quality)"
            )
        })
}

fn parse_grasp_type(name: &str) -> Result<graspd_proto::v1::GraspType, String> {
    graspd_proto::v1::GraspType::from_str_name(&format!("GRASP_TYPE_{}", name.to_uppercase()))
        .filter(|t| *t != graspd_proto::v1::GraspType::Unspecified)
        .ok_or_else(|| {
            format!(
                "unknown grasp type '{name}' (large_wrap, small_wrap, power, pinch, precision, tripod)"
            )
        })
}
