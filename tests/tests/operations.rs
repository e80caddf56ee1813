//! Operating the real server (issue 8): Prometheus metrics count requests, errors and plan
//! stages on both transports; request ids come back and name the request's log lines;
//! readiness; bearer-token authentication on both transports with the probes left open.

use graspd_e2e::{
    Server, binary, grpc_request, http, json_request, metric, rest_error, rgbd_frame_proto,
};
use graspd_proto::v1 as pb;
use graspd_testkit::Object;
use graspd_testkit::rgbd::{RgbdScene, SceneObject};
use std::process::Command;
use std::time::Duration;
use tonic::Code;
use tonic::metadata::MetadataValue;

const PLAN: &str = "/graspd.v1.GraspPlanner/PlanGrasp";

/// An RGB-D request (one can on the table, the most salient object) for the perception stages.
fn rgbd_request() -> pb::PlanGraspRequest {
    let r = RgbdScene::on_table(vec![SceneObject::new(
        Object::TomatoSoupCan,
        0.0,
        0.0,
        [200, 40, 30],
    )])
    .render()
    .unwrap();
    pb::PlanGraspRequest {
        input: Some(pb::plan_grasp_request::Input::Rgbd(rgbd_frame_proto(
            &r, false,
        ))),
        hand: Some(pb::plan_grasp_request::Hand::HandName(
            "parallel_gripper".into(),
        )),
        options: Some(pb::PlannerOptions {
            seed: Some(5),
            ..Default::default()
        }),
        hints: None,
        output: None,
        extra_views: Vec::new(),
    }
}

