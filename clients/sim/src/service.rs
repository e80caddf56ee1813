//! The gRPC side: graspd-sim talks to a running graspd only over its public API, as a robot stack
//! does (GetHand / RegisterHand for the hand model, PlanGrasp with the rendered RGB-D frame).

use crate::SimError;
use crate::camera::RgbdImage;
use crate::hand::SimHand;
use graspd_api::convert::pose_to_proto;
use graspd_core::planning::Pose;
use graspd_proto::v1 as pb;
use graspd_proto::v1::grasp_planner_client::GraspPlannerClient;
use nalgebra::{Isometry3, Point3};
use std::path::Path;
use tonic::transport::Channel;

/// A connected client plus the runtime its calls block on (trials run on plain threads).
#[derive(Clone)]
pub struct Service {
    client: GraspPlannerClient<Channel>,
    channel: Channel,
    rt: tokio::runtime::Handle,
}

/// What a robot stack asks of PlanGrasp beyond the frame: how many ranked plans to return and,
/// optionally, the grasp type (graspd detects it when None) and the object by name.
#[derive(Debug, Clone, Default)]
pub struct PlanAsk {
    /// `options.candidates` (0: graspd's default, one plan).
    pub candidates: u32,
    pub grasp_type: Option<pb::GraspType>,
    /// `options.mode` (None: graspd's default).
    pub mode: Option<pb::PlannerMode>,
    /// `hints.object`: the object graspd's recogniser takes for this name is the target.
    pub object: Option<String>,
}

/// What a trial needs from a plan.
#[derive(Debug, Clone)]
pub struct PlanResult {
    pub response: pb::PlanGraspResponse,
    /// Round-trip latency of the PlanGrasp call, s.
    pub latency: f64,
}

impl Service {
    /// Connects to `addr` (e.g. `http://127.0.0.1:50051`) on the runtime `rt`.
    pub fn connect(addr: &str, rt: tokio::runtime::Handle) -> Result<Self, SimError> {
        let endpoint = Channel::from_shared(addr.to_string())
            .map_err(|e| SimError::Input(format!("--graspd: {e}")))?;
        let channel = rt
            .block_on(endpoint.connect())
            .map_err(|e| SimError::Service(format!("cannot connect to graspd at {addr}: {e}")))?;
        let client = GraspPlannerClient::new(channel.clone())
            .max_decoding_message_size(64 << 20)
            .max_encoding_message_size(64 << 20);
        Ok(Service {
            client,
            channel,
            rt,
        })
    }

    /// Makes sure graspd knows the hand: GetHand, and RegisterHand with the model file and every
    /// mesh beside it when it does not. Returns whether it registered.
    pub fn ensure_hand(&self, hand: &SimHand) -> Result<bool, SimError> {
        let mut c = self.client.clone();
        let name = hand.graspd_hand.clone();
        match self
            .rt
            .block_on(c.get_hand(pb::GetHandRequest { name: name.clone() }))
        {
            Ok(_) => return Ok(false),
            Err(s) if s.code() == tonic::Code::NotFound => {}
            Err(s) => return Err(SimError::Service(format!("GetHand {name}: {s}"))),
        }
        let model = hand.model.clone();
        let dir = model.parent().unwrap_or(Path::new("."));
        let text = std::fs::read_to_string(&model)
            .map_err(|e| SimError::Input(format!("hands: {}: {e}", model.display())))?;
        let mut assets = Vec::new();
        collect_assets(dir, dir, &mut assets)?;
        let req = pb::RegisterHandRequest {
            name: name.clone(),
            model: Some(pb::HandModel {
                format: "mjcf".into(),
                text,
                assets,
                ..Default::default()
            }),
            ..Default::default()
        };
        self.rt
            .block_on(c.register_hand(req))
            .map_err(|s| SimError::Service(format!("RegisterHand {name}: {s}")))?;
        Ok(true)
    }

