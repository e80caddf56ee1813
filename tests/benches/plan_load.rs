//! Planning under load, over gRPC and REST on loopback, against the release `graspd`: C
//! concurrent clients send R requests each (a 2,000-point YCB view, the three built-in hands in
//! turn, seed = request number), bounded in count and time. Reports throughput, latency
//! p50/p99/max and the errors by status, for each transport and concurrency.
//!
//! ```text
//! cargo build --release --bins
//! cargo bench -p graspd-e2e --bench plan_load                       # C = 1, 2, 8, 32; 200 requests each
//! cargo bench -p graspd-e2e --bench plan_load -- --requests 400 --concurrency 16
//! ```

use graspd_e2e::{Server, base64, bench_arg, packed, release_graspd};
use graspd_proto::v1 as pb;
use graspd_proto::v1::grasp_planner_client::GraspPlannerClient;
use graspd_testkit::{Object, standard_view};
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

const HANDS: [&str; 3] = ["parallel_gripper", "barrett", "shadow"];
/// No run may take longer than this; requests not sent by then are counted as not sent.
const RUN_LIMIT: Duration = Duration::from_secs(120);

struct Outcome {
    latencies_ms: Vec<f64>,
    errors: BTreeMap<String, usize>,
    not_sent: usize,
    seconds: f64,
}

fn grpc_request(points: &[u8], i: usize) -> pb::PlanGraspRequest {
    pb::PlanGraspRequest {
        input: Some(pb::plan_grasp_request::Input::Cloud(pb::PointCloud {
            points: points.to_vec(),
            normals: Vec::new(),
            frame_id: String::new(),
        })),
        hand: Some(pb::plan_grasp_request::Hand::HandName(
            HANDS[i % HANDS.len()].into(),
        )),
        options: Some(pb::PlannerOptions {
            seed: Some(i as u64),
            ..Default::default()
        }),
        hints: None,
        output: None,
        extra_views: Vec::new(),
    }
}

fn rest_body(points_b64: &str, i: usize) -> String {
    serde_json::json!({
        "cloud": {"points": points_b64},
        "hand_name": HANDS[i % HANDS.len()],
        "options": {"seed": i},
    })
    .to_string()
}

async fn run_grpc(url: String, points: Arc<Vec<u8>>, clients: usize, per_client: usize) -> Outcome {
    let started = Instant::now();
    let tasks: Vec<_> = (0..clients)
        .map(|c| {
            let (url, points) = (url.clone(), points.clone());
            tokio::spawn(async move {
                let mut client = GraspPlannerClient::connect(url).await.expect("connect");
                let mut lat = Vec::new();
                let mut errors = BTreeMap::new();
                let mut not_sent = 0;
                for r in 0..per_client {
                    if started.elapsed() > RUN_LIMIT {
                        not_sent += 1;
                        continue;
                    }
                    let t = Instant::now();
                    match client
                        .plan_grasp(grpc_request(&points, c * per_client + r))
                        .await
                    {
                        Ok(_) => lat.push(t.elapsed().as_secs_f64() * 1e3),
                        Err(s) => *errors.entry(format!("{:?}", s.code())).or_insert(0) += 1,
                    }
                }
                (lat, errors, not_sent)
            })
        })
        .collect();
    collect(tasks, started).await
}

async fn run_rest(
    base: String,
    points_b64: Arc<String>,
    clients: usize,
    per_client: usize,
) -> Outcome {
    let started = Instant::now();
    let http = reqwest::Client::new();
    let tasks: Vec<_> = (0..clients)
        .map(|c| {
            let (base, points_b64, http) = (base.clone(), points_b64.clone(), http.clone());
            tokio::spawn(async move {
                let mut lat = Vec::new();
                let mut errors = BTreeMap::new();
                let mut not_sent = 0;
                for r in 0..per_client {
                    if started.elapsed() > RUN_LIMIT {
                        not_sent += 1;
                        continue;
                    }
                    let t = Instant::now();
                    let answer = http
                        .post(format!("{base}/v1/plan"))
                        .header("content-type", "application/json")
                        .body(rest_body(&points_b64, c * per_client + r))
                        .send()
                        .await;
                    match answer {
                        Ok(resp) if resp.status().is_success() => {
                            let _ = resp.bytes().await;
                            lat.push(t.elapsed().as_secs_f64() * 1e3);
                        }
                        Ok(resp) => *errors.entry(resp.status().to_string()).or_insert(0) += 1,
                        Err(e) => *errors.entry(format!("transport: {e}")).or_insert(0) += 1,
                    }
                }
                (lat, errors, not_sent)
            })
        })
        .collect();
    collect(tasks, started).await
}

type Task = tokio::task::JoinHandle<(Vec<f64>, BTreeMap<String, usize>, usize)>;

async fn collect(tasks: Vec<Task>, started: Instant) -> Outcome {
    let mut o = Outcome {
        latencies_ms: Vec::new(),
        errors: BTreeMap::new(),
        not_sent: 0,
        seconds: 0.0,
    };
    for t in tasks {
        let (lat, errors, not_sent) = t.await.expect("client task");
        o.latencies_ms.extend(lat);
        for (k, v) in errors {
            *o.errors.entry(k).or_insert(0) += v;
        }
        o.not_sent += not_sent;
    }
    o.seconds = started.elapsed().as_secs_f64();
    o.latencies_ms.sort_by(f64::total_cmp);
    o
}

fn q(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

fn main() {
    let graspd = release_graspd();
    let view = standard_view(Object::TomatoSoupCan, 2000, 1);
    let points = Arc::new(packed(&view.cloud.points));
    let points_b64 = Arc::new(base64(&points));
    let requests: usize = bench_arg("--requests").unwrap_or(200);
    let levels: Vec<usize> = match bench_arg("--concurrency") {
        Some(c) => vec![c],
        None => vec![1, 2, 8, 32],
    };
    let server = Server::start_binary(&graspd, &[]);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    println!(
        "plan load: {} on loopback, tomato_soup_can 2,000-point view, hands {HANDS:?} in turn, {requests} requests per row, {} cores",
        graspd.display(),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    println!("| transport | clients | plans/s | p50 ms | p99 ms | max ms | errors | not sent |");
    println!("|---|---:|---:|---:|---:|---:|---|---:|");
    for &clients in &levels {
        let per_client = requests.div_ceil(clients);
        for transport in ["gRPC", "REST"] {
            let o = runtime.block_on(async {
                if transport == "gRPC" {
                    run_grpc(server.grpc_url(), points.clone(), clients, per_client).await
                } else {
                    run_rest(
                        format!("http://{}", server.rest_addr),
                        points_b64.clone(),
                        clients,
                        per_client,
                    )
                    .await
                }
            });
            let errors = if o.errors.is_empty() {
                "0".to_string()
            } else {
                format!("{:?}", o.errors)
            };
            println!(
                "| {transport} | {clients} | {:.0} | {:.2} | {:.2} | {:.2} | {errors} | {} |",
                o.latencies_ms.len() as f64 / o.seconds,
                q(&o.latencies_ms, 0.5),
                q(&o.latencies_ms, 0.99),
                o.latencies_ms.last().copied().unwrap_or(f64::NAN),
                o.not_sent,
            );
        }
    }
}
