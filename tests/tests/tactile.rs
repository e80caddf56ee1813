//! Tactile stabilization end to end (issue 5): a real BioTac recording streamed over gRPC gets
//! one setpoint per frame, `POST /v1/tactile/analyze` (CSV and JSON) gives the same results, bad
//! sessions and frames end the stream with INVALID_ARGUMENT naming the field, and the session
//! limit refuses the extra session and frees the slot the moment a client disconnects. With the
//! shipped LSTM model (models/tactile) a session reports material probabilities while in contact,
//! a session asking for a model the server has not loaded is refused naming the field, and a
//! `--tactile-model` file that does not load stops the start.

use graspd_api::convert;
use graspd_api::request::{LayoutChoice, TactileFingerRequest, TactileSessionRequest};
use graspd_core::tactile::stabilizer::LATCH_STEP_S;
use graspd_core::tactile::{Frame, Recording, StabilizerConfig, TareConfig};
use graspd_e2e::{Server, assert_valid_plan_works, http, refused_naming, rest_error};
use graspd_proto::v1 as pb;
use graspd_proto::v1::stabilize_request::Kind;
use graspd_proto::v1::tactile_stabilizer_client::TactileStabilizerClient;
use std::time::{Duration, Instant};
use tokio::sync::mpsc;
use tonic::codegen::tokio_stream::wrappers::ReceiverStream;
use tonic::{Code, Status, Streaming};

const RECORDING: &str = "tactile/biotac_slide/mat5/mat5_1_bio.csv";

