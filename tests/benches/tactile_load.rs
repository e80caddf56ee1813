//! Tactile stabilization under load (issue 5): N concurrent `Stabilize` gRPC streams on loopback,
//! each sending one BioTac frame every 1/rate s (1 kHz by default), against the release `graspd`.
//!
//! Latency of a frame = the moment its setpoint arrives − the moment the client handed the frame
//! to the stream (a full send queue, i.e. a server that falls behind, is charged to the frame).
//! The client's own lag behind the schedule (tokio's 1 ms timer granularity, the load generator
//! sharing the 2 cores) is reported apart as "send lag". The server's CPU time comes from /proc and gives the cost per
//! frame of the whole path (HTTP/2, protobuf, the stabilizer). The load generator runs on one
//! thread in this process, on the same 2 cores as the server.
//!
//! ```text
//! cargo build --release --bins
//! cargo bench -p graspd-e2e --bench tactile_load                      # 1, 5, 10, 25, 50 sessions
//! cargo bench -p graspd-e2e --bench tactile_load -- --sessions 50 --rate 1000 --seconds 10
//! cargo bench -p graspd-e2e --bench tactile_load -- --rate 100 --staggered
//! cargo bench -p graspd-e2e --bench tactile_load -- --model-free
//! ```
//!
//! By default every session's frame is due at the same instant (the worst case: a burst of N
//! frames each period); `--staggered` spreads session i's schedule i/N of a period later, as
//! independent clients would be.

use graspd_api::convert;
use graspd_api::request::{LayoutChoice, TactileFingerRequest, TactileSessionRequest};
use graspd_core::tactile::{DetectorChoice, Frame, Recording, StabilizerConfig, TareConfig};
use graspd_e2e::{Server, bench_arg, release_graspd};
use graspd_proto::v1 as pb;
use graspd_proto::v1::stabilize_request::Kind;
use graspd_proto::v1::tactile_stabilizer_client::TactileStabilizerClient;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::mpsc;
use tokio::time::MissedTickBehavior;
use tonic::codegen::tokio_stream::wrappers::ReceiverStream;

const RECORDING: &str = "tactile/biotac_slide/mat5/mat5_1_bio.csv";

struct Run {
    sessions: usize,
    rate_hz: f64,
    seconds: f64,
    warmup_s: f64,
    /// Whether the sessions' frames are spread over the period (independent clients) instead
    /// of all due at the same instant.
    staggered: bool,
    /// Whether the sessions ask for the model-free detector (else the default: the shipped LSTM).
    model_free: bool,
}

struct Outcome {
    latencies_us: Vec<f64>,
    lags_us: Vec<f64>,
    answered: usize,
    expected: usize,
    errors: usize,
    server_cpu_s: f64,
    measured_s: f64,
}

fn session(model_free: bool) -> pb::TactileSession {
    convert::tactile_session_to_proto(&TactileSessionRequest {
        fingers: vec![TactileFingerRequest {
            name: "th".into(),
            layout: LayoutChoice::Name("biotac".into()),
            tare: TareConfig::pretared(),
            electrodes_only: false,
            calibration: None,
        }],
        config: StabilizerConfig {
            detector: if model_free {
                DetectorChoice::ModelFree(Default::default())
            } else {
                DetectorChoice::Default
            },
            ..StabilizerConfig::default()
        },
    })
}

/// utime + stime of a process, seconds.
fn cpu_seconds(pid: u32) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / USER_HZ
}

/// Clock ticks per second of /proc/<pid>/stat: USER_HZ, 100 on Linux (x86_64 and arm64).
const USER_HZ: f64 = 100.0;

async fn one_session(
    url: String,
    frames: Arc<Vec<Frame>>,
    run: Arc<Run>,
    start: Instant,
) -> (Vec<f64>, Vec<f64>, usize, usize, bool) {
    let period = Duration::from_secs_f64(1.0 / run.rate_hz);
    let total = (run.seconds * run.rate_hz) as usize;
    let warmup = (run.warmup_s * run.rate_hz) as usize;
    let mut client = match TactileStabilizerClient::connect(url).await {
        Ok(c) => c,
        Err(_) => return (Vec::new(), Vec::new(), 0, total - warmup, true),
    };
    let (tx, rx) = mpsc::channel(64);
    let (sent_tx, mut sent_rx) = mpsc::unbounded_channel::<(Instant, Instant)>();
    let _ = tx
        .send(pb::StabilizeRequest {
            kind: Some(Kind::Session(session(run.model_free))),
        })
        .await;
    let sender = tokio::spawn(async move {
        let mut tick = tokio::time::interval_at(start.into(), period);
        tick.set_missed_tick_behavior(MissedTickBehavior::Burst);
        for i in 0..total {
            tick.tick().await;
            let mut f = frames[i % frames.len()].clone();
            f.timestamp = i as f64 * period.as_secs_f64();
            let m = pb::StabilizeRequest {
                kind: Some(Kind::Frame(convert::tactile_frame_to_proto(&f))),
            };
            let _ = sent_tx.send((start + period * i as u32, Instant::now()));
            if tx.send(m).await.is_err() {
                break;
            }
        }
    });
    let mut stream = match client.stabilize(ReceiverStream::new(rx)).await {
        Ok(r) => r.into_inner(),
        Err(_) => return (Vec::new(), Vec::new(), 0, total - warmup, true),
    };
    let mut latencies = Vec::with_capacity(total);
    let mut lags = Vec::with_capacity(total);
    let mut answered = 0;
    let mut failed = false;
    loop {
        match stream.message().await {
            Ok(Some(m)) => {
                let i = m.frame_index as usize;
                let Some((due, sent)) = sent_rx.recv().await else {
                    break;
                };
                if i >= warmup {
                    latencies.push(sent.elapsed().as_secs_f64() * 1e6);
                    lags.push(sent.saturating_duration_since(due).as_secs_f64() * 1e6);
                    answered += 1;
                }
            }
            Ok(None) => break,
            Err(_) => {
                failed = true;
                break;
            }
        }
    }
    sender.abort();
    (latencies, lags, answered, total - warmup, failed)
}

