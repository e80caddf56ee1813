//! Overload against the real server (issue 8): a burst beyond the planner's concurrency and
//! queue gets plans or the shedding status (RESOURCE_EXHAUSTED with `retry-after-ms`, 503 with
//! `Retry-After`), none hangs and memory stays bounded; a caller's deadline is honoured while
//! queued or planning (DEADLINE_EXCEEDED, 504), and the planner keeps working afterwards.

use graspd_e2e::{
    Server, assert_valid_plan_works, base64, cylinder, grpc_request_with_points, http, metric,
    packed, rest_error,
};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};
use tonic::Code;
use tonic::codegen::http::Uri;

type RawClient = graspd_proto::v1::grasp_planner_client::GraspPlannerClient<
    hyper_util::client::legacy::Client<
        hyper_util::client::legacy::connect::HttpConnector,
        tonic::body::Body,
    >,
>;

/// A gRPC client over a plain HTTP/2 connection: it sends `grpc-timeout` but, unlike tonic's
/// channel (which answers CANCELLED "Timeout expired" itself at the deadline), waits for the
/// server's answer, so the test sees what the server says.
fn raw_grpc(server: &Server) -> RawClient {
    let client = hyper_util::client::legacy::Client::builder(hyper_util::rt::TokioExecutor::new())
        .http2_only(true)
        .build_http();
    let origin: Uri = server.grpc_url().parse().unwrap();
    RawClient::with_origin(client, origin)
}

/// Points of the large clouds: each plan takes tens of milliseconds or more.
const LARGE: usize = 100_000;

fn large_packed() -> Vec<u8> {
    packed(&cylinder(LARGE))
}

fn large_json(points: &[u8]) -> serde_json::Value {
    serde_json::json!({
        "cloud": {"points": base64(points)},
        "hand_name": "shadow",
        "options": {"seed": 3},
        "hints": {"support_plane": {"normal": [0, 0, 1], "offset": 0}},
    })
}

#[derive(Debug, PartialEq, Eq)]
enum Answer {
    Planned,
    Shed,
}

