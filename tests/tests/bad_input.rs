//! Untrusted input through both transports: every rejection has the right status, names the
//! offending field, and leaves the server serving (a valid request right after succeeds).

use graspd_core::cloud::io::write_ply_ascii;
use graspd_e2e::{
    Server, assert_valid_plan_works, base64, cylinder, grpc_request, grpc_request_with_points,
    http, json_request, packed, rest_error,
};
use graspd_proto::v1 as pb;
use serde_json::json;
use tonic::Code;

/// Sends a gRPC request, expects `code`, and checks that the message contains each of `needles`.
async fn expect_grpc(server: &Server, request: pb::PlanGraspRequest, code: Code, needles: &[&str]) {
    let e = server
        .grpc()
        .await
        .plan_grasp(request)
        .await
        .expect_err("the request must be refused");
    assert_eq!(e.code(), code, "{}", e.message());
    for n in needles {
        assert!(e.message().contains(n), "'{}' lacks '{n}'", e.message());
    }
}

/// Posts JSON, expects the HTTP status and the error's field, and checks the message.
async fn expect_rest(
    server: &Server,
    body: serde_json::Value,
    status: u16,
    field: &str,
    needles: &[&str],
) {
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&body)
        .send()
        .await
        .unwrap();
    check_rest(response, status, field, needles).await;
}

async fn check_rest(response: reqwest::Response, status: u16, field: &str, needles: &[&str]) {
    let (got, code, got_field, message) = rest_error(response).await;
    assert_eq!(got, status, "{code}: {got_field:?}: {message}");
    assert_eq!(got_field.as_deref(), Some(field), "{message}");
    for n in needles {
        assert!(message.contains(n), "'{message}' lacks '{n}'");
    }
}

fn with_points(mut body: serde_json::Value, points: serde_json::Value) -> serde_json::Value {
    body["cloud"]["points"] = points;
    body
}

#[tokio::test]
async fn empty_cloud() {
    let server = Server::start();
    expect_grpc(
        &server,
        grpc_request_with_points(Vec::new(), "shadow", 0),
        Code::InvalidArgument,
        &["cloud", "empty"],
    )
    .await;
    let body = with_points(json_request("shadow", 0), json!([]));
    expect_rest(&server, body, 400, "cloud", &["empty"]).await;
    assert_valid_plan_works(&server).await;
}

#[tokio::test]
async fn nan_and_infinite_coordinates() {
    let server = Server::start();
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut points = cylinder(100);
        points[7].y = bad;
        expect_grpc(
            &server,
            grpc_request_with_points(packed(&points), "shadow", 0),
            Code::InvalidArgument,
            &["cloud.points[7]", "NaN or infinite"],
        )
        .await;
        let body = with_points(json_request("shadow", 0), json!(base64(&packed(&points))));
        expect_rest(&server, body, 400, "cloud.points[7]", &["NaN or infinite"]).await;
    }
    // JSON has no NaN; an out-of-range number is malformed JSON.
    let body = r#"{"cloud":{"points":[[0,0,1e999]]},"hand_name":"shadow"}"#;
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .header("content-type", "application/json")
        .body(body)
        .send()
        .await
        .unwrap();
    let (status, code, field, _) = rest_error(response).await;
    assert_eq!((status, code.as_str()), (400, "invalid_argument"));
    assert!(field.unwrap().starts_with("cloud.points"));
    assert_valid_plan_works(&server).await;
}

#[tokio::test]
async fn too_few_points() {
    let server = Server::start();
    let points = cylinder(10);
    expect_grpc(
        &server,
        grpc_request_with_points(packed(&points), "shadow", 0),
        Code::InvalidArgument,
        &["cloud", "10 points", "at least 32"],
    )
    .await;
    let arrays: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
    let body = with_points(json_request("shadow", 0), json!(arrays));
    expect_rest(&server, body, 400, "cloud", &["at least 32"]).await;
    assert_valid_plan_works(&server).await;
}

#[tokio::test]
async fn byte_length_not_a_multiple_of_12() {
    let server = Server::start();
    expect_grpc(
        &server,
        grpc_request_with_points(vec![0; 13], "shadow", 0),
        Code::InvalidArgument,
        &["cloud.points: byte length 13 is not a multiple of 12"],
    )
    .await;
    let body = with_points(json_request("shadow", 0), json!(base64(&[0; 13])));
    expect_rest(
        &server,
        body,
        400,
        "cloud.points",
        &["byte length 13 is not a multiple of 12"],
    )
    .await;
    let mut request = grpc_request("shadow", 0);
    if let Some(pb::plan_grasp_request::Input::Cloud(c)) = &mut request.input {
        c.normals = vec![0; 25];
    }
    expect_grpc(
        &server,
        request,
        Code::InvalidArgument,
        &["cloud.normals: byte length 25"],
    )
    .await;
    assert_valid_plan_works(&server).await;
}