fn measure(server: &Server, frames: &Arc<Vec<Frame>>, run: Run) -> Outcome {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    let run = Arc::new(run);
    let url = server.grpc_url();
    runtime.block_on(async {
        // Every session starts its schedule at the same instant, 300 ms from now (connections
        // are set up before the first frame is due).
        let start = Instant::now() + Duration::from_millis(300);
        let period = Duration::from_secs_f64(1.0 / run.rate_hz);
        let tasks: Vec<_> = (0..run.sessions)
            .map(|i| {
                // Staggered: session i's frames are due i/N of a period after session 0's.
                let offset = if run.staggered {
                    period.mul_f64(i as f64 / run.sessions as f64)
                } else {
                    Duration::ZERO
                };
                tokio::spawn(one_session(
                    url.clone(),
                    frames.clone(),
                    run.clone(),
                    start + offset,
                ))
            })
            .collect();
        let measured_from = start + Duration::from_secs_f64(run.warmup_s);
        tokio::time::sleep_until(measured_from.into()).await;
        let cpu0 = cpu_seconds(server.pid());
        let t0 = Instant::now();
        let mut outcome = Outcome {
            latencies_us: Vec::new(),
            lags_us: Vec::new(),
            answered: 0,
            expected: 0,
            errors: 0,
            server_cpu_s: 0.0,
            measured_s: 0.0,
        };
        for t in tasks {
            let (lat, lags, answered, expected, failed) = t.await.expect("session task");
            outcome.latencies_us.extend(lat);
            outcome.lags_us.extend(lags);
            outcome.answered += answered;
            outcome.expected += expected;
            outcome.errors += usize::from(failed);
        }
        outcome.measured_s = t0.elapsed().as_secs_f64();
        outcome.server_cpu_s = cpu_seconds(server.pid()) - cpu0;
        outcome
    })
}

fn quantile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

fn main() {
    let graspd = release_graspd();
    let path = graspd_testkit::testdata_dir().join(RECORDING);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("cannot read {}: {e}", path.display());
            std::process::exit(2);
        }
    };
    let frames = Arc::new(
        Recording::from_csv(&text, None, None)
            .expect("the recording parses")
            .frames(),
    );
    let rate: f64 = bench_arg("--rate").unwrap_or(1000.0);
    let seconds: f64 = bench_arg("--seconds").unwrap_or(10.0);
    let staggered = std::env::args().any(|a| a == "--staggered");
    let model_free = std::env::args().any(|a| a == "--model-free");
    let counts: Vec<usize> = match bench_arg::<usize>("--sessions") {
        Some(n) => vec![n],
        None => vec![1, 5, 10, 25, 50],
    };
    let server = Server::start_binary(&graspd, &["--max-tactile-sessions", "256"]);
    println!(
        "tactile load: {} ({}), {} detector, rate {rate} Hz per session, {}, {seconds} s per run (first 1 s not counted), {} cores",
        graspd.display(),
        RECORDING,
        if model_free { "model-free" } else { "LSTM" },
        if staggered {
            "the sessions' frames spread over the period"
        } else {
            "every session's frame due at the same instant"
        },
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    println!(
        "| sessions | frames/s offered | frames/s answered | p50 µs | p99 µs | max µs | send lag p99 µs | lost | server CPU, cores | server µs CPU/frame |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for sessions in counts {
        let mut o = measure(
            &server,
            &frames,
            Run {
                sessions,
                rate_hz: rate,
                seconds: seconds + 1.0,
                warmup_s: 1.0,
                staggered,
                model_free,
            },
        );
        o.latencies_us.sort_by(f64::total_cmp);
        o.lags_us.sort_by(f64::total_cmp);
        // Over the whole measured span, which includes draining what fell behind.
        let answered_per_s = o.answered as f64 / o.measured_s.max(seconds);
        println!(
            "| {sessions} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} | {} | {:.2} | {:.1} |",
            sessions as f64 * rate,
            answered_per_s,
            quantile(&o.latencies_us, 0.5),
            quantile(&o.latencies_us, 0.99),
            o.latencies_us.last().copied().unwrap_or(f64::NAN),
            quantile(&o.lags_us, 0.99),
            o.expected - o.answered + o.errors,
            o.server_cpu_s / o.measured_s,
            o.server_cpu_s / o.answered.max(1) as f64 * 1e6,
        );
    }
}
