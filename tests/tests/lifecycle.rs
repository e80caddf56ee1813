//! Process behaviour: graceful shutdown on SIGTERM and Ctrl-C, gRPC health, and configuration from a file.

use graspd_e2e::{Server, binary, http};
use std::process::Command;

#[tokio::test]
async fn sigterm_and_ctrl_c_stop_the_server_cleanly() {
    for signal in ["TERM", "INT"] {
        let server = Server::start();
        let response = http()
            .get(server.rest_url("/healthz"))
            .send()
            .await
            .unwrap();
        assert_eq!(response.status(), 200);
        let status = server.signal(signal);
        assert!(status.success(), "SIG{signal}: {status:?}");
    }
}

#[tokio::test]
async fn grpc_health_reports_serving() {
    use tonic_health::pb::health_check_response::ServingStatus;
    use tonic_health::pb::{HealthCheckRequest, health_client::HealthClient};
    let server = Server::start();
    let channel = tonic::transport::Channel::from_shared(server.grpc_url())
        .unwrap()
        .connect()
        .await
        .unwrap();
    let mut health = HealthClient::new(channel);
    for service in ["", "graspd.v1.GraspPlanner"] {
        let response = health
            .check(HealthCheckRequest {
                service: service.into(),
            })
            .await
            .unwrap()
            .into_inner();
        assert_eq!(response.status(), ServingStatus::Serving, "'{service}'");
    }
}

#[test]
fn flags_override_environment_override_the_config_file() {
    let dir = std::env::temp_dir().join(format!("graspd-e2e-config-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("graspd.toml");
    std::fs::write(
        &path,
        "max_points = 1000\nmax_message_bytes = 4096\nrest_addr = \"127.0.0.1:9999\"\n",
    )
    .unwrap();
    let out = Command::new(binary("graspd", "GRASPD_BIN"))
        .env("GRASPD_CONFIG", &path)
        .env("GRASPD_MAX_POINTS", "2000")
        .env_remove("GRASPD_REST_ADDR")
        .env_remove("GRASPD_GRPC_ADDR")
        .env_remove("GRASPD_MAX_MESSAGE_BYTES")
        .args(["--max-message-bytes", "1MiB", "--print-config"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let config = String::from_utf8_lossy(&out.stdout);
    assert!(config.contains("max_points = 2000"), "{config}");
    assert!(config.contains("max_message_bytes = 1048576"), "{config}");
    assert!(
        config.contains("rest_addr = \"127.0.0.1:9999\""),
        "{config}"
    );
    assert!(config.contains("grpc_addr = \"0.0.0.0:50051\""), "{config}");
    std::fs::remove_dir_all(&dir).ok();
}

/// SIGTERM while a plan is computing: the server stops taking connections, answers the plan in
/// flight, then exits 0.
#[tokio::test]
async fn sigterm_drains_a_plan_in_flight() {
    let server = Server::start();
    // A 200,000-point cloud plans for seconds (debug build).
    let body = serde_json::json!({
        "cloud": {"points": graspd_e2e::base64(&graspd_e2e::packed(&graspd_e2e::cylinder(200_000)))},
        "hand_name": "shadow",
        "options": {"seed": 1},
        "hints": {"support_plane": {"normal": [0.0, 0.0, 1.0], "offset": 0.0}},
    });
    let url = server.rest_url("/v1/plan");
    let in_flight = tokio::spawn(async move { http().post(url).json(&body).send().await });
    // Let the request reach the planner.
    tokio::time::sleep(std::time::Duration::from_millis(300)).await;
    assert!(
        !in_flight.is_finished(),
        "the plan finished before the signal: use a larger cloud"
    );
    let t = std::time::Instant::now();
    let rest = server.rest_url("/healthz");
    let exit = tokio::task::spawn_blocking(move || server.signal("TERM"));
    let response = in_flight
        .await
        .unwrap()
        .expect("the plan in flight is answered");
    assert_eq!(response.status(), 200);
    eprintln!("answered {:.2} s after SIGTERM", t.elapsed().as_secs_f64());
    let plan: serde_json::Value = response.json().await.unwrap();
    assert!(plan["contacts"].as_array().is_some_and(|c| !c.is_empty()));
    let status = exit.await.unwrap();
    assert!(status.success(), "{status:?}");
    // After the drain nothing listens.
    assert!(http().get(rest).send().await.is_err());
}

/// `--drain-delay-ms`: after SIGTERM the server keeps serving for the delay with `/readyz` at
/// 503 "draining" on new connections (so a load balancer takes it out), then exits 0.
#[tokio::test]
async fn a_drain_delay_keeps_serving_while_not_ready() {
    let server = Server::start_with(&["--drain-delay-ms", "1500"]);
    let ready = server.rest_url("/readyz");
    let plan_url = server.rest_url("/v1/plan");
    let pid = server.pid();
    let t = std::time::Instant::now();
    let exit = tokio::task::spawn_blocking(move || server.signal("TERM"));
    tokio::time::sleep(std::time::Duration::from_millis(300)).await;
    // A fresh client: a new connection.
    let response = graspd_e2e::http().get(&ready).send().await.unwrap();
    assert_eq!(response.status(), 503);
    let body: serde_json::Value = response.json().await.unwrap();
    assert_eq!(body["status"], "draining");
    let plan = http()
        .post(&plan_url)
        .json(&graspd_e2e::json_request("parallel_gripper", 1))
        .send()
        .await
        .unwrap();
    assert_eq!(plan.status(), 200, "still planning during the delay");
    let status = exit.await.unwrap();
    assert!(status.success(), "{status:?}");
    assert!(
        t.elapsed() >= std::time::Duration::from_millis(1500),
        "exited {:?} after the signal, before the delay (pid {pid})",
        t.elapsed()
    );
}
