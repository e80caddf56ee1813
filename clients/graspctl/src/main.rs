//! `graspctl`: plan grasps on PCD/PLY clouds, list hands and replay tactile recordings, over
//! graspd's gRPC API.

mod calibrate;
mod stabilize;
mod summary;

use clap::{Args, Parser, Subcommand};
use graspd_api::convert;
use graspd_api::json::{HandJson, HandSynergiesJson, HandsJson, PlanResponseJson};
use graspd_api::request::{HandChoice, ImageHints, OutputOptions, PlanRequest, PlanSource};
use graspd_core::cloud::Plane;
use graspd_core::cloud::io::read_cloud_file;
use graspd_core::hand::parse_hand_toml;
use graspd_core::perception::{CameraIntrinsics, RgbdFrame, WireImage};
use graspd_core::planning::PlannerMode;
use graspd_core::{FieldError, GraspType, PlanHints, PlannerOptions};
use graspd_proto::v1 as pb;
use graspd_proto::v1::grasp_planner_client::GraspPlannerClient;
use graspd_proto::v1::tactile_stabilizer_client::TactileStabilizerClient;
use nalgebra::{Point3, Vector3};
use std::path::PathBuf;
use std::process::ExitCode;
use thiserror::Error;
use tonic::metadata::{Ascii, MetadataValue};
use tonic::service::Interceptor;
use tonic::service::interceptor::InterceptedService;
use tonic::transport::Channel;

#[derive(Debug, Parser)]
#[command(
    name = "graspctl",
    version,
    about = "Client of the graspd grasp-planning service"
)]
struct Cli {
    /// graspd's gRPC address.
    #[arg(
        long,
        global = true,
        env = "GRASPD_SERVER",
        default_value = "http://127.0.0.1:50051"
    )]
    server: String,
    /// Print the server's answer as JSON (the REST API's shape) instead of a summary.
    #[arg(long, global = true)]
    json: bool,
    /// Bearer token for a server with authentication on (sent as `authorization: Bearer …`).
    #[arg(long, global = true, env = "GRASPD_TOKEN", hide_env_values = true)]
    token: Option<String>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Plan a grasp on a point-cloud file (PCD or PLY, ASCII or binary) or an RGB-D frame (a PNG
    /// or JPEG colour image and a 16-bit PNG depth image).
    Plan(PlanArgs),
    /// List the server's hands, or show one.
    Hands {
        /// Show this hand in detail.
        name: Option<String>,
        /// Show the hand's posture synergies instead (dissertation §7.3; a hand with
        /// kinematics; the server fits them on the first request, in seconds).
        #[arg(long, requires = "name")]
        synergies: bool,
    },
    /// Replay a BioTac recording (CSV) through the tactile stabilization stream: a live view,
    /// then a summary (with --json: one setpoint per line on stdout, the summary on stderr).
    Stabilize(stabilize::StabilizeArgs),
    /// Tactile calibrations: fit one on a folder of labelled recordings, list, delete.
    Tactile {
        #[command(subcommand)]
        command: calibrate::TactileCommand,
    },
}