#[tokio::test]
async fn metrics_count_plans_errors_and_stages_on_both_transports() {
    let server = Server::start();
    let before = server.metrics().await;
    assert_eq!(
        metric(&before, "graspd_requests_total", &[("route", PLAN)]),
        None,
        "{before}"
    );

    let mut grpc = server.grpc().await;
    grpc.plan_grasp(grpc_request("shadow", 1)).await.unwrap();
    grpc.plan_grasp(rgbd_request()).await.unwrap();
    let mut bad = grpc_request("shadow", 1);
    bad.hand = Some(pb::plan_grasp_request::Hand::HandName(
        "no_such_hand".into(),
    ));
    assert_eq!(
        grpc.plan_grasp(bad).await.unwrap_err().code(),
        Code::InvalidArgument
    );
    let unknown = pb::GetHandRequest {
        name: "no_such_hand".into(),
    };
    assert_eq!(
        grpc.get_hand(unknown).await.unwrap_err().code(),
        Code::NotFound
    );
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&json_request("shadow", 1))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&serde_json::json!({"cloud": {"points": "AAA"}, "hand_name": "shadow"}))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 400);

    let response = http()
        .get(server.rest_url("/metrics"))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let content_type = response.headers()["content-type"]
        .to_str()
        .unwrap()
        .to_owned();
    assert!(
        content_type.starts_with("application/openmetrics-text"),
        "{content_type}"
    );
    let text = response.text().await.unwrap();
    let m = |name: &str, labels: &[(&str, &str)]| metric(&text, name, labels);
    let grpc_plan = [("transport", "grpc"), ("route", PLAN)];
    let rest_plan = [("transport", "rest"), ("route", "POST /v1/plan")];
    assert_eq!(
        m(
            "graspd_requests_total",
            &[grpc_plan[0], grpc_plan[1], ("code", "OK")]
        ),
        Some(2.0),
        "{text}"
    );
    assert_eq!(
        m(
            "graspd_requests_total",
            &[rest_plan[0], rest_plan[1], ("code", "200")]
        ),
        Some(1.0)
    );
    // Errors by code: gRPC code names, HTTP statuses.
    assert_eq!(
        m(
            "graspd_request_errors_total",
            &[grpc_plan[0], grpc_plan[1], ("code", "INVALID_ARGUMENT")]
        ),
        Some(1.0)
    );
    assert_eq!(
        m(
            "graspd_request_errors_total",
            &[
                ("route", "/graspd.v1.GraspPlanner/GetHand"),
                ("code", "NOT_FOUND")
            ]
        ),
        Some(1.0)
    );
    assert_eq!(
        m(
            "graspd_request_errors_total",
            &[rest_plan[0], rest_plan[1], ("code", "400")]
        ),
        Some(1.0)
    );
    assert_eq!(
        m("graspd_request_errors_total", &[("code", "OK")]),
        None,
        "{text}"
    );
    // Latency histograms with their buckets.
    assert_eq!(
        m("graspd_request_duration_seconds_count", &grpc_plan),
        Some(3.0)
    );
    assert_eq!(
        m(
            "graspd_request_duration_seconds_bucket",
            &[grpc_plan[0], grpc_plan[1], ("le", "+Inf")]
        ),
        Some(3.0)
    );
    assert!(
        text.lines()
            .filter(|l| l.starts_with("graspd_request_duration_seconds_bucket{")
                && l.contains("route=\"POST /v1/plan\""))
            .count()
            > 10,
        "{text}"
    );
    // The planner's stages: three plans (two clouds, one frame); perception for the frame.
    for stage in [
        "preprocess",
        "normals",
        "grasp_type",
        "stage1",
        "stage2",
        "finalize",
        "total",
    ] {
        assert_eq!(
            m(
                "graspd_plan_stage_duration_seconds_count",
                &[("stage", stage)]
            ),
            Some(3.0),
            "{stage}"
        );
        assert_eq!(
            m(
                "graspd_plan_stage_duration_seconds_bucket",
                &[("stage", stage), ("le", "+Inf")]
            ),
            Some(3.0),
            "{stage}"
        );
    }
    for stage in [
        "decode",
        "saliency",
        "segmentation",
        "roi",
        "grasp_type",
        "total",
    ] {
        assert_eq!(
            m(
                "graspd_perception_stage_duration_seconds_count",
                &[("stage", stage)]
            ),
            Some(1.0),
            "{stage}"
        );
    }
    assert!(
        m(
            "graspd_plan_stage_duration_seconds_sum",
            &[("stage", "total")]
        )
        .unwrap()
            > 0.0
    );
    let plans = |transport, outcome| {
        m(
            "graspd_plans_total",
            &[("transport", transport), ("outcome", outcome)],
        )
        .unwrap_or(0.0)
    };
    let feasible = |transport| plans(transport, "feasible") + plans(transport, "infeasible");
    assert_eq!((feasible("grpc"), feasible("rest")), (2.0, 1.0), "{text}");
    assert_eq!(plans("grpc", "rejected"), 1.0, "{text}");
    // This scrape is the one REST request in flight; nothing waits or plans now.
    assert_eq!(
        m("graspd_requests_in_flight", &[("transport", "rest")]),
        Some(1.0)
    );
    assert_eq!(
        m("graspd_requests_in_flight", &[("transport", "grpc")]),
        Some(0.0)
    );
    assert_eq!(m("graspd_plans_running", &[]), Some(0.0));
    assert_eq!(m("graspd_plans_queued", &[]), Some(0.0));
    assert_eq!(m("graspd_tactile_sessions_active", &[]), Some(0.0));
    assert_eq!(m("graspd_ready", &[]), Some(1.0));
    assert_eq!(
        m("graspd_shed_requests_total", &[("transport", "grpc")]),
        Some(0.0)
    );
    assert_eq!(
        m(
            "graspd_unauthenticated_requests_total",
            &[("transport", "rest")]
        ),
        Some(0.0)
    );
    assert!(text.trim_end().ends_with("# EOF"));
}

fn grpc_id(id: &str) -> tonic::Request<pb::PlanGraspRequest> {
    let mut request = tonic::Request::new(grpc_request("shadow", 1));
    request
        .metadata_mut()
        .insert("x-request-id", MetadataValue::try_from(id).unwrap());
    request
}

fn is_generated(id: &str) -> bool {
    id.len() == 36 && id.chars().all(|c| c.is_ascii_hexdigit() || c == '-')
}