/// Samples the server's RSS every 10 ms until stopped; returns the peak.
fn watch_rss(server: &Server) -> (Arc<AtomicBool>, std::thread::JoinHandle<u64>) {
    let stop = Arc::new(AtomicBool::new(false));
    let peak = Arc::new(AtomicU64::new(0));
    let path = format!("/proc/{}/status", server.pid());
    let (s, p) = (stop.clone(), peak.clone());
    let handle = std::thread::spawn(move || {
        while !s.load(Ordering::Relaxed) {
            if let Some(kib) = std::fs::read_to_string(&path).ok().and_then(|t| {
                t.lines()
                    .find_map(|l| l.strip_prefix("VmRSS:"))
                    .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            }) {
                p.fetch_max(kib * 1024, Ordering::Relaxed);
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        p.load(Ordering::Relaxed)
    });
    (stop, handle)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn a_burst_gets_plans_or_shedding_none_hangs_and_memory_stays_bounded() {
    const CONCURRENCY: usize = 1;
    const QUEUE: usize = 2;
    const BURST: usize = 4 * (CONCURRENCY + QUEUE);
    let server = Server::start_with(&["--max-concurrent-plans", "1", "--max-queued-plans", "2"]);
    let points = large_packed();
    let json = Arc::new(large_json(&points));
    let grpc = server.grpc().await;
    let (stop, rss) = watch_rss(&server);
    let started = Instant::now();

    let mut tasks = tokio::task::JoinSet::new();
    for i in 0..BURST {
        if i % 2 == 0 {
            let mut client = grpc.clone();
            let request = grpc_request_with_points(points.clone(), "shadow", 3);
            tasks.spawn(async move {
                match client.plan_grasp(request).await {
                    Ok(_) => Answer::Planned,
                    Err(status) => {
                        assert_eq!(status.code(), Code::ResourceExhausted, "{status:?}");
                        assert_eq!(status.metadata().get("retry-after-ms").unwrap(), "1000");
                        assert!(status.message().contains("max_queued_plans"), "{status:?}");
                        Answer::Shed
                    }
                }
            });
        } else {
            let url = server.rest_url("/v1/plan");
            let body = json.clone();
            tasks.spawn(async move {
                let response = http().post(url).json(&*body).send().await.unwrap();
                if response.status() == 200 {
                    return Answer::Planned;
                }
                assert_eq!(response.headers()["retry-after"], "1");
                let (status, code, _, message) = rest_error(response).await;
                assert_eq!(
                    (status, code.as_str()),
                    (503, "resource_exhausted"),
                    "{message}"
                );
                Answer::Shed
            });
        }
    }
    let answers = tokio::time::timeout(Duration::from_secs(180), tasks.join_all())
        .await
        .expect("the burst hung");
    let elapsed = started.elapsed();
    stop.store(true, Ordering::Relaxed);
    let peak = rss.join().unwrap();

    let shed = answers.iter().filter(|a| **a == Answer::Shed).count();
    let planned = answers.len() - shed;
    eprintln!(
        "burst of {BURST}: {planned} planned, {shed} shed in {elapsed:?}; peak RSS {} MB",
        peak >> 20
    );
    assert_eq!(answers.len(), BURST);
    assert!(shed >= 1, "nothing was shed");
    assert!(planned >= 1, "nothing was planned");
    assert!(peak > 0 && peak < 300 << 20, "peak RSS {} MB", peak >> 20);
    let after = server.rss_bytes().expect("VmRSS");
    assert!(after < 300 << 20, "RSS after the burst {} MB", after >> 20);

    let text = server.metrics().await;
    assert_eq!(
        metric(&text, "graspd_shed_requests_total", &[]),
        Some(shed as f64),
        "{text}"
    );
    assert_eq!(metric(&text, "graspd_plans_queued", &[]), Some(0.0));
    assert_eq!(metric(&text, "graspd_plans_running", &[]), Some(0.0));
    assert_valid_plan_works(&server).await;
}

#[tokio::test]
async fn an_expired_deadline_gets_deadline_exceeded_and_the_next_request_works() {
    let server = Server::start_with(&["--max-concurrent-plans", "1", "--max-queued-plans", "4"]);
    let points = large_packed();
    let mut grpc = server.grpc().await;

    // How long a large plan takes here.
    let started = Instant::now();
    grpc.plan_grasp(grpc_request_with_points(points.clone(), "shadow", 3))
        .await
        .unwrap();
    let plan_time = started.elapsed();

    let mut raw = raw_grpc(&server);
    let mut request = tonic::Request::new(grpc_request_with_points(points.clone(), "shadow", 3));
    request.set_timeout(Duration::from_millis(1));
    let status = raw.plan_grasp(request).await.unwrap_err();
    assert_eq!(status.code(), Code::DeadlineExceeded, "{status:?}");

    // A deadline that passes while planning: answered at the deadline, not when the plan ends.
    let budget = (plan_time / 4).max(Duration::from_millis(5));
    let mut request = tonic::Request::new(grpc_request_with_points(points.clone(), "shadow", 3));
    request.set_timeout(budget);
    let started = Instant::now();
    let status = raw.plan_grasp(request).await.unwrap_err();
    let answered = started.elapsed();
    assert_eq!(status.code(), Code::DeadlineExceeded, "{status:?}");
    eprintln!("plan {plan_time:?}; deadline {budget:?} answered after {answered:?}");
    assert!(
        answered < budget + Duration::from_millis(500),
        "answered after {answered:?} for a {budget:?} deadline"
    );

    // REST: the optional x-request-timeout-ms header, and a bad value named. Small bodies: the
    // server may answer before it has read a large one and close the connection, and the client
    // then fails writing it (EPIPE) instead of reading the answer.
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .header("x-request-timeout-ms", "1")
        .json(&graspd_e2e::json_request("shadow", 0))
        .send()
        .await
        .unwrap();
    let (status, code, _, _) = rest_error(response).await;
    assert_eq!((status, code.as_str()), (504, "deadline_exceeded"));
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .header("x-request-timeout-ms", "soon")
        .json(&graspd_e2e::json_request("shadow", 0))
        .send()
        .await
        .unwrap();
    let (status, code, field, _) = rest_error(response).await;
    assert_eq!((status, code.as_str()), (400, "invalid_argument"));
    assert_eq!(field.as_deref(), Some("x-request-timeout-ms"));

    // The abandoned plans end in the background and give their planner back: with one planner,
    // the next requests (which wait for it) still plan, on both transports.
    assert_valid_plan_works(&server).await;
    let mut request = tonic::Request::new(grpc_request_with_points(points, "shadow", 3));
    request.set_timeout(Duration::from_secs(60));
    grpc.plan_grasp(request).await.unwrap();
    let text = server.metrics().await;
    assert_eq!(
        metric(
            &text,
            "graspd_request_errors_total",
            &[("code", "DEADLINE_EXCEEDED")]
        ),
        Some(2.0),
        "{text}"
    );
    assert_eq!(
        metric(&text, "graspd_request_errors_total", &[("code", "504")]),
        Some(1.0)
    );
    assert_eq!(metric(&text, "graspd_plans_running", &[]), Some(0.0));
}

/// Hand imports, tactile analyses and calibrations use the planners' threads and queue: while a
/// long plan holds the only place (`--max-concurrent-plans 1 --max-queued-plans 0`), each is shed
/// like a plan — RESOURCE_EXHAUSTED with `retry-after-ms` (gRPC), 503 with `Retry-After` (REST)
/// — and once the plan is done each works (issue 20).
#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn hand_imports_and_tactile_analyses_are_shed_like_plans() {
    let server = Server::start_with(&["--max-concurrent-plans", "1", "--max-queued-plans", "0"]);
    let grpc = server.grpc().await;
    // About a second on the 2-core machine; what follows takes milliseconds.
    let request = grpc_request_with_points(packed(&cylinder(2 * LARGE)), "shadow", 3);
    let started = Instant::now();
    let plan = tokio::spawn({
        let mut client = grpc.clone();
        async move { client.plan_grasp(request).await }
    });
    while metric(&server.metrics().await, "graspd_plans_running", &[]) != Some(1.0) {
        assert!(
            !plan.is_finished(),
            "the plan ended before it was seen running"
        );
        tokio::time::sleep(Duration::from_millis(2)).await;
    }

    let urdf = r#"<robot name="pair">
      <link name="base"><collision><geometry><box size="0.06 0.04 0.02"/></geometry></collision></link>
      <link name="a"><collision><origin xyz="0 0 0.03"/><geometry><cylinder radius="0.008" length="0.06"/></geometry></collision></link>
      <link name="b"><collision><origin xyz="0 0 0.03"/><geometry><cylinder radius="0.008" length="0.06"/></geometry></collision></link>
      <joint name="ja" type="revolute"><parent link="base"/><child link="a"/>
        <origin xyz="0.02 0 0.01"/><axis xyz="0 1 0"/><limit lower="-1.2" upper="0.3"/></joint>
      <joint name="jb" type="revolute"><parent link="base"/><child link="b"/>
        <origin xyz="-0.02 0 0.01"/><axis xyz="0 1 0"/><limit lower="-0.3" upper="1.2"/></joint>
    </robot>"#;
    let register = graspd_proto::v1::RegisterHandRequest {
        name: "pair".into(),
        model: Some(graspd_proto::v1::HandModel {
            format: "urdf".into(),
            text: urdf.into(),
            ..Default::default()
        }),
        ..Default::default()
    };
    let register_json =
        serde_json::json!({"name": "pair", "model": {"format": "urdf", "text": urdf}});
    let reading = serde_json::json!({"pdc": 0.0, "pac": 0.0, "tdc": 0.0, "tac": 0.0,
                                     "electrodes": vec![0.0; 19]});
    let analyze_json = serde_json::json!({
        "session": {"fingers": [{"name": "th", "layout": "biotac", "tare": {"pretared": true}}]},
        "frames": [{"timestamp": 0.0, "fingers": [reading]}],
    });

    let status = grpc
        .clone()
        .register_hand(register.clone())
        .await
        .unwrap_err();
    assert_eq!(status.code(), Code::ResourceExhausted, "{status:?}");
    assert_eq!(status.metadata().get("retry-after-ms").unwrap(), "1000");
    for (path, body) in [
        ("/v1/hands", &register_json),
        ("/v1/tactile/analyze", &analyze_json),
    ] {
        let response = http()
            .post(server.rest_url(path))
            .json(body)
            .send()
            .await
            .unwrap();
        assert_eq!(
            response
                .headers()
                .get("retry-after")
                .map(|v| v.to_str().unwrap()),
            Some("1"),
            "{path}"
        );
        let (status, code, _, message) = rest_error(response).await;
        assert_eq!(
            (status, code.as_str()),
            (503, "resource_exhausted"),
            "{path}: {message}"
        );
        assert!(message.contains("max_queued_plans"), "{message}");
    }
    assert!(
        !plan.is_finished(),
        "the plan ended during the test ({:?}): make it longer",
        started.elapsed()
    );
    assert!(plan.await.unwrap().is_ok());
    eprintln!("the long plan took {:?}", started.elapsed());
    let shed = metric(&server.metrics().await, "graspd_shed_requests_total", &[]).unwrap();
    assert_eq!(shed, 3.0);

    grpc.clone().register_hand(register).await.unwrap();
    let response = http()
        .post(server.rest_url("/v1/tactile/analyze"))
        .json(&analyze_json)
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200, "{}", response.text().await.unwrap());
}

/// Writes a large POST over HTTP/1.1 in chunks, as a client that sends its whole body before
/// reading; returns the status line it then reads (or the write or read error).
fn post_whole_body(
    addr: std::net::SocketAddr,
    headers: &str,
    len: usize,
) -> Result<String, String> {
    use std::io::{BufRead, BufReader, Write};
    let mut s = std::net::TcpStream::connect(addr).map_err(|e| e.to_string())?;
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    s.set_write_timeout(Some(Duration::from_secs(30))).unwrap();
    write!(
        s,
        "POST /v1/plan HTTP/1.1\r\nhost: localhost\r\ncontent-type: application/json\r\n\
         content-length: {len}\r\n{headers}\r\n"
    )
    .map_err(|e| e.to_string())?;
    let chunk = vec![b' '; 64 * 1024];
    let mut sent = 0;
    while sent < len {
        let n = chunk.len().min(len - sent);
        s.write_all(&chunk[..n])
            .map_err(|e| format!("writing the body at byte {sent}: {e}"))?;
        sent += n;
    }
    let mut line = String::new();
    BufReader::new(s)
        .read_line(&mut line)
        .map_err(|e| format!("reading the answer: {e}"))?;
    Ok(line.trim_end().to_string())
}

/// An answer decided before the body is read — a deadline already passed, a missing token —
/// still reaches an HTTP/1.1 client that writes its whole (large) body first: graspd reads and
/// drops the rest of the body (up to max_message_bytes) before answering, instead of closing
/// the connection under the client's writes (EPIPE) (issue 20).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn answers_decided_early_reach_a_client_still_writing_its_body() {
    let server = Server::start_with(&["--auth-token", "secret-token"]);
    let addr = server.rest_addr;
    let len = 16 << 20;
    let cases = [
        (
            "authorization: Bearer secret-token\r\nx-request-timeout-ms: 1\r\n",
            "504",
        ),
        ("", "401"),
    ];
    for (headers, status) in cases {
        let line = tokio::task::spawn_blocking(move || post_whole_body(addr, headers, len))
            .await
            .unwrap();
        let line = line.unwrap_or_else(|e| panic!("{status}: {e}"));
        assert!(line.starts_with(&format!("HTTP/1.1 {status}")), "{line}");
    }
}
