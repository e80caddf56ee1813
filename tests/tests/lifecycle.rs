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
