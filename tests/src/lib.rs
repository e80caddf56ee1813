//! Harness of the end-to-end tests: starts the real `graspd` binary on ephemeral loopback ports,
//! reads the `graspd listening …` line to learn them, and kills the process on drop. Also the
//! synthetic clouds and request builders the tests share.
//!
//! The binaries come from `GRASPD_BIN` / `GRASPCTL_BIN`, else `<target>/debug/`; build them
//! first (`make test` or `cargo build --bins`).

use base64::Engine;
use graspd_core::cloud::encode_packed_xyz;
use graspd_proto::v1 as pb;
use graspd_proto::v1::grasp_planner_client::GraspPlannerClient;
use graspd_testkit::rgbd::RgbdRender;
use nalgebra::Point3;
use std::io::{BufRead, BufReader};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex, mpsc};
use std::time::Duration;
use tonic::transport::Channel;

/// How long the server may take to print its listening line.
const START_TIMEOUT: Duration = Duration::from_secs(30);

/// The workspace's target directory (`CARGO_TARGET_DIR`, else `<workspace>/target`).
pub fn target_dir() -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .parent()
            .expect("tests/ has a parent")
            .join("target"),
    }
}

/// The path of a workspace binary: `$env_var`, else `<target>/debug/<name>`.
pub fn binary(name: &str, env_var: &str) -> PathBuf {
    let path = std::env::var_os(env_var)
        .map(PathBuf::from)
        .unwrap_or_else(|| target_dir().join("debug").join(name));
    assert!(
        path.is_file(),
        "{} not found: run `make test` or `cargo build --bins` first (or set {env_var})",
        path.display()
    );
    path
}

/// A running `graspd`; killed when dropped.
pub struct Server {
    child: Child,
    pub grpc_addr: SocketAddr,
    pub rest_addr: SocketAddr,
    /// The plain-HTTP probe port, when started with `--probe-addr`.
    pub probe_addr: Option<SocketAddr>,
    /// Its log lines (stderr), when started with [`Server::start_with_logs`].
    logs: Option<Arc<Mutex<Vec<String>>>>,
}

impl Server {
    /// Starts graspd with default limits.
    pub fn start() -> Self {
        Self::start_with(&[])
    }

    /// Starts graspd with extra flags (e.g. `["--max-message-bytes", "65536"]`).
    pub fn start_with(args: &[&str]) -> Self {
        Self::start_binary(&binary("graspd", "GRASPD_BIN"), args)
    }

    /// Starts graspd with extra flags and keeps its log lines (stderr) for [`Server::logs`]; they
    /// are echoed to the test's stderr too. Pass `--log` to choose what is logged.
    pub fn start_with_logs(args: &[&str]) -> Self {
        Self::start_inner(&binary("graspd", "GRASPD_BIN"), args, true)
    }

    /// Starts the graspd binary at `path` (e.g. a release build for a benchmark) with extra flags.
    pub fn start_binary(path: &std::path::Path, args: &[&str]) -> Self {
        Self::start_inner(path, args, false)
    }