    /// The hand's posture synergies (GetHandSynergies, dissertation §7.3), checked and
    /// converted.
    pub fn hand_synergies(
        &self,
        name: &str,
    ) -> Result<graspd_core::hand::PostureSynergies, SimError> {
        let mut c = self.client.clone();
        let answer = self
            .rt
            .block_on(c.get_hand_synergies(pb::GetHandSynergiesRequest { name: name.into() }))
            .map_err(|s| SimError::Service(format!("GetHandSynergies {name}: {s}")))?;
        graspd_api::convert::synergies_from_proto(answer.into_inner(), "synergies")
            .map(|h| h.synergies)
            .map_err(|e| SimError::Service(format!("GetHandSynergies {name}: {e}")))
    }

    /// PlanGrasp on a rendered frame (or the object's cloud when `cloud` is given), with further
    /// views of the scene fused (`extra_views`, RGB-D input only).
    pub fn plan(
        &self,
        hand: &SimHand,
        image: &RgbdImage,
        extra_views: &[RgbdImage],
        cloud: Option<&[Point3<f64>]>,
        seed: u64,
        ask: &PlanAsk,
    ) -> Result<PlanResult, tonic::Status> {
        let mut c = self.client.clone();
        let input = match cloud {
            Some(points) => {
                let mut bytes = Vec::with_capacity(points.len() * 12);
                for p in points {
                    for v in [p.x, p.y, p.z] {
                        bytes.extend_from_slice(&(v as f32).to_le_bytes());
                    }
                }
                pb::plan_grasp_request::Input::Cloud(pb::PointCloud {
                    points: bytes,
                    normals: Vec::new(),
                    frame_id: "world".into(),
                })
            }
            None => pb::plan_grasp_request::Input::Rgbd(frame_to_proto(image)),
        };
        let eye = image.camera_to_world.translation.vector;
        let req = pb::PlanGraspRequest {
            input: Some(input),
            hand: Some(pb::plan_grasp_request::Hand::HandName(
                hand.graspd_hand.clone(),
            )),
            options: Some(pb::PlannerOptions {
                seed: Some(seed),
                squeeze_depth: Some(hand.squeeze_depth),
                candidates: (ask.candidates > 0).then_some(ask.candidates),
                mode: ask.mode.map(|m| m as i32),
                ..Default::default()
            }),
            extra_views: extra_views.iter().map(frame_to_proto).collect(),
            hints: Some(pb::PlanHints {
                viewpoint: cloud.map(|_| pb::Vec3 {
                    x: eye.x,
                    y: eye.y,
                    z: eye.z,
                }),
                grasp_type: ask.grasp_type.map_or(0, |t| t as i32),
                object: ask.object.clone().unwrap_or_default(),
                ..Default::default()
            }),
            ..Default::default()
        };
        let t0 = std::time::Instant::now();
        let response = self.rt.block_on(c.plan_grasp(req))?.into_inner();
        Ok(PlanResult {
            response,
            latency: t0.elapsed().as_secs_f64(),
        })
    }

    /// PlanReach from the hand frame at `start` to a plan's grasp (its hand pose, approach and
    /// pre-grasp distance), the other objects in `scene` as obstacles, the hand a sphere of
    /// `hand_radius` (None: graspd's default), the approach onto the grasp `approach_s` long.
    pub fn reach(
        &self,
        start: &Isometry3<f64>,
        plan: &pb::PlanGraspResponse,
        scene: &RgbdImage,
        hand_radius: Option<f64>,
        approach_s: f64,
    ) -> Result<pb::PlanReachResponse, tonic::Status> {
        let pose = |p: &Option<pb::Pose>| {
            graspd_api::convert::pose_from_proto(p, "")
                .map(|p| p.isometry())
                .map_err(|e| tonic::Status::invalid_argument(e.to_string()))
        };
        let (goal, pre) = (pose(&plan.hand_pose)?, pose(&plan.pregrasp_pose)?);
        let req = pb::PlanReachRequest {
            start: Some(pose_to_proto(&Pose::from_isometry(start))),
            goal: plan.hand_pose,
            approach: plan.approach,
            pregrasp_distance: Some((goal.translation.vector - pre.translation.vector).norm()),
            scene: Some(frame_to_proto(scene)),
            hand_radius,
            options: Some(pb::ReachOptions {
                approach_duration: approach_s,
                ..Default::default()
            }),
            ..Default::default()
        };
        let mut c = self.client.clone();
        Ok(self.rt.block_on(c.plan_reach(req))?.into_inner())
    }
}

