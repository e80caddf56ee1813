//! The object by name through the real server (issue 18, part 1): `hints.object` picks the
//! named object among several on the table (gRPC and REST), an absent or unknown name is
//! NOT_FOUND / 404 naming the objects found, conflicting hints and a server without the
//! recogniser are INVALID_ARGUMENT / 400 naming `hints.object`, and the next request works;
//! graspctl names the object on its command line.

use graspd::grpc::status::FIELD_METADATA_KEY;
use graspd_api::convert::plan_from_proto;
use graspd_core::perception::TargetChoice;
use graspd_e2e::{Server, base64, binary, http, rest_error, rgbd_frame_proto};
use graspd_proto::v1 as pb;
use graspd_testkit::Object;
use graspd_testkit::rgbd::{RgbdRender, RgbdScene, SceneObject};
use serde_json::json;
use std::sync::OnceLock;
use tonic::Code;

const HAND: &str = "parallel_gripper";

/// A mustard bottle (object 0), a tomato soup can (1) and an orange (2), with their scanned
/// textures.
fn scene() -> &'static RgbdRender {
    static R: OnceLock<RgbdRender> = OnceLock::new();
    R.get_or_init(|| {
        RgbdScene::on_table(vec![
            SceneObject::scanned(Object::MustardBottle, 0.02, -0.12),
            SceneObject::scanned(Object::TomatoSoupCan, 0.0, 0.0),
            SceneObject::scanned(Object::Orange, -0.02, 0.12),
        ])
        .render()
        .unwrap()
    })
}

fn request(object: &str, pixel: Option<(u32, u32)>) -> pb::PlanGraspRequest {
    pb::PlanGraspRequest {
        input: Some(pb::plan_grasp_request::Input::Rgbd(rgbd_frame_proto(
            scene(),
            true,
        ))),
        hand: Some(pb::plan_grasp_request::Hand::HandName(HAND.into())),
        options: Some(pb::PlannerOptions {
            seed: Some(3),
            ..Default::default()
        }),
        hints: Some(pb::PlanHints {
            object: object.into(),
            attention_pixel: pixel.map(|(u, v)| pb::Pixel { u, v }),
            ..Default::default()
        }),
        output: None,
        extra_views: Vec::new(),
    }
}

fn rest_body(object: &str) -> serde_json::Value {
    let r = scene();
    let t = r.camera_to_world.translation.vector;
    let q = r.camera_to_world.rotation;
    json!({
        "rgbd": {
            "color": {"width": r.width, "height": r.height, "encoding": "rgb8", "data": base64(&r.rgb)},
            "depth": {"width": r.width, "height": r.height, "encoding": "16UC1", "data": base64(&r.depth_mm_le())},
            "intrinsics": {"fx": r.intrinsics.fx, "fy": r.intrinsics.fy, "cx": r.intrinsics.cx, "cy": r.intrinsics.cy},
            "camera_to_world": {"position": [t.x, t.y, t.z], "orientation": {"x": q.i, "y": q.j, "z": q.k, "w": q.w}},
        },
        "hand_name": HAND,
        "options": {"seed": 3},
        "hints": {"object": object},
    })
}

#[tokio::test]
async fn hints_object_plans_the_named_object() {
    let server = Server::start();
    let r = scene();
    let mut grpc = server.grpc().await;
    for (k, name) in [
        (0, "mustard_bottle"),
        (1, "Tomato soup can"),
        (2, "017_orange"),
    ] {
        let response = grpc
            .plan_grasp(request(name, None))
            .await
            .unwrap()
            .into_inner();
        let plan = plan_from_proto(response).unwrap();
        let p = plan.perception.as_ref().unwrap();
        assert_eq!(p.target_source, TargetChoice::Object, "{name}");
        assert_eq!(p.recognised.len(), 3, "{name}: {:?}", p.recognised);
        assert!(p.timings.recognition > 0.0);
        let d = r.distance_to_object(k, &plan.attention_point);
        assert!(d <= 0.003, "{name}: attention point {d} m off it");
        for c in plan.contacts.iter().filter(|c| !c.inferred) {
            let d = r.distance_to_object(k, &c.position);
            assert!(d <= 0.003, "{name}: contact {d} m off it");
        }
    }
    // REST, the same object.
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&rest_body("orange"))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let body: serde_json::Value = response.json().await.unwrap();
    assert_eq!(body["perception"]["target_source"], "object");
    let recognised = body["perception"]["recognised"].as_array().unwrap();
    assert!(
        recognised.iter().any(|o| o["class_name"] == "orange"),
        "{recognised:?}"
    );
}

