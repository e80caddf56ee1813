//! `options.mode = learned_quality` (issue 18, dissertation ch. 3) on the real binary: the
//! Robotiq 2F-85 imported from its MJCF plans a soup can's single-view cloud with the built-in
//! grasp-quality network — straight down, the network's P(success), the Gaussian process's
//! posterior and the calls the Bayesian search made in the response — the same over gRPC and
//! REST; a hand without a two-jaw pinch, and a server without the network, are refused naming
//! `options.mode`, and the next request still works. A grasp the caller gives
//! (`hints.parallel_grasp`) is realised as given.

use graspd::grpc::status::FIELD_METADATA_KEY;
use graspd_e2e::{Server, http, packed, rest_error};
use graspd_proto::v1 as pb;
use graspd_testkit::view::standard_view;
use graspd_testkit::ycb::Object;
use tonic::Code;

fn v3(x: f64, y: f64, z: f64) -> pb::Vec3 {
    pb::Vec3 { x, y, z }
}

fn import_gripper() -> Vec<String> {
    let file = graspd_testkit::testdata_dir().join("hands/robotiq_2f85/2f85.xml");
    vec![
        "--import-hand".to_string(),
        format!("robotiq_2f85={}", file.display()),
    ]
}

fn request(hand: &str) -> pb::PlanGraspRequest {
    let view = standard_view(Object::TomatoSoupCan, 2000, 2);
    let (vp, pl) = (view.viewpoint, view.support_plane);
    pb::PlanGraspRequest {
        input: Some(pb::plan_grasp_request::Input::Cloud(pb::PointCloud {
            points: packed(&view.object_cloud().points),
            normals: Vec::new(),
            frame_id: "world".into(),
        })),
        hand: Some(pb::plan_grasp_request::Hand::HandName(hand.into())),
        options: Some(pb::PlannerOptions {
            seed: Some(3),
            mode: Some(pb::PlannerMode::LearnedQuality as i32),
            ..Default::default()
        }),
        hints: Some(pb::PlanHints {
            support_plane: Some(pb::Plane {
                normal: Some(v3(pl.normal.x, pl.normal.y, pl.normal.z)),
                offset: pl.offset,
            }),
            viewpoint: Some(v3(vp.x, vp.y, vp.z)),
            ..Default::default()
        }),
        output: None,
        extra_views: Vec::new(),
    }
}

fn rest_body(hand: &str) -> serde_json::Value {
    let view = standard_view(Object::TomatoSoupCan, 2000, 2);
    let (vp, pl) = (view.viewpoint, view.support_plane);
    let points: Vec<[f64; 3]> = view
        .object_cloud()
        .points
        .iter()
        .map(|p| [p.x, p.y, p.z])
        .collect();
    serde_json::json!({
        "hand_name": hand,
        "cloud": {"points": points},
        "options": {"seed": 3, "mode": "learned_quality"},
        "hints": {
            "support_plane": {"normal": [pl.normal.x, pl.normal.y, pl.normal.z], "offset": pl.offset},
            "viewpoint": [vp.x, vp.y, vp.z]
        }
    })
}