fn recording_text() -> String {
    let path = graspd_testkit::testdata_dir().join(RECORDING);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

fn recording_frames() -> Vec<Frame> {
    Recording::from_csv(&recording_text(), None, None)
        .expect("the recording parses")
        .frames()
}

/// One classic BioTac named `th`; the dexrob recordings are already tared.
fn session() -> pb::TactileSession {
    convert::tactile_session_to_proto(&TactileSessionRequest {
        fingers: vec![TactileFingerRequest {
            name: "th".into(),
            layout: LayoutChoice::Name("biotac".into()),
            tare: TareConfig::pretared(),
            electrodes_only: false,
            calibration: None,
        }],
        config: StabilizerConfig::default(),
    })
}

fn frame_message(f: &Frame) -> pb::StabilizeRequest {
    pb::StabilizeRequest {
        kind: Some(Kind::Frame(convert::tactile_frame_to_proto(f))),
    }
}

type Open = (
    mpsc::Sender<pb::StabilizeRequest>,
    Streaming<pb::StabilizationSetpoint>,
);

/// Opens a stream whose first message is `session`; Ok once the server has opened the session.
async fn open(server: &Server, session: pb::TactileSession) -> Result<Open, Status> {
    open_at(server.grpc_url(), session).await
}

async fn open_at(url: String, session: pb::TactileSession) -> Result<Open, Status> {
    let mut client = TactileStabilizerClient::connect(url)
        .await
        .expect("connect to graspd's gRPC port");
    let (tx, rx) = mpsc::channel(8);
    tx.send(pb::StabilizeRequest {
        kind: Some(Kind::Session(session)),
    })
    .await
    .unwrap();
    let response = client.stabilize(ReceiverStream::new(rx)).await?;
    Ok((tx, response.into_inner()))
}

fn field_of(s: &Status) -> String {
    s.metadata()
        .get("graspd-field")
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_string()
}

/// Sends `frames` one by one, reading each answer; returns the answers and the final error.
async fn exchange(
    (tx, mut rx): Open,
    frames: &[Frame],
) -> (Vec<pb::StabilizationSetpoint>, Option<Status>) {
    let mut answers = Vec::new();
    for f in frames {
        if tx.send(frame_message(f)).await.is_err() {
            break;
        }
        match rx.message().await {
            Ok(Some(m)) => answers.push(m),
            Ok(None) => return (answers, None),
            Err(s) => return (answers, Some(s)),
        }
    }
    drop(tx);
    let end = rx.message().await;
    (answers, end.err())
}

#[tokio::test]
async fn grpc_stream_replays_a_real_recording_and_analyze_gives_the_same_results() {
    let server = Server::start();
    let frames = recording_frames();
    assert!(frames.len() > 500, "{} frames", frames.len());

    // Stream: a sender task pushes every frame while this task reads the answers.
    let (tx, mut rx) = open(&server, session()).await.expect("session opens");
    let sent = frames.clone();
    let sender = tokio::spawn(async move {
        for f in &sent {
            tx.send(frame_message(f))
                .await
                .expect("the stream stays open");
        }
    });
    let mut streamed = Vec::new();
    while let Some(m) = rx.message().await.expect("no stream error") {
        assert_eq!(m.frame_index, streamed.len() as u64);
        assert_eq!(m.timestamp, frames[streamed.len()].timestamp);
        assert_eq!(m.fingers.len(), 1);
        assert_eq!(m.fingers[0].finger, "th");
        streamed.push(m);
    }
    sender.await.unwrap();
    assert_eq!(streamed.len(), frames.len(), "one setpoint per frame");
    let in_contact = streamed
        .iter()
        .filter(|m| m.fingers[0].event != pb::ContactEvent::NonContact as i32)
        .count();
    assert!(
        in_contact > 0,
        "the recording presses the sensor; no frame was in contact"
    );
    assert!(
        streamed
            .iter()
            .any(|m| m.fingers[0].mode == pb::ControlMode::Force as i32
                && m.fingers[0].setpoint.is_some())
    );
    let streamed: Vec<serde_json::Value> = streamed
        .into_iter()
        .map(|m| serde_json::to_value(convert::setpoint_from_proto(m).unwrap()).unwrap())
        .collect();

    // Analyze, the recording as text/csv with the session in the query.
    let response = http()
        .post(server.rest_url("/v1/tactile/analyze?pretared=true&finger=th&layout=biotac"))
        .header("content-type", "text/csv")
        .body(recording_text())
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let body: serde_json::Value = response.json().await.unwrap();
    assert_eq!(body["frame_count"], frames.len());
    let analyzed = body["frames"].as_array().unwrap();
    assert_eq!(analyzed.len(), frames.len());
    for (i, (a, s)) in analyzed.iter().zip(&streamed).enumerate() {
        assert_eq!(a, s, "frame {i}: analyze and the stream differ");
    }

    // Analyze, the same recording as JSON.
    let session = serde_json::json!({
        "fingers": [{"name": "th", "layout": "biotac", "tare": {"pretared": true}}]
    });
    assert_eq!(analyze_json(&server, session, &frames).await, streamed);
}

/// `POST /v1/tactile/analyze` with a JSON body: `session` over `frames` (one finger each);
/// returns the answer's frames.
async fn analyze_json(
    server: &Server,
    session: serde_json::Value,
    frames: &[Frame],
) -> Vec<serde_json::Value> {
    let frames: Vec<serde_json::Value> = frames
        .iter()
        .map(|f| {
            let r = &f.fingers[0];
            serde_json::json!({"timestamp": f.timestamp, "fingers": [{
                "pdc": r.pdc, "pac": r.pac, "tdc": r.tdc, "tac": r.tac, "electrodes": r.electrodes,
            }]})
        })
        .collect();
    let response = http()
        .post(server.rest_url("/v1/tactile/analyze"))
        .json(&serde_json::json!({"session": session, "frames": frames}))
        .send()
        .await
        .unwrap();
    analyzed_frames(response).await
}

/// The frames of a 200 answer of `POST /v1/tactile/analyze`.
async fn analyzed_frames(response: reqwest::Response) -> Vec<serde_json::Value> {
    assert_eq!(response.status(), 200);
    let body: serde_json::Value = response.json().await.unwrap();
    body["frames"].as_array().unwrap().clone()
}

/// `latch_slip` (a deviation from Eq 6.9, off by default) on the real slide: every transport
/// gives the same answers, and in contact f_d is f0 + δf_s per slip episode since the contact
/// began, a slip that lasts counting again every LATCH_STEP_S (clipped at f_max) — frames that
/// no longer slip keep the raised force, where Eq 6.9 as printed drops it back to f0.
#[tokio::test]
async fn a_latched_slip_keeps_the_force_raised_until_contact_is_lost() {
    let server = Server::start();
    let text = recording_text();
    let analyze = |query: &'static str| {
        let url = server.rest_url(&format!(
            "/v1/tactile/analyze?pretared=true&finger=th&layout=biotac&delta_material=0{query}"
        ));
        let text = text.clone();
        async move {
            let response = http()
                .post(url)
                .header("content-type", "text/csv")
                .body(text)
                .send()
                .await
                .unwrap();
            analyzed_frames(response).await
        }
    };
    let latched = analyze("&latch_slip=true").await;
    let plain = analyze("").await;
    let (f0, delta, f_max) = (1.5, 0.5, 5.0);
    let mut episodes = 0u32;
    let mut slipping = false;
    let mut raised_at = f64::NEG_INFINITY;
    let (mut held_after_slip, mut fell_back) = (0, 0);
    for (i, (l, p)) in latched.iter().zip(&plain).enumerate() {
        let (l, p) = (&l["fingers"][0], &p["fingers"][0]);
        assert_eq!(
            l["event"], p["event"],
            "frame {i}: the latch changes no detection"
        );
        let event = l["event"].as_str().unwrap();
        let t = latched[i]["timestamp"].as_f64().unwrap();
        match event {
            "non_contact" => episodes = 0,
            "slip" if !slipping || t - raised_at >= LATCH_STEP_S => {
                episodes += 1;
                raised_at = t;
            }
            _ => {}
        }
        slipping = event == "slip";
        let want = if event == "non_contact" {
            f0
        } else {
            (f0 + delta * episodes as f64).min(f_max)
        };
        let got = l["desired_force"].as_f64().unwrap();
        assert!(
            (got - want).abs() < 1e-9,
            "frame {i}: f_d {got}, want {want}"
        );
        if event == "contact" && episodes > 0 {
            held_after_slip += 1;
            if p["desired_force"].as_f64().unwrap() == f0 {
                fell_back += 1;
            }
        }
    }
    assert!(
        held_after_slip > 0 && fell_back == held_after_slip,
        "contact after slip: {held_after_slip} frames, Eq 6.9 dropped {fell_back} back to f0"
    );

    // The JSON body and the gRPC stream take the same option and answer alike.
    let frames = recording_frames();
    let session_json = serde_json::json!({
        "fingers": [{"name": "th", "layout": "biotac", "tare": {"pretared": true}}],
        "delta_material": 0.0, "latch_slip": true,
    });
    assert_eq!(analyze_json(&server, session_json, &frames).await, latched);
    let mut grpc_session = session();
    grpc_session.delta_material = Some(0.0);
    grpc_session.latch_slip = Some(true);
    let open = open(&server, grpc_session).await.expect("session opens");
    let (answers, end) = exchange(open, &frames).await;
    assert!(end.is_none(), "{end:?}");
    let streamed: Vec<serde_json::Value> = answers
        .into_iter()
        .map(|m| serde_json::to_value(convert::setpoint_from_proto(m).unwrap()).unwrap())
        .collect();
    assert_eq!(streamed, latched);
}