#[tokio::test]
async fn unknown_hand() {
    let server = Server::start();
    expect_grpc(
        &server,
        grpc_request("foo", 0),
        Code::InvalidArgument,
        &["hand_name: unknown hand 'foo' (known: barrett, parallel_gripper, shadow)"],
    )
    .await;
    expect_rest(
        &server,
        json_request("foo", 0),
        400,
        "hand_name",
        &["unknown hand 'foo' (known: barrett, parallel_gripper, shadow)"],
    )
    .await;
    let mut request = grpc_request("shadow", 0);
    request.hand = None;
    expect_grpc(&server, request, Code::InvalidArgument, &["hand_name"]).await;
    assert_valid_plan_works(&server).await;
}

#[tokio::test]
async fn grasp_type_the_hand_cannot_realise() {
    let server = Server::start();
    let mut request = grpc_request("parallel_gripper", 0);
    request.hints.as_mut().unwrap().grasp_type = pb::GraspType::Tripod as i32;
    expect_grpc(
        &server,
        request,
        Code::InvalidArgument,
        &["hints.grasp_type", "parallel_gripper", "tripod"],
    )
    .await;
    let mut body = json_request("parallel_gripper", 0);
    body["hints"]["grasp_type"] = json!("tripod");
    expect_rest(
        &server,
        body,
        400,
        "hints.grasp_type",
        &["cannot realise tripod"],
    )
    .await;
    let mut body = json_request("shadow", 0);
    body["hints"]["grasp_type"] = json!("grab");
    expect_rest(&server, body, 400, "hints.grasp_type", &["grab"]).await;
    assert_valid_plan_works(&server).await;
}

#[tokio::test]
async fn invalid_options_and_inline_hands_name_the_field() {
    let server = Server::start();
    let mut request = grpc_request("shadow", 0);
    request.options.as_mut().unwrap().epsilon = Some(f64::NAN);
    expect_grpc(
        &server,
        request,
        Code::InvalidArgument,
        &["options.epsilon"],
    )
    .await;
    let mut body = json_request("shadow", 0);
    body["options"]["max_iterations"] = json!(1_000_000_000u64);
    expect_rest(
        &server,
        body,
        400,
        "options.max_iterations",
        &["must be within"],
    )
    .await;

    let mut body = json_request("shadow", 0);
    body.as_object_mut().unwrap().remove("hand_name");
    body["hand_description"] =
        json!({"name": "x", "geometry": {}, "fingers": [], "grasp_types": []});
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&body)
        .send()
        .await
        .unwrap();
    let (status, _, field, message) = rest_error(response).await;
    assert_eq!(status, 400, "{message}");
    assert!(field.unwrap().starts_with("hand_description"), "{message}");
    assert_valid_plan_works(&server).await;
}

#[tokio::test]
async fn payload_over_the_configured_limit() {
    let server = Server::start_with(&["--max-message-bytes", "65536"]);
    let big = packed(&cylinder(10_000));
    expect_grpc(
        &server,
        grpc_request_with_points(big.clone(), "shadow", 0),
        Code::ResourceExhausted,
        &["request", "65536", "max_message_bytes"],
    )
    .await;
    let body = with_points(json_request("shadow", 0), json!(base64(&big)));
    expect_rest(&server, body, 413, "body", &["65536", "max_message_bytes"]).await;
    assert_valid_plan_works(&server).await;
}

#[tokio::test]
async fn cloud_over_the_configured_point_limit() {
    let server = Server::start_with(&["--max-points", "1000"]);
    expect_grpc(
        &server,
        grpc_request("shadow", 0),
        Code::ResourceExhausted,
        &["cloud.points", "2000 points", "max_points"],
    )
    .await;
    expect_rest(
        &server,
        json_request("shadow", 0),
        413,
        "cloud.points",
        &["max_points"],
    )
    .await;
    let response = server
        .grpc()
        .await
        .plan_grasp(grpc_request_with_points(
            packed(&cylinder(900)),
            "shadow",
            0,
        ))
        .await;
    assert!(response.is_ok(), "{response:?}");
}