#[derive(Debug, Args)]
struct PlanArgs {
    /// The cloud file (PCD or PLY), in metres.
    #[arg(
        long,
        value_name = "FILE",
        required_unless_present = "rgb",
        conflicts_with = "rgb"
    )]
    cloud: Option<PathBuf>,
    /// The colour image of an RGB-D frame (PNG or JPEG), registered to --depth.
    #[arg(long, value_name = "FILE", requires_all = ["depth", "intrinsics"])]
    rgb: Option<PathBuf>,
    /// The depth image (16-bit PNG, millimetres unless --depth-scale says otherwise).
    #[arg(long, value_name = "FILE", requires = "rgb")]
    depth: Option<PathBuf>,
    /// Pinhole intrinsics of the frame, fx,fy,cx,cy (pixels).
    #[arg(long, value_name = "FX,FY,CX,CY", value_parser = parse_numbers::<4>)]
    intrinsics: Option<[f64; 4]>,
    /// Metres per depth unit (default 0.001).
    #[arg(long, value_name = "M")]
    depth_scale: Option<f64>,
    /// The object at this pixel is the target, and the attention point lies there: u,v.
    #[arg(long, value_name = "U,V", value_parser = parse_numbers::<2>, requires = "rgb")]
    pixel: Option<[f64; 2]>,
    /// The object with most pixels in this box is the target: u_min,v_min,u_max,v_max.
    #[arg(long, value_name = "U0,V0,U1,V1", value_parser = parse_numbers::<4>, requires = "rgb")]
    region: Option<[f64; 4]>,
    /// The object the server's recogniser takes for this name is the target ("apple",
    /// "tomato soup can").
    #[arg(long, value_name = "NAME", requires = "rgb")]
    object: Option<String>,
    /// Write the overlay (ROI, attention point, heat map, contacts, opposition) to this PNG.
    #[arg(long, value_name = "FILE", requires = "rgb")]
    overlay: Option<PathBuf>,
    /// Write the plan as a binary glTF scene (points, support plane, contacts, opposition, the
    /// hand posed at the pre-grasp, grasp and squeeze) to this file; any glTF viewer opens it.
    #[arg(long, value_name = "FILE")]
    glb: Option<PathBuf>,
    /// A hand of the server (see `graspctl hands`).
    #[arg(
        long,
        value_name = "NAME",
        required_unless_present = "hand_file",
        conflicts_with = "hand_file"
    )]
    hand: Option<String>,
    /// An inline hand description (TOML, the format of the server's hand files).
    #[arg(long, value_name = "FILE")]
    hand_file: Option<PathBuf>,
    /// RNG seed: the same request and seed give the same plan.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Force a grasp type: large_wrap, small_wrap, power, pinch, precision, tripod.
    #[arg(long, value_name = "TYPE")]
    grasp_type: Option<GraspType>,
    /// The support plane n·x + d = 0 as nx,ny,nz,d (n toward the object).
    #[arg(long, value_name = "NX,NY,NZ,D", value_parser = parse_plane, allow_hyphen_values = true)]
    support_plane: Option<Plane>,
    /// Sensor position in the cloud's frame, x,y,z.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true)]
    viewpoint: Option<Point3<f64>>,
    /// Approach near this point, x,y,z.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true)]
    attention: Option<Point3<f64>>,
    /// The planner: dual_stage (the method), without_opposition (Table 5.1's ablation: skip
    /// stage 1) or learned_quality (ch. 3's learned parallel-jaw quality, a two-jaw gripper).
    #[arg(long, value_name = "MODE", default_value = "dual_stage")]
    mode: PlannerMode,
    /// The "without opposition" ablation (Table 5.1): skip stage 1 (as `--mode without_opposition`).
    #[arg(long, conflicts_with = "mode")]
    without_opposition: bool,
}

fn parse_numbers<const N: usize>(s: &str) -> Result<[f64; N], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("'{s}': {e}"))?;
    v.try_into().map_err(|v: Vec<f64>| {
        format!(
            "'{s}': expected {N} comma-separated numbers, got {}",
            v.len()
        )
    })
}

fn parse_point(s: &str) -> Result<Point3<f64>, String> {
    parse_numbers::<3>(s).map(Point3::from)
}

fn parse_plane(s: &str) -> Result<Plane, String> {
    let [x, y, z, d] = parse_numbers::<4>(s)?;
    Plane::checked(Vector3::new(x, y, z), d, "--support-plane").map_err(|e| e.message)
}