/// An electrodes-only finger (issue 16 part 3) on a real BioTac SP recording, which has only
/// the 24 electrodes: JSON analyze takes frames with no pac at all, the gRPC stream frames with
/// an empty pac, and both answer every frame alike, in contact once the baseline is complete;
/// the same frames on an ordinary finger are refused naming the pac.
#[tokio::test]
async fn an_electrodes_only_finger_runs_on_a_real_biotac_sp_recording() {
    let server = Server::start();
    let path = graspd_testkit::testdata_dir().join("tactile/biotac_sp/dos_basic/n/case122.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let frames: Vec<Frame> = text
        .lines()
        .skip(1)
        .enumerate()
        .map(|(k, line)| Frame {
            timestamp: 0.01 * k as f64,
            fingers: vec![graspd_core::tactile::FingerReading {
                electrodes: line.split(',').map(|v| v.trim().parse().unwrap()).collect(),
                ..Default::default()
            }],
        })
        .collect();
    let finger = |electrodes_only: bool| {
        serde_json::json!({"name": "ff", "layout": "biotac_sp", "electrodes_only": electrodes_only,
                           "tare": {"baseline_frames": 50}})
    };
    let json_frames: Vec<serde_json::Value> = frames
        .iter()
        .map(|f| {
            serde_json::json!({"timestamp": f.timestamp, "fingers": [{
                "pdc": 0, "tdc": 0, "tac": 0, "electrodes": f.fingers[0].electrodes}]})
        })
        .collect();
    let response = http()
        .post(server.rest_url("/v1/tactile/analyze"))
        .json(&serde_json::json!({"session": {"fingers": [finger(true)]}, "frames": json_frames}))
        .send()
        .await
        .unwrap();
    let analyzed = analyzed_frames(response).await;
    assert_eq!(analyzed.len(), frames.len());
    let touching = analyzed[60..]
        .iter()
        .filter(|f| f["fingers"][0]["event"] != "non_contact")
        .count();
    assert!(
        touching > 150,
        "{touching} of {} frames in contact",
        analyzed.len() - 60
    );

    let mut session = pb::TactileSession::default();
    session.fingers.push(pb::TactileFinger {
        name: "ff".into(),
        layout: Some(pb::tactile_finger::Layout::LayoutName("biotac_sp".into())),
        tare: Some(pb::TareSettings {
            baseline_frames: Some(50),
            ..Default::default()
        }),
        electrodes_only: true,
        calibration: None,
    });
    let open = open(&server, session).await.expect("session opens");
    let (answers, end) = exchange(open, &frames).await;
    assert!(end.is_none(), "{end:?}");
    let streamed: Vec<serde_json::Value> = answers
        .into_iter()
        .map(|m| serde_json::to_value(convert::setpoint_from_proto(m).unwrap()).unwrap())
        .collect();
    assert_eq!(streamed, analyzed);

    let response = http()
        .post(server.rest_url("/v1/tactile/analyze"))
        .json(&serde_json::json!({"session": {"fingers": [finger(false)]},
                                  "frames": &json_frames[..3]}))
        .send()
        .await
        .unwrap();
    let message = refused_naming(response, "frames[0].fingers[0].pac").await;
    assert!(message.contains("electrodes_only"), "{message}");
}

#[tokio::test]
async fn bad_sessions_and_frames_end_the_stream_naming_the_field() {
    let server = Server::start();
    let frames = recording_frames();
    let good = &frames[..3];

    // Mismatched electrode count.
    let mut short = good[2].clone();
    short.fingers[0].electrodes.pop();
    let open1 = open(&server, session()).await.unwrap();
    let (answers, end) = exchange(open1, &[good[0].clone(), good[1].clone(), short]).await;
    assert_eq!(answers.len(), 2);
    let e = end.expect("the stream ends with an error");
    assert_eq!(e.code(), Code::InvalidArgument, "{e:?}");
    assert_eq!(field_of(&e), "frame.fingers[0].electrodes");
    assert!(
        e.message()
            .contains("frame.fingers[0].electrodes: 18 values, layout biotac has 19"),
        "{}",
        e.message()
    );

    // Wrong finger count.
    let mut two = good[1].clone();
    two.fingers.push(two.fingers[0].clone());
    let (answers, end) = exchange(
        open(&server, session()).await.unwrap(),
        &[good[0].clone(), two],
    )
    .await;
    assert_eq!(answers.len(), 1);
    let e = end.unwrap();
    assert_eq!(e.code(), Code::InvalidArgument);
    assert_eq!(field_of(&e), "frame.fingers");
    assert!(
        e.message()
            .contains("2 readings, the session has 1 fingers")
    );

    // Out-of-order timestamps.
    let (answers, end) = exchange(
        open(&server, session()).await.unwrap(),
        &[good[1].clone(), good[0].clone()],
    )
    .await;
    assert_eq!(answers.len(), 1);
    let e = end.unwrap();
    assert_eq!(e.code(), Code::InvalidArgument);
    assert_eq!(field_of(&e), "frame.timestamp");
    assert!(e.message().contains("out of order"), "{}", e.message());

    // Bad sessions are refused before any frame.
    let mut s = session();
    s.fingers[0].layout = Some(pb::tactile_finger::Layout::LayoutName("biotac_xl".into()));
    let e = open(&server, s).await.unwrap_err();
    assert_eq!(e.code(), Code::InvalidArgument);
    assert_eq!(field_of(&e), "session.fingers[0].layout");
    assert!(e.message().contains("biotac, biotac_sp"), "{}", e.message());
    let mut s = session();
    s.stride = Some(0);
    let e = open(&server, s).await.unwrap_err();
    assert_eq!(field_of(&e), "session.stride");
    let mut s = session();
    s.fingers[0].layout = Some(pb::tactile_finger::Layout::CustomLayout(pb::CustomLayout {
        name: "two".into(),
        electrodes: vec![
            pb::Electrode {
                x_mm: 0.0,
                y_mm: 0.0
            };
            2
        ],
    }));
    let e = open(&server, s).await.unwrap_err();
    assert_eq!(field_of(&e), "session.fingers[0].layout.electrodes[1]");
    let mut s = session();
    s.centroid_slip_mm_s = Some(-5.0);
    let e = open(&server, s).await.unwrap_err();
    assert_eq!(field_of(&e), "session.centroid_slip_mm_s");

    // A frame as the first message.
    let mut client = TactileStabilizerClient::connect(server.grpc_url())
        .await
        .unwrap();
    let first = tonic::codegen::tokio_stream::iter([frame_message(&good[0])]);
    let e = client.stabilize(first).await.unwrap_err();
    assert_eq!(e.code(), Code::InvalidArgument);
    assert_eq!(field_of(&e), "session");

    // The same faults through analyze name the frame.
    let response = http()
        .post(server.rest_url("/v1/tactile/analyze"))
        .json(&serde_json::json!({
            "session": {"fingers": [{"name": "th", "layout": "biotac_sp"}]},
            "frames": [{"timestamp": 0.0, "fingers": [{
                "pdc": 0, "pac": 0, "tdc": 0, "tac": 0, "electrodes": vec![0.0; 19]}]}],
        }))
        .send()
        .await
        .unwrap();
    let message = refused_naming(response, "frames[0].fingers[0].electrodes").await;
    assert!(message.contains("layout biotac_sp has 24"), "{message}");
    let response = http()
        .post(server.rest_url("/v1/tactile/analyze?pretared=yes"))
        .header("content-type", "text/csv")
        .body(recording_text())
        .send()
        .await
        .unwrap();
    refused_naming(response, "query").await;
    let response = http()
        .post(server.rest_url("/v1/tactile/analyze?pretared=true&centroid_slip_mm_s=0"))
        .header("content-type", "text/csv")
        .body(recording_text())
        .send()
        .await
        .unwrap();
    let message = refused_naming(response, "session.centroid_slip_mm_s").await;
    assert!(message.contains("positive"), "{message}");
}

#[tokio::test]
async fn the_session_limit_refuses_the_extra_session_and_frees_it_on_disconnect() {
    let server = Server::start_with(&["--max-tactile-sessions", "1"]);
    let frames = recording_frames();
    // The first client runs on its own runtime, so that dropping the runtime cuts its connection
    // mid-session like a crashed client (no clean end of the request stream).
    let url = server.grpc_url();
    let first = frames[0].clone();
    let (opened_tx, opened_rx) = std::sync::mpsc::channel();
    let (kill_tx, kill_rx) = std::sync::mpsc::channel::<()>();
    let client = std::thread::spawn(move || {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap();
        let held = rt.block_on(async move {
            let (tx, mut rx) = open_at(url, session()).await.expect("first session");
            tx.send(frame_message(&first)).await.unwrap();
            assert!(rx.message().await.unwrap().is_some());
            (tx, rx)
        });
        opened_tx.send(()).unwrap();
        let _ = kill_rx.recv();
        drop(rt);
        drop(held);
    });
    opened_rx.recv().unwrap();

    let e = open(&server, session()).await.unwrap_err();
    assert_eq!(e.code(), Code::ResourceExhausted, "{e:?}");
    assert!(
        e.message().contains("max_tactile_sessions"),
        "{}",
        e.message()
    );
    let response = http()
        .post(server.rest_url("/v1/tactile/analyze?pretared=true"))
        .header("content-type", "text/csv")
        .body(recording_text())
        .send()
        .await
        .unwrap();
    let (status, code, _, _) = rest_error(response).await;
    assert_eq!((status, code.as_str()), (503, "resource_exhausted"));

    // Disconnect.
    kill_tx.send(()).unwrap();
    client.join().unwrap();
    let started = Instant::now();
    let second = loop {
        match open(&server, session()).await {
            Ok(o) => break o,
            Err(e) if e.code() == Code::ResourceExhausted => {
                assert!(
                    started.elapsed() < Duration::from_secs(5),
                    "the slot was not freed after the disconnect"
                );
                tokio::time::sleep(Duration::from_millis(20)).await;
            }
            Err(e) => panic!("{e:?}"),
        }
    };
    let (answers, end) = exchange(second, &frames[..2]).await;
    assert_eq!(answers.len(), 2);
    assert!(end.is_none(), "{end:?}");
}

/// Resident memory of a process, bytes (Linux).
fn rss_bytes(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|kb| kb.parse::<u64>().ok())
        .map_or(0, |kb| kb * 1024)
}