/// A rendered frame as PlanGrasp takes it (colour rgb8, depth 32FC1 in metres, the camera's
/// pose in the world).
fn frame_to_proto(image: &RgbdImage) -> pb::RgbdFrame {
    let intr = image.intrinsics;
    pb::RgbdFrame {
        color: Some(pb::Image {
            width: intr.width,
            height: intr.height,
            encoding: "rgb8".into(),
            step: intr.width * 3,
            data: image.rgb.clone(),
            is_bigendian: false,
        }),
        depth: Some(pb::Image {
            width: intr.width,
            height: intr.height,
            encoding: "32FC1".into(),
            step: intr.width * 4,
            data: image.depth.iter().flat_map(|d| d.to_le_bytes()).collect(),
            is_bigendian: false,
        }),
        intrinsics: Some(pb::CameraIntrinsics {
            fx: intr.fx,
            fy: intr.fy,
            cx: intr.cx,
            cy: intr.cy,
            k: Vec::new(),
        }),
        depth_scale: 1.0,
        camera_to_world: Some(pose_to_proto(&Pose::from_isometry(&image.camera_to_world))),
    }
}

/// An open `Stabilize` stream: one frame in, its setpoint out, in lockstep with the simulation.
pub struct StabilizeStream {
    tx: tokio::sync::mpsc::Sender<pb::StabilizeRequest>,
    responses: tonic::Streaming<pb::StabilizationSetpoint>,
    rt: tokio::runtime::Handle,
}

impl Service {
    /// Opens a TactileStabilizer.Stabilize stream with `session` as its first message.
    pub fn stabilize(&self, session: pb::TactileSession) -> Result<StabilizeStream, SimError> {
        let channel = self.channel.clone();
        let (tx, rx) = tokio::sync::mpsc::channel(4);
        tx.try_send(pb::StabilizeRequest {
            kind: Some(pb::stabilize_request::Kind::Session(session)),
        })
        .map_err(|e| SimError::Service(format!("Stabilize: {e}")))?;
        let mut client =
            graspd_proto::v1::tactile_stabilizer_client::TactileStabilizerClient::new(channel);
        let responses = self
            .rt
            .block_on(client.stabilize(tokio_stream::wrappers::ReceiverStream::new(rx)))
            .map_err(|s| SimError::Service(format!("Stabilize: {s}")))?
            .into_inner();
        Ok(StabilizeStream {
            tx,
            responses,
            rt: self.rt.clone(),
        })
    }
}

impl StabilizeStream {
    /// Sends one frame and waits for its setpoint.
    pub fn frame(
        &mut self,
        frame: pb::TactileFrame,
    ) -> Result<pb::StabilizationSetpoint, SimError> {
        let tx = self.tx.clone();
        let responses = &mut self.responses;
        self.rt.block_on(async move {
            tx.send(pb::StabilizeRequest {
                kind: Some(pb::stabilize_request::Kind::Frame(frame)),
            })
            .await
            .map_err(|_| SimError::Service("Stabilize: the stream closed".into()))?;
            match responses.message().await {
                Ok(Some(m)) => Ok(m),
                Ok(None) => Err(SimError::Service("Stabilize: the stream ended".into())),
                Err(s) => Err(SimError::Service(format!("Stabilize: {s}"))),
            }
        })
    }
}

/// Every file under `dir` but documentation, as assets with paths relative to `base`.
fn collect_assets(base: &Path, dir: &Path, out: &mut Vec<pb::HandAsset>) -> Result<(), SimError> {
    let rd = std::fs::read_dir(dir)
        .map_err(|e| SimError::Input(format!("hands: {}: {e}", dir.display())))?;
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            collect_assets(base, &p, out)?;
            continue;
        }
        let ext = p
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        if !matches!(ext.as_str(), "stl" | "obj" | "msh" | "png" | "xml") {
            continue;
        }
        let rel = p
            .strip_prefix(base)
            .unwrap_or(&p)
            .to_string_lossy()
            .into_owned();
        let data = std::fs::read(&p)
            .map_err(|e| SimError::Input(format!("hands: {}: {e}", p.display())))?;
        out.push(pb::HandAsset { path: rel, data });
    }
    Ok(())
}