#[tokio::test]
async fn malformed_cloud_files() {
    let server = Server::start();
    let good = write_ply_ascii(&cylinder(100), None);
    let truncated = good[..good.len() / 2].to_vec();
    let lying = String::from_utf8(good.clone())
        .unwrap()
        .replace("element vertex 100", "element vertex 100000000")
        .into_bytes();
    let pcd = b"VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 5\nHEIGHT 1\nPOINTS 5\nDATA binary\n\x00\x01".to_vec();
    for bytes in [truncated, lying, pcd, b"hello world".to_vec()] {
        let form = reqwest::multipart::Form::new()
            .part(
                "cloud",
                reqwest::multipart::Part::bytes(bytes).file_name("x.ply"),
            )
            .text("request", r#"{"hand_name":"shadow"}"#);
        let response = http()
            .post(server.rest_url("/v1/plan"))
            .multipart(form)
            .send()
            .await
            .unwrap();
        check_rest(response, 400, "cloud.file", &[]).await;
    }
    let form = reqwest::multipart::Form::new()
        .part("cloud", reqwest::multipart::Part::bytes(good.clone()))
        .text("request", r#"{"hand_name":"shadow","bogus":true}"#);
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .multipart(form)
        .send()
        .await
        .unwrap();
    check_rest(response, 400, "bogus", &["unknown field"]).await;
    let form = reqwest::multipart::Form::new()
        .part("points", reqwest::multipart::Part::bytes(good))
        .text("request", r#"{"hand_name":"shadow"}"#);
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .multipart(form)
        .send()
        .await
        .unwrap();
    check_rest(response, 400, "multipart", &["unknown part 'points'"]).await;
    assert_valid_plan_works(&server).await;
}

#[tokio::test]
async fn unknown_and_malformed_json() {
    let server = Server::start();
    let mut body = json_request("shadow", 0);
    body["colud"] = json!(1);
    expect_rest(&server, body, 400, "colud", &["unknown field `colud`"]).await;
    let mut body = json_request("shadow", 0);
    body["options"]["epsilonn"] = json!(0.5);
    expect_rest(&server, body, 400, "options.epsilonn", &["unknown field"]).await;
    let mut body = json_request("shadow", 0);
    body["hints"]["attention_point"] = json!({"x": 0, "y": 0, "w": 1});
    expect_rest(
        &server,
        body,
        400,
        "hints.attention_point.w",
        &["unknown field"],
    )
    .await;

    for (content_type, body, status, field) in [
        ("application/json", "{\"hand_name\": ", 400, "body"),
        ("application/json", "[1, 2]", 400, "body"),
        ("text/plain", "{}", 415, ""),
    ] {
        let response = http()
            .post(server.rest_url("/v1/plan"))
            .header("content-type", content_type)
            .body(body)
            .send()
            .await
            .unwrap();
        let (got, _, got_field, message) = rest_error(response).await;
        assert_eq!(got, status, "{message}");
        if !field.is_empty() {
            assert_eq!(got_field.as_deref(), Some(field), "{message}");
        }
    }
    assert_valid_plan_works(&server).await;
}

/// Every POST route reads its body the same way (`rest/body.rs`): an unsupported content type
/// is 415 `unsupported_media_type`, a multipart part given twice is 400 naming the part, an
/// unknown part 400 on `multipart` — and the server goes on answering.
#[tokio::test]
async fn every_post_route_reads_its_body_alike() {
    let server = Server::start();
    let post = |route: &str| http().post(server.rest_url(route));
    // Per route: a part that may come once, with a value the route accepts the first time.
    for (route, (once, value)) in [
        ("/v1/plan", ("request", r#"{"hand_name":"shadow"}"#)),
        ("/v1/hands", ("model", "<mujoco/>")),
        ("/v1/tactile/analyze", ("session", r#"{"fingers":[]}"#)),
    ] {
        let response = post(route)
            .header("content-type", "text/plain")
            .body("{}")
            .send()
            .await
            .unwrap();
        let (status, code, _, message) = rest_error(response).await;
        assert_eq!(
            (status, code.as_str()),
            (415, "unsupported_media_type"),
            "{route}: {message}"
        );
        for (form, field, needle) in [
            (
                reqwest::multipart::Form::new()
                    .text(once, value)
                    .text(once, value),
                once,
                format!("the part '{once}' is given twice"),
            ),
            (
                reqwest::multipart::Form::new().text("bogus", "x"),
                "multipart",
                "unknown part 'bogus'".to_string(),
            ),
        ] {
            let response = post(route).multipart(form).send().await.unwrap();
            check_rest(response, 400, field, &[&needle]).await;
        }
    }
    assert_valid_plan_works(&server).await;
}

/// An option's range has one home (`PlannerOptions::validate`): μ = 7 is refused alike by both
/// transports, naming the option, with the same message; one within the range is accepted.
#[tokio::test]
async fn an_option_is_judged_alike_on_both_transports() {
    let server = Server::start();
    let message = "must be within [0.01, 5], got 7";
    let mut request = grpc_request("shadow", 0);
    request.options.as_mut().unwrap().friction = Some(7.0);
    expect_grpc(
        &server,
        request,
        Code::InvalidArgument,
        &["options.friction", message],
    )
    .await;
    let mut body = json_request("shadow", 0);
    body["options"]["friction"] = json!(7.0);
    expect_rest(&server, body, 400, "options.friction", &[message]).await;
    let mut body = json_request("shadow", 0);
    body["options"]["friction"] = json!(4.5);
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&body)
        .send()
        .await
        .unwrap();
    assert_eq!(response.status().as_u16(), 200);
}