#[tokio::test]
async fn a_reader_that_does_not_read_stalls_its_stream_not_the_servers_memory() {
    let server = Server::start();
    let frames = recording_frames();
    let (tx, mut rx) = open(&server, session()).await.unwrap();
    let before = rss_bytes(server.pid());
    // Send without reading any answer: the bounded queues and HTTP/2 flow control must stop the
    // sender long before 50,000 frames (about 20 MB of readings) are in flight.
    let mut sent = 0usize;
    let mut stalled = false;
    for i in 0..50_000 {
        let mut f = frames[i % frames.len()].clone();
        f.timestamp = i as f64 * 0.001;
        match tokio::time::timeout(Duration::from_secs(2), tx.send(frame_message(&f))).await {
            Ok(Ok(())) => sent += 1,
            Ok(Err(_)) => panic!("the stream closed after {sent} frames"),
            Err(_) => {
                stalled = true;
                break;
            }
        }
    }
    assert!(
        stalled,
        "all {sent} frames were taken without reading an answer"
    );
    let grown = rss_bytes(server.pid()).saturating_sub(before);
    eprintln!("stalled after {sent} unread frames; server memory +{grown} bytes");
    assert!(
        grown < 16 << 20,
        "server memory grew by {grown} bytes with {sent} frames unread"
    );
    // Reading resumes the stream: the answers come in order, one per frame.
    for i in 0..sent.min(500) {
        let m = rx.message().await.unwrap().expect("an answer");
        assert_eq!(m.frame_index as usize, i);
    }
    drop(tx);
    drop(rx);
    assert_valid_plan_works(&server).await;
}