#[derive(Debug, Error)]
pub(crate) enum CliError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {error}")]
    File { path: PathBuf, error: FieldError },
    #[error("cannot connect to {server}: {source}")]
    Connect {
        server: String,
        source: tonic::transport::Error,
    },
    #[error("the server answered {code:?}: {message}", code = .0.code(), message = .0.message())]
    Status(#[from] tonic::Status),
    #[error("the server's answer is malformed: {0}")]
    Answer(FieldError),
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{0}")]
    Token(String),
    #[error("cannot write JSON: {0}")]
    Json(#[from] serde_json::Error),
}

pub(crate) fn read(path: &PathBuf) -> Result<Vec<u8>, CliError> {
    std::fs::read(path).map_err(|source| CliError::Read {
        path: path.clone(),
        source,
    })
}

/// Adds the bearer token, when one is given, to every call.
#[derive(Debug, Clone)]
pub(crate) struct Bearer(Option<MetadataValue<Ascii>>);

impl Bearer {
    pub(crate) fn new(token: Option<&str>) -> Result<Self, CliError> {
        token
            .map(|t| {
                format!("Bearer {t}")
                    .parse()
                    .map_err(|_| CliError::Token("must be visible ASCII".into()))
            })
            .transpose()
            .map(Bearer)
    }
}

impl Interceptor for Bearer {
    fn call(&mut self, mut r: tonic::Request<()>) -> Result<tonic::Request<()>, tonic::Status> {
        if let Some(v) = &self.0 {
            r.metadata_mut().insert("authorization", v.clone());
        }
        Ok(r)
    }
}

/// A channel to `server`.
pub(crate) async fn channel(server: &str) -> Result<Channel, CliError> {
    let endpoint = Channel::from_shared(server.to_string())
        .map_err(|e| CliError::Token(format!("bad server address '{server}': {e}")))?;
    endpoint
        .connect()
        .await
        .map_err(|source| CliError::Connect {
            server: server.to_string(),
            source,
        })
}

type Planner = GraspPlannerClient<InterceptedService<Channel, Bearer>>;

pub(crate) type Tactile = TactileStabilizerClient<InterceptedService<Channel, Bearer>>;

pub(crate) async fn connect_tactile(
    server: &str,
    token: Option<&str>,
) -> Result<Tactile, CliError> {
    Ok(TactileStabilizerClient::with_interceptor(
        channel(server).await?,
        Bearer::new(token)?,
    ))
}

async fn connect(server: &str, token: Option<&str>) -> Result<Planner, CliError> {
    Ok(GraspPlannerClient::with_interceptor(
        channel(server).await?,
        Bearer::new(token)?,
    ))
}

fn build_source(args: &PlanArgs) -> Result<PlanSource, CliError> {
    let (Some(rgb), Some(depth), Some([fx, fy, cx, cy])) =
        (&args.rgb, &args.depth, args.intrinsics)
    else {
        let path = args.cloud.as_ref().expect("clap requires --cloud or --rgb");
        let cloud = read_cloud_file(&read(path)?).map_err(|error| CliError::File {
            path: path.clone(),
            error,
        })?;
        return Ok(PlanSource::Cloud(cloud));
    };
    // PNG / JPEG files: the encodings and sizes come from the files themselves.
    let file = |path: &PathBuf| -> Result<WireImage, CliError> {
        Ok(WireImage {
            data: read(path)?,
            ..WireImage::default()
        })
    };
    let frame = RgbdFrame::from_wire(
        file(rgb)?,
        file(depth)?,
        CameraIntrinsics { fx, fy, cx, cy },
        args.depth_scale,
        None,
        "frame",
    )
    .map_err(|error| CliError::File {
        path: if error.field.starts_with("frame.color") {
            rgb.clone()
        } else {
            depth.clone()
        },
        error,
    })?;
    Ok(PlanSource::Rgbd(Box::new(frame)))
}

/// A pixel coordinate given on the command line.
fn pixel(v: f64) -> u32 {
    v.round().clamp(0.0, u32::MAX as f64) as u32
}

fn build_request(args: &PlanArgs) -> Result<PlanRequest, CliError> {
    let source = build_source(args)?;
    let hand = match (&args.hand, &args.hand_file) {
        (_, Some(path)) => {
            let text = String::from_utf8_lossy(&read(path)?).into_owned();
            HandChoice::Inline(Box::new(parse_hand_toml(&text).map_err(|error| {
                CliError::File {
                    path: path.clone(),
                    error,
                }
            })?))
        }
        (Some(name), None) => HandChoice::Name(name.clone()),
        (None, None) => unreachable!("clap requires --hand or --hand-file"),
    };
    Ok(PlanRequest {
        source,
        extra_views: Vec::new(),
        hand,
        options: PlannerOptions {
            seed: args.seed,
            mode: if args.without_opposition {
                PlannerMode::WithoutOpposition
            } else {
                args.mode
            },
            ..PlannerOptions::default()
        },
        hints: PlanHints {
            grasp_type: args.grasp_type,
            attention_point: args.attention,
            support_plane: args.support_plane,
            viewpoint: args.viewpoint,
            up: None,
            detected_attention: None,
            detected_types: None,
            seen_from: Vec::new(),
            parallel_grasp: None,
        },
        image_hints: ImageHints {
            attention_pixel: args.pixel.map(|[u, v]| (pixel(u), pixel(v))),
            region: args.region.map(|r| r.map(pixel)),
            object: args.object.clone().unwrap_or_default(),
            most_salient: false,
        },
        output: OutputOptions {
            overlay: args.overlay.is_some(),
            scene_glb: args.glb.is_some(),
            ..OutputOptions::default()
        },
    })
}

async fn run(cli: Cli) -> Result<(), CliError> {
    match &cli.command {
        Command::Stabilize(args) => {
            stabilize::run(&cli.server, cli.token.as_deref(), args, cli.json).await?
        }
        Command::Tactile { command } => {
            calibrate::run(&cli.server, cli.token.as_deref(), command, cli.json).await?
        }
        Command::Plan(args) => {
            let request = convert::plan_request_to_proto(&build_request(args)?);
            let mut client = connect(&cli.server, cli.token.as_deref()).await?;
            let response = client.plan_grasp(request).await?.into_inner();
            let plan = convert::plan_from_proto(response).map_err(CliError::Answer)?;
            if let Some(path) = &args.overlay {
                let png = plan
                    .perception
                    .as_ref()
                    .and_then(|p| p.overlay_png.as_deref())
                    .ok_or_else(|| CliError::Answer(FieldError::new("overlay_png", "missing")))?;
                std::fs::write(path, png).map_err(|source| CliError::Write {
                    path: path.clone(),
                    source,
                })?;
            }
            if let Some(path) = &args.glb {
                let glb = plan
                    .scene_glb
                    .as_deref()
                    .ok_or_else(|| CliError::Answer(FieldError::new("scene_glb", "missing")))?;
                std::fs::write(path, glb).map_err(|source| CliError::Write {
                    path: path.clone(),
                    source,
                })?;
            }
            if cli.json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&PlanResponseJson::from(&plan))?
                );
            } else {
                print!("{}", summary::plan(&plan));
            }
        }
        Command::Hands { name: None, .. } => {
            let mut client = connect(&cli.server, cli.token.as_deref()).await?;
            let response = client
                .list_hands(pb::ListHandsRequest {})
                .await?
                .into_inner();
            let hands = response
                .hands
                .into_iter()
                .map(|h| convert::hand_from_proto(h, "hands[]"))
                .collect::<Result<Vec<_>, _>>()
                .map_err(CliError::Answer)?;
            if cli.json {
                println!("{}", serde_json::to_string_pretty(&HandsJson { hands })?);
            } else {
                print!("{}", summary::hands(&hands));
            }
        }
        Command::Hands {
            name: Some(name),
            synergies: true,
        } => {
            let mut client = connect(&cli.server, cli.token.as_deref()).await?;
            let response = client
                .get_hand_synergies(pb::GetHandSynergiesRequest { name: name.clone() })
                .await?
                .into_inner();
            let synergies =
                convert::synergies_from_proto(response, "synergies").map_err(CliError::Answer)?;
            if cli.json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&HandSynergiesJson::from(&synergies))?
                );
            } else {
                print!("{}", summary::synergies(&synergies));
            }
        }
        Command::Hands {
            name: Some(name), ..
        } => {
            let mut client = connect(&cli.server, cli.token.as_deref()).await?;
            let response = client
                .get_hand(pb::GetHandRequest { name: name.clone() })
                .await?
                .into_inner();
            let hand = response
                .hand
                .ok_or_else(|| CliError::Answer(FieldError::new("hand", "missing")))?;
            let hand = convert::hand_from_proto(hand, "hand").map_err(CliError::Answer)?;
            if cli.json {
                println!("{}", serde_json::to_string_pretty(&HandJson::from(hand))?);
            } else {
                print!("{}", summary::hand(&hand));
            }
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let runtime = match tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("graspctl: cannot start the async runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    match runtime.block_on(run(cli)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("graspctl: error: {e}");
            ExitCode::FAILURE
        }
    }
}