    fn start_inner(path: &std::path::Path, args: &[&str], keep_logs: bool) -> Self {
        let mut command = Command::new(path);
        for var in [
            "GRASPD_CONFIG",
            "GRASPD_GRPC_ADDR",
            "GRASPD_REST_ADDR",
            "GRASPD_MAX_MESSAGE_BYTES",
            "GRASPD_MAX_POINTS",
            "GRASPD_MAX_CONCURRENT_PLANS",
            "GRASPD_MAX_QUEUED_PLANS",
            "GRASPD_DRAIN_DELAY_MS",
            "GRASPD_MAX_TACTILE_SESSIONS",
            "GRASPD_AUTH_TOKENS",
            "GRASPD_AUTH_TOKENS_FILE",
            "GRASPD_LOG_FORMAT",
            "GRASPD_HANDS_DIR",
            "GRASPD_CALIBRATIONS_DIR",
            "GRASPD_IMPORT_HANDS",
            "GRASPD_TLS_CERT",
            "GRASPD_TLS_KEY",
            "GRASPD_TLS_CLIENT_CA",
            "GRASPD_TACTILE_MODEL",
        ] {
            command.env_remove(var);
        }
        if std::env::var_os("GRASPD_LOG").is_none() {
            command.env("GRASPD_LOG", "warn");
        }
        let mut child = command
            .args(["--grpc-addr", "127.0.0.1:0", "--rest-addr", "127.0.0.1:0"])
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(if keep_logs {
                Stdio::piped()
            } else {
                Stdio::inherit()
            })
            .spawn()
            .expect("cannot start graspd");
        let logs = child.stderr.take().map(|stderr| {
            let logs = Arc::new(Mutex::new(Vec::new()));
            let sink = logs.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(stderr).lines() {
                    let Ok(line) = line else { break };
                    eprintln!("{line}");
                    sink.lock().unwrap().push(line);
                }
            });
            logs
        });
        let stdout = child.stdout.take().expect("piped stdout");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if line.starts_with("graspd listening ") {
                    let _ = tx.send(line);
                }
            }
        });
        let line = match rx.recv_timeout(START_TIMEOUT) {
            Ok(line) => line,
            Err(_) => {
                let _ = child.kill();
                let status = child.wait();
                panic!("graspd did not print its listening line (exit: {status:?})");
            }
        };
        let addr = |key: &str| -> SocketAddr {
            line.split_whitespace()
                .find_map(|w| w.strip_prefix(key))
                .and_then(|a| a.parse().ok())
                .unwrap_or_else(|| panic!("no {key}ADDR in '{line}'"))
        };
        Server {
            grpc_addr: addr("grpc="),
            rest_addr: addr("rest="),
            probe_addr: line
                .split_whitespace()
                .find_map(|w| w.strip_prefix("probe="))
                .and_then(|a| a.parse().ok()),
            child,
            logs,
        }
    }

    /// The log lines so far (empty unless started with [`Server::start_with_logs`]).
    pub fn logs(&self) -> Vec<String> {
        self.logs
            .as_ref()
            .map(|l| l.lock().unwrap().clone())
            .unwrap_or_default()
    }

    /// The server's resident memory (`VmRSS` of /proc/PID/status), bytes; None off Linux.
    pub fn rss_bytes(&self) -> Option<u64> {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.pid())).ok()?;
        let kib: u64 = status
            .lines()
            .find_map(|l| l.strip_prefix("VmRSS:"))?
            .trim()
            .strip_suffix("kB")?
            .trim()
            .parse()
            .ok()?;
        Some(kib * 1024)
    }

    /// The `/metrics` exposition.
    pub async fn metrics(&self) -> String {
        let response = http()
            .get(self.rest_url("/metrics"))
            .send()
            .await
            .expect("GET /metrics");
        assert_eq!(response.status(), 200, "GET /metrics");
        response.text().await.expect("metrics text")
    }

    pub fn grpc_url(&self) -> String {
        format!("http://{}", self.grpc_addr)
    }

    pub fn rest_url(&self, path: &str) -> String {
        format!("http://{}{path}", self.rest_addr)
    }

    pub async fn grpc(&self) -> GraspPlannerClient<Channel> {
        GraspPlannerClient::connect(self.grpc_url())
            .await
            .expect("connect to graspd's gRPC port")
    }

    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Sends `signal` (e.g. "TERM", "INT") and waits for the exit.
    pub fn signal(mut self, signal: &str) -> ExitStatus {
        let ok = Command::new("kill")
            .args([&format!("-{signal}"), &self.child.id().to_string()])
            .status()
            .expect("run kill")
            .success();
        assert!(ok, "kill -{signal} failed");
        for _ in 0..200 {
            if let Some(status) = self.child.try_wait().expect("wait for graspd") {
                return status;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        panic!("graspd did not exit within 10 s of SIG{signal}");
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// An HTTP client for the REST tests.
pub fn http() -> reqwest::Client {
    reqwest::Client::builder()
        .timeout(Duration::from_secs(60))
        .build()
        .expect("http client")
}

/// `n` points on a 7 cm-diameter, 10 cm-tall cylinder standing on z = 0 (side and top, the
/// part a camera above would see), rounded to float32 so that packed and JSON encodings carry
/// the same values.
pub fn cylinder(n: usize) -> Vec<Point3<f64>> {
    let r = 0.035;
    let h = 0.10;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let top = n / 5;
    let f = |v: f64| v as f32 as f64;
    (0..n)
        .map(|i| {
            let a = i as f64 * golden;
            if i < top {
                let rho = r * ((i as f64 + 0.5) / top as f64).sqrt();
                Point3::new(f(rho * a.cos()), f(rho * a.sin()), f(h))
            } else {
                let t = (i - top) as f64 / (n - top) as f64;
                Point3::new(f(r * a.cos()), f(r * a.sin()), f(h * t))
            }
        })
        .collect()
}

/// Packed little-endian float32 x, y, z.
pub fn packed(points: &[Point3<f64>]) -> Vec<u8> {
    encode_packed_xyz(points)
}

pub fn base64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// The support plane z = 0 of [`cylinder`].
pub fn table_plane() -> pb::Plane {
    pb::Plane {
        normal: Some(pb::Vec3 {
            x: 0.0,
            y: 0.0,
            z: 1.0,
        }),
        offset: 0.0,
    }
}

/// A valid gRPC plan request on the cylinder.
pub fn grpc_request(hand: &str, seed: u64) -> pb::PlanGraspRequest {
    grpc_request_with_points(packed(&cylinder(2000)), hand, seed)
}

pub fn grpc_request_with_points(points: Vec<u8>, hand: &str, seed: u64) -> pb::PlanGraspRequest {
    pb::PlanGraspRequest {
        input: Some(pb::plan_grasp_request::Input::Cloud(pb::PointCloud {
            points,
            normals: Vec::new(),
            frame_id: "world".into(),
        })),
        hand: Some(pb::plan_grasp_request::Hand::HandName(hand.into())),
        options: Some(pb::PlannerOptions {
            seed: Some(seed),
            ..Default::default()
        }),
        hints: Some(pb::PlanHints {
            support_plane: Some(table_plane()),
            ..Default::default()
        }),
        output: None,
        extra_views: Vec::new(),
    }
}

/// The same request as [`grpc_request`] in REST JSON (points as base64 of the same bytes).
pub fn json_request(hand: &str, seed: u64) -> serde_json::Value {
    serde_json::json!({
        "cloud": {"points": base64(&packed(&cylinder(2000)))},
        "hand_name": hand,
        "options": {"seed": seed},
        "hints": {"support_plane": {"normal": [0, 0, 1], "offset": 0}},
    })
}

/// Asserts that a valid plan request still succeeds through both transports (after a bad one).
pub async fn assert_valid_plan_works(server: &Server) {
    let response = server
        .grpc()
        .await
        .plan_grasp(grpc_request("shadow", 1))
        .await;
    assert!(response.is_ok(), "valid gRPC plan failed: {response:?}");
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&json_request("shadow", 1))
        .send()
        .await
        .expect("REST request");
    let status = response.status();
    let body = response.text().await.unwrap_or_default();
    assert_eq!(status, 200, "valid REST plan failed: {body}");
}

/// A REST error body: (code, field, message).
pub async fn rest_error(response: reqwest::Response) -> (u16, String, Option<String>, String) {
    let status = response.status().as_u16();
    let body: serde_json::Value = response.json().await.expect("error body is JSON");
    let e = &body["error"];
    (
        status,
        e["code"].as_str().unwrap_or_default().to_string(),
        e["field"].as_str().map(str::to_string),
        e["message"].as_str().unwrap_or_default().to_string(),
    )
}

/// Asserts a REST refusal of bad input: 400 `invalid_argument` naming `field`. Returns the
/// message.
pub async fn refused_naming(response: reqwest::Response, field: &str) -> String {
    let (status, code, got, message) = rest_error(response).await;
    assert_eq!(
        (status, code.as_str(), got.as_deref()),
        (400, "invalid_argument", Some(field)),
        "{message}"
    );
    message
}

/// Drops the wall-clock fields, which differ between any two runs.
pub fn without_timings(mut v: serde_json::Value) -> serde_json::Value {
    let o = v.as_object_mut().unwrap();
    o.remove("timings");
    for stage in ["stage1", "stage2"] {
        o[stage].as_object_mut().unwrap().remove("seconds");
    }
    v
}

/// The value of the sample `name` whose labels include all of `labels` (summed when several
/// match), from a Prometheus/OpenMetrics text exposition; None when none matches.
pub fn metric(text: &str, name: &str, labels: &[(&str, &str)]) -> Option<f64> {
    let mut found = None;
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let (series, value) = match line.rsplit_once(' ') {
            Some(split) => split,
            None => continue,
        };
        let (sample, label_text) = match series.split_once('{') {
            Some((n, rest)) => (n, rest.trim_end_matches('}')),
            None => (series, ""),
        };
        if sample != name {
            continue;
        }
        let has = |k: &str, v: &str| label_text.split(',').any(|kv| kv == format!("{k}=\"{v}\""));
        if labels.iter().all(|(k, v)| has(k, v))
            && let Ok(v) = value.parse::<f64>()
        {
            *found.get_or_insert(0.0) += v;
        }
    }
    found
}

fn camera_pose(r: &RgbdRender) -> pb::Pose {
    let t = r.camera_to_world.translation.vector;
    let q = r.camera_to_world.rotation;
    pb::Pose {
        position: Some(pb::Vec3 {
            x: t.x,
            y: t.y,
            z: t.z,
        }),
        orientation: Some(pb::Quaternion {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        }),
    }
}

/// A rendered frame as the gRPC message: raw rgb8 and 16UC1 (millimetres), with the camera pose
/// when `with_pose` (outputs then in the world frame).
pub fn rgbd_frame_proto(r: &RgbdRender, with_pose: bool) -> pb::RgbdFrame {
    let image = |encoding: &str, data: Vec<u8>| pb::Image {
        width: r.width as u32,
        height: r.height as u32,
        encoding: encoding.into(),
        step: 0,
        data,
        is_bigendian: false,
    };
    pb::RgbdFrame {
        color: Some(image("rgb8", r.rgb.clone())),
        depth: Some(image("16UC1", r.depth_mm_le())),
        intrinsics: Some(pb::CameraIntrinsics {
            fx: r.intrinsics.fx,
            fy: r.intrinsics.fy,
            cx: r.intrinsics.cx,
            cy: r.intrinsics.cy,
            k: Vec::new(),
        }),
        depth_scale: 0.0,
        camera_to_world: with_pose.then(|| camera_pose(r)),
    }
}

/// A bench's `--name VALUE` argument, parsed.
pub fn bench_arg<T: std::str::FromStr>(name: &str) -> Option<T> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
}

/// The release `graspd` the load benches drive (`GRASPD_BIN`, else `<target>/release/graspd`);
/// exits with a hint when it has not been built.
pub fn release_graspd() -> PathBuf {
    let graspd = std::env::var_os("GRASPD_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| target_dir().join("release").join("graspd"));
    if !graspd.is_file() {
        eprintln!(
            "{} not found: build it with `cargo build --release --bins` (or set GRASPD_BIN)",
            graspd.display()
        );
        std::process::exit(2);
    }
    graspd
}