mod websocket {
    use super::*;
    use futures_util::{SinkExt, StreamExt};
    use tokio_tungstenite::tungstenite::Message;

    type Ws = tokio_tungstenite::WebSocketStream<
        tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>,
    >;

    async fn connect(server: &Server) -> Ws {
        let url = format!("ws://{}/v1/stabilize", server.rest_addr);
        tokio_tungstenite::connect_async(url)
            .await
            .expect("WebSocket handshake")
            .0
    }

    async fn send(ws: &mut Ws, v: serde_json::Value) {
        ws.send(Message::text(v.to_string())).await.unwrap();
    }

    async fn next_json(ws: &mut Ws) -> serde_json::Value {
        loop {
            match ws
                .next()
                .await
                .expect("a message")
                .expect("no socket error")
            {
                Message::Text(t) => return serde_json::from_str(t.as_str()).unwrap(),
                Message::Ping(_) | Message::Pong(_) => continue,
                other => panic!("unexpected {other:?}"),
            }
        }
    }

    fn session_json() -> serde_json::Value {
        serde_json::json!({"fingers": [{"name": "th", "layout": "biotac", "tare": {"pretared": true}}]})
    }

    fn frame_json(f: &Frame) -> serde_json::Value {
        let r = &f.fingers[0];
        serde_json::json!({"frame": {"timestamp": f.timestamp, "fingers": [{
            "pdc": r.pdc, "pac": r.pac, "tdc": r.tdc, "tac": r.tac, "electrodes": r.electrodes,
        }]}})
    }