#[tokio::test]
async fn request_ids_come_back_on_both_transports_and_name_the_log_lines() {
    let server = Server::start_with_logs(&["--log", "info", "--log-format", "json"]);
    let long = "x".repeat(129);
    let mut grpc = server.grpc().await;

    let response = grpc.plan_grasp(grpc_id("robot-7/plan:42")).await.unwrap();
    assert_eq!(
        response.metadata().get("x-request-id").unwrap(),
        "robot-7/plan:42"
    );
    let response = grpc.plan_grasp(grpc_request("shadow", 1)).await.unwrap();
    let generated = response
        .metadata()
        .get("x-request-id")
        .unwrap()
        .to_str()
        .unwrap();
    assert!(is_generated(generated), "{generated}");
    let response = grpc.plan_grasp(grpc_id(&long)).await.unwrap();
    let replaced = response
        .metadata()
        .get("x-request-id")
        .unwrap()
        .to_str()
        .unwrap();
    assert!(is_generated(replaced), "{replaced}");
    // Error answers carry it too.
    let mut bad = grpc_id("bad-one");
    bad.get_mut().hand = Some(pb::plan_grasp_request::Hand::HandName("nope".into()));
    let status = grpc.plan_grasp(bad).await.unwrap_err();
    assert_eq!(status.metadata().get("x-request-id").unwrap(), "bad-one");

    let rest = |id: Option<&str>| {
        let mut request = http()
            .post(server.rest_url("/v1/plan"))
            .json(&json_request("shadow", 1));
        if let Some(id) = id {
            request = request.header("x-request-id", id);
        }
        request.send()
    };
    let response = rest(Some("rest-id-1")).await.unwrap();
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["x-request-id"], "rest-id-1");
    let response = rest(None).await.unwrap();
    assert!(is_generated(
        response.headers()["x-request-id"].to_str().unwrap()
    ));
    let response = rest(Some(&long)).await.unwrap();
    let replaced_rest = response.headers()["x-request-id"]
        .to_str()
        .unwrap()
        .to_owned();
    assert!(is_generated(&replaced_rest), "{replaced_rest}");
    let response = http()
        .get(server.rest_url("/no/such/route"))
        .header("x-request-id", "lost-1")
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 404);
    assert_eq!(response.headers()["x-request-id"], "lost-1");

    // The "planned" lines carry their request's id in the span.
    let planned_with = |id: &str| {
        server.logs().iter().any(|line| {
            let Ok(v) = serde_json::from_str::<serde_json::Value>(line) else {
                return false;
            };
            v["fields"]["message"] == "planned" && v["span"]["request_id"] == id
        })
    };
    // The log line of the last plan may follow its answer: wait for every one of them.
    let ids = ["robot-7/plan:42", "rest-id-1", &replaced_rest];
    for _ in 0..100 {
        if ids.iter().all(|id| planned_with(id)) {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    for id in ids {
        assert!(
            planned_with(id),
            "no 'planned' line with request_id {id}:\n{:#?}",
            server.logs()
        );
    }
    assert!(!server.logs().iter().any(|l| l.contains(&long)));
}

#[tokio::test]
async fn readiness_and_liveness_answer_once_started() {
    let server = Server::start();
    for (path, status) in [("/readyz", "ready"), ("/healthz", "ok")] {
        let response = http().get(server.rest_url(path)).send().await.unwrap();
        assert_eq!(response.status(), 200, "{path}");
        let body: serde_json::Value = response.json().await.unwrap();
        assert_eq!(body["status"], status, "{path}");
    }
}

async fn grpc_health(server: &Server) -> Result<i32, tonic::Status> {
    use tonic_health::pb::{HealthCheckRequest, health_client::HealthClient};
    let channel = tonic::transport::Channel::from_shared(server.grpc_url())
        .unwrap()
        .connect()
        .await
        .unwrap();
    HealthClient::new(channel)
        .check(HealthCheckRequest {
            service: "graspd.v1.GraspPlanner".into(),
        })
        .await
        .map(|r| r.into_inner().status)
}

fn bearer<T>(mut request: tonic::Request<T>, token: &str) -> tonic::Request<T> {
    request.metadata_mut().insert(
        "authorization",
        MetadataValue::try_from(format!("Bearer {token}")).unwrap(),
    );
    request
}

#[tokio::test]
async fn bearer_tokens_guard_both_transports_and_leave_the_probes_open() {
    let dir = std::env::temp_dir().join(format!("graspd-e2e-auth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("tokens");
    std::fs::write(&file, "# the fleet's token\nfleet-token-2\n").unwrap();
    let server = Server::start_with(&[
        "--auth-token",
        "flag-token-1",
        "--auth-tokens-file",
        file.to_str().unwrap(),
    ]);

    // gRPC: none and wrong refused, both configured tokens accepted.
    let mut grpc = server.grpc().await;
    let status = grpc
        .plan_grasp(grpc_request("shadow", 1))
        .await
        .unwrap_err();
    assert_eq!(status.code(), Code::Unauthenticated, "{status:?}");
    assert!(status.metadata().get("x-request-id").is_some());
    let status = grpc
        .list_hands(bearer(
            tonic::Request::new(pb::ListHandsRequest {}),
            "flag-token-",
        ))
        .await
        .unwrap_err();
    assert_eq!(status.code(), Code::Unauthenticated);
    for token in ["flag-token-1", "fleet-token-2"] {
        grpc.plan_grasp(bearer(
            tonic::Request::new(grpc_request("shadow", 1)),
            token,
        ))
        .await
        .unwrap_or_else(|e| panic!("{token}: {e:?}"));
    }
    // The probes stay open.
    assert_eq!(grpc_health(&server).await.unwrap(), 1, "SERVING");

    // REST: 401 with WWW-Authenticate and the JSON error; the right token plans.
    for auth in [None, Some("Bearer wrong"), Some("Basic flag-token-1")] {
        let mut request = http()
            .post(server.rest_url("/v1/plan"))
            .json(&json_request("shadow", 1));
        if let Some(a) = auth {
            request = request.header("authorization", a);
        }
        let response = request.send().await.unwrap();
        assert_eq!(response.headers()["www-authenticate"], "Bearer", "{auth:?}");
        let (status, code, _, message) = rest_error(response).await;
        assert_eq!(
            (status, code.as_str()),
            (401, "unauthenticated"),
            "{auth:?}"
        );
        assert!(!message.contains("flag-token"), "{message}");
    }
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .bearer_auth("flag-token-1")
        .json(&json_request("shadow", 1))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let response = http()
        .get(server.rest_url("/v1/hands"))
        .bearer_auth("fleet-token-2")
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    for path in ["/healthz", "/readyz", "/metrics", "/openapi.json"] {
        let response = http().get(server.rest_url(path)).send().await.unwrap();
        assert_eq!(response.status(), 200, "{path} without a token");
    }
    let text = server.metrics().await;
    assert_eq!(
        metric(
            &text,
            "graspd_unauthenticated_requests_total",
            &[("transport", "grpc")]
        ),
        Some(2.0),
        "{text}"
    );
    assert_eq!(
        metric(
            &text,
            "graspd_unauthenticated_requests_total",
            &[("transport", "rest")]
        ),
        Some(3.0)
    );
    assert_eq!(
        metric(
            &text,
            "graspd_request_errors_total",
            &[("code", "UNAUTHENTICATED")]
        ),
        Some(2.0)
    );
    assert_eq!(
        metric(&text, "graspd_request_errors_total", &[("code", "401")]),
        Some(3.0)
    );
    drop(server);

    // The configuration shows how many tokens, never which.
    let out = Command::new(binary("graspd", "GRASPD_BIN"))
        .env("GRASPD_AUTH_TOKENS", "env-token-a,env-token-b")
        .env_remove("GRASPD_CONFIG")
        .env_remove("GRASPD_AUTH_TOKENS_FILE")
        .args([
            "--auth-tokens-file",
            file.to_str().unwrap(),
            "--print-config",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let config = String::from_utf8_lossy(&out.stdout);
    assert!(config.contains("# auth_tokens: 3 configured"), "{config}");
    assert!(
        !config.contains("env-token") && !config.contains("fleet-token"),
        "{config}"
    );
    let help = Command::new(binary("graspd", "GRASPD_BIN"))
        .env("GRASPD_AUTH_TOKENS", "env-token-a")
        .arg("--help")
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("--auth-token") && !help.contains("env-token-a"),
        "{help}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_bad_token_configuration_stops_the_start() {
    let out = Command::new(binary("graspd", "GRASPD_BIN"))
        .env_remove("GRASPD_CONFIG")
        .env_remove("GRASPD_AUTH_TOKENS_FILE")
        .env_remove("GRASPD_AUTH_TOKENS")
        .args(["--auth-token", "has space", "--print-config"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("auth_tokens") && !err.contains("has space"),
        "{err}"
    );
}

#[tokio::test]
async fn open_tactile_sessions_show_in_the_metrics() {
    use futures_util::SinkExt;
    use tokio_tungstenite::tungstenite::Message;
    let server = Server::start();
    let url = format!("ws://{}/v1/stabilize", server.rest_addr);
    let (mut ws, _) = tokio_tungstenite::connect_async(url).await.unwrap();
    let session = serde_json::json!({"session": {"fingers": [
        {"name": "th", "layout": "biotac", "tare": {"pretared": true}}
    ]}});
    ws.send(Message::text(session.to_string())).await.unwrap();
    let sessions = async || {
        metric(
            &server.metrics().await,
            "graspd_tactile_sessions_active",
            &[],
        )
        .unwrap()
    };
    let mut open = 0.0;
    for _ in 0..100 {
        open = sessions().await;
        if open == 1.0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    assert_eq!(open, 1.0);
    ws.close(None).await.unwrap();
    drop(ws);
    for _ in 0..100 {
        open = sessions().await;
        if open == 0.0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    assert_eq!(open, 0.0);
}