/// graspctl plan --object on PNG files: the target is chosen by name; an absent one is an
/// error naming the field.
#[test]
fn graspctl_plans_the_object_named_on_its_command_line() {
    let server = Server::start();
    let r = scene();
    let dir = std::env::temp_dir().join(format!("graspd-recognition-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (rgb, depth) = (dir.join("rgb.png"), dir.join("depth.png"));
    std::fs::write(&rgb, r.color_png()).unwrap();
    std::fs::write(&depth, r.depth_png()).unwrap();
    let k = r.intrinsics;
    let plan = |name: &str| {
        std::process::Command::new(binary("graspctl", "GRASPCTL_BIN"))
            .env_remove("GRASPD_SERVER")
            .args(["--server", &server.grpc_url(), "plan", "--hand", HAND])
            .arg("--rgb")
            .arg(&rgb)
            .arg("--depth")
            .arg(&depth)
            .arg("--intrinsics")
            .arg(format!("{},{},{},{}", k.fx, k.fy, k.cx, k.cy))
            .args(["--object", name])
            .output()
            .unwrap()
    };
    let out = plan("orange");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("target by object"), "{stdout}");
    let out = plan("banana");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("hints.object") && stderr.contains("no banana in view"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[tokio::test]
async fn absent_unknown_or_conflicting_names_are_refused_naming_the_field() {
    let server = Server::start();
    let mut grpc = server.grpc().await;
    // A known object that is not on the table, and a name the recogniser does not know.
    for (name, says) in [
        ("banana", "no banana in view"),
        ("teapot", "not an object the recogniser knows"),
    ] {
        let status = grpc.plan_grasp(request(name, None)).await.unwrap_err();
        assert_eq!(status.code(), Code::NotFound, "{name}: {status:?}");
        assert_eq!(
            status.metadata().get(FIELD_METADATA_KEY).unwrap(),
            "hints.object"
        );
        assert!(status.message().contains(says), "{}", status.message());
        assert!(
            status.message().contains("mustard_bottle (p "),
            "the objects found are named: {}",
            status.message()
        );
        let response = http()
            .post(server.rest_url("/v1/plan"))
            .json(&rest_body(name))
            .send()
            .await
            .unwrap();
        let (code, kind, field, message) = rest_error(response).await;
        assert_eq!((code, kind.as_str()), (404, "not_found"), "{message}");
        assert_eq!(field.as_deref(), Some("hints.object"));
    }
    // A name with a pixel: which one is meant?
    let status = grpc
        .plan_grasp(request("orange", Some((320, 240))))
        .await
        .unwrap_err();
    assert_eq!(status.code(), Code::InvalidArgument);
    assert_eq!(
        status.metadata().get(FIELD_METADATA_KEY).unwrap(),
        "hints.object"
    );
    // The next request still works.
    grpc.plan_grasp(request("orange", None)).await.unwrap();
}

#[tokio::test]
async fn without_the_recogniser_a_name_is_invalid() {
    let server = Server::start_with(&["--recogniser-model", "none"]);
    let status = server
        .grpc()
        .await
        .plan_grasp(request("orange", None))
        .await
        .unwrap_err();
    assert_eq!(status.code(), Code::InvalidArgument);
    assert_eq!(
        status.metadata().get(FIELD_METADATA_KEY).unwrap(),
        "hints.object"
    );
    assert!(
        status.message().contains("recogniser"),
        "{}",
        status.message()
    );
}