    /// A WebSocket session's log lines carry its upgrade request's id, like every request's
    /// (issue 20): opened, closed, and a refused message.
    #[tokio::test]
    async fn websocket_sessions_log_with_their_request_id() {
        use tokio_tungstenite::tungstenite::client::IntoClientRequest;
        let server = Server::start_with_logs(&["--log", "debug", "--log-format", "json"]);
        let mut request = format!("ws://{}/v1/stabilize", server.rest_addr)
            .into_client_request()
            .unwrap();
        request
            .headers_mut()
            .insert("x-request-id", "ws-session-9".parse().unwrap());
        let (mut ws, response) = tokio_tungstenite::connect_async(request).await.unwrap();
        assert_eq!(response.headers()["x-request-id"], "ws-session-9");
        send(&mut ws, serde_json::json!({"session": session_json()})).await;
        let frames = recording_frames();
        send(&mut ws, frame_json(&frames[0])).await;
        next_json(&mut ws).await;
        send(&mut ws, serde_json::json!({"frame": {"timestamp": -1.0}})).await;
        assert!(next_json(&mut ws).await["error"].is_object());
        let logged = |message: &str| {
            server.logs().iter().any(|line| {
                serde_json::from_str::<serde_json::Value>(line).is_ok_and(|v| {
                    v["fields"]["message"] == message && v["span"]["request_id"] == "ws-session-9"
                })
            })
        };
        let expected = [
            "tactile session opened",
            "tactile session refused a message",
            "tactile session closed",
        ];
        for _ in 0..100 {
            if expected.iter().all(|m| logged(m)) {
                break;
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
        for m in expected {
            assert!(
                logged(m),
                "no {m:?} line with the request id:\n{:#?}",
                server.logs()
            );
        }
    }

    #[tokio::test]
    async fn websocket_session_replays_a_real_recording_like_analyze() {
        let server = Server::start();
        let frames = recording_frames();
        let response = http()
            .post(server.rest_url("/v1/tactile/analyze?pretared=true&finger=th"))
            .header("content-type", "text/csv")
            .body(recording_text())
            .send()
            .await
            .unwrap();
        assert_eq!(response.status(), 200);
        let analyzed: serde_json::Value = response.json().await.unwrap();

        let mut ws = connect(&server).await;
        send(&mut ws, serde_json::json!({"session": session_json()})).await;
        for (i, f) in frames.iter().enumerate() {
            send(&mut ws, frame_json(f)).await;
            let mut answer = next_json(&mut ws).await;
            assert_eq!(answer["frame_index"], i, "{answer}");
            answer.as_object_mut().unwrap().remove("frame_index");
            assert_eq!(answer, analyzed["frames"][i], "frame {i}");
        }
        ws.close(None).await.unwrap();
    }

    #[tokio::test]
    async fn websocket_errors_name_the_field_and_close() {
        let server = Server::start_with(&["--max-tactile-sessions", "1"]);
        let frames = recording_frames();
        let mut ws = connect(&server).await;
        send(&mut ws, serde_json::json!({"session": session_json()})).await;
        send(&mut ws, frame_json(&frames[1])).await;
        assert_eq!(next_json(&mut ws).await["frame_index"], 0);

        // A second session while the first is open: refused (limit 1).
        let mut other = connect(&server).await;
        send(&mut other, serde_json::json!({"session": session_json()})).await;
        let e = next_json(&mut other).await;
        assert_eq!(e["error"]["code"], "resource_exhausted", "{e}");

        // Out of order ends the first socket with the field named.
        send(&mut ws, frame_json(&frames[0])).await;
        let e = next_json(&mut ws).await;
        assert_eq!(e["error"]["field"], "frame.timestamp", "{e}");
        assert_eq!(e["error"]["code"], "invalid_argument");
        match ws.next().await {
            Some(Ok(Message::Close(Some(c)))) => assert_eq!(u16::from(c.code), 1008),
            other => panic!("expected a close frame, got {other:?}"),
        }
        drop(ws);

        // Its slot is free again: a new socket gets a session; a frame first is an error.
        let started = Instant::now();
        loop {
            let mut ws = connect(&server).await;
            send(&mut ws, serde_json::json!({"session": session_json()})).await;
            send(&mut ws, frame_json(&frames[0])).await;
            let answer = next_json(&mut ws).await;
            if answer["frame_index"] == 0 {
                break;
            }
            assert_eq!(answer["error"]["code"], "resource_exhausted", "{answer}");
            assert!(started.elapsed() < Duration::from_secs(5), "slot not freed");
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
        let mut ws = connect(&server).await;
        send(&mut ws, frame_json(&frames[0])).await;
        let e = next_json(&mut ws).await;
        assert_eq!(e["error"]["field"], "session", "{e}");

        // A plain GET is told to use a WebSocket.
        let (status, code, _, _) = rest_error(
            http()
                .get(server.rest_url("/v1/stabilize"))
                .send()
                .await
                .unwrap(),
        )
        .await;
        assert!(status >= 400, "{status}");
        assert_eq!(code, "websocket_required");
    }
}

fn repo_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The ONNX Runtime library for the model tests: `$ORT_DYLIB_PATH` (set by `make test`) or the
/// one scripts/fetch-onnxruntime.sh writes.
fn onnxruntime() -> String {
    std::env::var("ORT_DYLIB_PATH")
        .ok()
        .filter(|p| !p.is_empty())
        .unwrap_or_else(|| {
            repo_root()
                .join(".tools/onnxruntime/libonnxruntime.so.1.31.1")
                .display()
                .to_string()
        })
}

#[tokio::test]
async fn the_lstm_model_reports_materials_while_in_contact() {
    let model = repo_root().join("models/tactile/tactile_detector.onnx");
    let lib = onnxruntime();
    let server = Server::start_with(&[
        "--tactile-model",
        model.to_str().unwrap(),
        "--onnxruntime",
        &lib,
    ]);
    let mut s = session();
    s.detector = Some(pb::TactileDetector {
        kind: Some(pb::tactile_detector::Kind::Model("lstm".into())),
    });
    let frames = recording_frames();
    let (tx, mut rx) = open(&server, s).await.expect("session opens");
    let sent = frames[..300].to_vec();
    let sender = tokio::spawn(async move {
        for f in &sent {
            tx.send(frame_message(f))
                .await
                .expect("the stream stays open");
        }
    });
    let (mut with_material, mut in_contact) = (0, 0);
    while let Some(m) = rx.message().await.expect("no stream error") {
        let f = &m.fingers[0];
        if f.event == pb::ContactEvent::NonContact as i32 {
            assert!(f.material_probabilities.is_empty());
            assert_eq!(f.material, pb::Material::Unknown as i32);
            continue;
        }
        in_contact += 1;
        if f.material_probabilities.len() == 4 {
            with_material += 1;
            let sum: f64 = f.material_probabilities.iter().sum();
            assert!((sum - 1.0).abs() < 1e-6, "{:?}", f.material_probabilities);
            assert_ne!(f.material, pb::Material::Unknown as i32);
        }
    }
    sender.await.unwrap();
    assert!(
        in_contact > 100,
        "{in_contact} frames in contact of 300 (the sensor is pressed)"
    );
    assert_eq!(
        with_material, in_contact,
        "every in-contact frame has material probabilities"
    );

    // The same session through REST analyze, with the detector left to the server's default
    // (the loaded model): material probabilities too.
    let response = http()
        .post(server.rest_url("/v1/tactile/analyze?pretared=true&finger=th&layout=biotac"))
        .header("content-type", "text/csv")
        .body(recording_text())
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let body: serde_json::Value = response.json().await.unwrap();
    let frames = body["frames"].as_array().unwrap();
    assert!(
        frames
            .iter()
            .any(|f| f["fingers"][0]["material_probabilities"].is_array()),
        "the default detector is the loaded model"
    );
}

#[tokio::test]
async fn asking_for_a_model_that_is_not_loaded_names_the_field() {
    let server = Server::start_with(&["--tactile-model", "none"]);
    let mut s = session();
    s.detector = Some(pb::TactileDetector {
        kind: Some(pb::tactile_detector::Kind::Model("lstm".into())),
    });
    let Err(e) = open(&server, s).await else {
        panic!("a session asking for an unloaded model was opened");
    };
    assert_eq!(e.code(), Code::InvalidArgument);
    assert!(
        e.message().contains("session.detector.model"),
        "{}",
        e.message()
    );
    assert!(
        e.message().contains("no tactile model is loaded"),
        "{}",
        e.message()
    );
    // Without a model the default is the model-free detector: no materials.
    let response = http()
        .post(server.rest_url("/v1/tactile/analyze?pretared=true&finger=th&layout=biotac"))
        .header("content-type", "text/csv")
        .body(recording_text())
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let body: serde_json::Value = response.json().await.unwrap();
    assert!(
        body["frames"]
            .as_array()
            .unwrap()
            .iter()
            .all(|f| f["fingers"][0]["material_probabilities"].is_null())
    );
}

#[test]
fn a_tactile_model_file_that_does_not_load_stops_the_start() {
    let bad = std::env::temp_dir().join(format!("graspd-bad-tactile-{}.onnx", std::process::id()));
    std::fs::write(&bad, b"not an onnx model").unwrap();
    let output = std::process::Command::new(graspd_e2e::binary("graspd", "GRASPD_BIN"))
        .args(["--grpc-addr", "127.0.0.1:0", "--rest-addr", "127.0.0.1:0"])
        .args(["--onnxruntime", &onnxruntime(), "--tactile-model"])
        .arg(&bad)
        .output()
        .unwrap();
    let _ = std::fs::remove_file(&bad);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(
        stderr.contains("cannot load the tactile model") && stderr.contains("graspd-bad-tactile"),
        "{stderr}"
    );
}