#[tokio::test]
async fn the_gripper_plans_with_the_learned_quality_over_grpc_and_rest() {
    let flags = import_gripper();
    let flags: Vec<&str> = flags.iter().map(String::as_str).collect();
    let server = Server::start_with(&flags);
    let mut grpc = server.grpc().await;
    let plan = grpc
        .plan_grasp(request("robotiq_2f85"))
        .await
        .unwrap()
        .into_inner();
    let lq = plan
        .learned_quality
        .expect("learned_quality in the response");
    assert!((0.0..=1.0).contains(&lq.probability), "{lq:?}");
    assert!(lq.posterior_std >= 0.0 && lq.posterior_std < 0.5, "{lq:?}");
    assert!(lq.network_calls >= 1 && lq.network_calls <= 60, "{lq:?}");
    assert!(lq.candidates >= lq.network_calls, "{lq:?}");
    assert_eq!(plan.mode, pb::PlannerMode::LearnedQuality as i32);
    let a = plan.approach.expect("approach");
    assert!(a.z < -0.98, "not down: {a:?}");
    assert!(!plan.joints.is_empty() && !plan.squeeze_joints.is_empty());
    // REST: the same plan, with the same search result.
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&rest_body("robotiq_2f85"))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let body: serde_json::Value = response.json().await.unwrap();
    let rest = &body["learned_quality"];
    assert_eq!(rest["network_calls"], lq.network_calls);
    assert!((rest["probability"].as_f64().unwrap() - lq.probability).abs() < 1e-9);
    // A hand with no two-jaw pinch is refused, naming the option; the next request works.
    let status = grpc.plan_grasp(request("shadow")).await.unwrap_err();
    assert_eq!(status.code(), Code::InvalidArgument, "{status:?}");
    assert_eq!(
        status.metadata().get(FIELD_METADATA_KEY).unwrap(),
        "options.mode"
    );
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&rest_body("shadow"))
        .send()
        .await
        .unwrap();
    let (code, _, field, message) = rest_error(response).await;
    assert_eq!(
        (code, field.as_deref()),
        (400, Some("options.mode")),
        "{message}"
    );
    grpc.plan_grasp(request("robotiq_2f85")).await.unwrap();
}

#[tokio::test]
async fn without_the_network_the_mode_is_refused() {
    let mut flags = import_gripper();
    flags.extend(["--grasp-quality-model".to_string(), "none".to_string()]);
    let flags: Vec<&str> = flags.iter().map(String::as_str).collect();
    let server = Server::start_with(&flags);
    let status = server
        .grpc()
        .await
        .plan_grasp(request("robotiq_2f85"))
        .await
        .unwrap_err();
    assert_eq!(status.code(), Code::InvalidArgument);
    assert_eq!(
        status.metadata().get(FIELD_METADATA_KEY).unwrap(),
        "options.mode"
    );
    assert!(status.message().contains("network"), "{}", status.message());
}

/// `hints.parallel_grasp`: the caller's grasp g straight down, realised with the gripper's
/// kinematics over gRPC — the jaws meet the can on each side of the given centre; over REST a
/// vertical jaw line is refused naming `hints.parallel_grasp.axis`.
#[tokio::test]
async fn a_given_parallel_grasp_is_realised_over_grpc_and_refused_when_vertical_over_rest() {
    let flags = import_gripper();
    let flags: Vec<&str> = flags.iter().map(String::as_str).collect();
    let server = Server::start_with(&flags);
    let view = standard_view(Object::TomatoSoupCan, 2000, 2);
    let top = view
        .object_cloud()
        .points
        .iter()
        .map(|p| p.z)
        .fold(f64::MIN, f64::max);
    let c = view.object_center;
    let mut req = request("robotiq_2f85");
    req.options = Some(pb::PlannerOptions {
        seed: Some(3),
        ..Default::default()
    });
    if let Some(h) = req.hints.as_mut() {
        h.parallel_grasp = Some(pb::ParallelGrasp {
            centre: Some(v3(c.x, c.y, top - 0.02)),
            axis: Some(v3(1.0, 0.0, 0.0)),
        });
    }
    let plan = server
        .grpc()
        .await
        .plan_grasp(req)
        .await
        .unwrap()
        .into_inner();
    assert!(plan.learned_quality.is_none());
    assert!(plan.approach.unwrap().z < -0.98);
    let xs: Vec<f64> = plan
        .contacts
        .iter()
        .filter(|k| k.finger != "palm")
        .map(|k| k.position.as_ref().unwrap().x - c.x)
        .collect();
    assert!(
        xs.iter().any(|&x| x < -0.02) && xs.iter().any(|&x| x > 0.02),
        "jaw contacts along x about the centre: {xs:?}"
    );
    let mut body = rest_body("robotiq_2f85");
    body["options"] = serde_json::json!({"seed": 3});
    body["hints"]["parallel_grasp"] =
        serde_json::json!({"centre": [c.x, c.y, top - 0.02], "axis": [0.0, 0.0, 1.0]});
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&body)
        .send()
        .await
        .unwrap();
    let (code, _, field, message) = rest_error(response).await;
    assert_eq!(
        (code, field.as_deref()),
        (400, Some("hints.parallel_grasp.axis")),
        "{message}"
    );
}
