//! Several RGB-D views in one PlanGrasp request (issue 15, `extra_views`), through the real
//! server: a tomato soup can beside a mustard bottle, seen from the −x side (the first frame,
//! which drives perception) and from the +x side. The second view's points of the can join the
//! target — its far side is then measured, not completed, so every contact lies on the can —
//! the bottle's do not; both transports plan alike; a view without its pose, views with a cloud,
//! and more views than `--max-views` are refused naming the field, and the next request works.

use graspd::grpc::status::FIELD_METADATA_KEY;
use graspd_e2e::{Server, assert_valid_plan_works, base64, http, rest_error, rgbd_frame_proto};
use graspd_proto::v1 as pb;
use graspd_testkit::Object;
use graspd_testkit::render::Camera;
use graspd_testkit::rgbd::{RgbdRender, RgbdScene, SceneObject};
use serde_json::json;
use std::sync::OnceLock;
use tonic::Code;

const HAND: &str = "parallel_gripper";

/// The scene from azimuth `az` (degrees; 180: from −x, the default view).
fn render_from(az: f64) -> RgbdRender {
    let mut scene = RgbdScene::on_table(vec![
        SceneObject::new(Object::TomatoSoupCan, 0.0, -0.09, [200, 40, 30]),
        SceneObject::new(Object::MustardBottle, 0.03, 0.1, [30, 60, 200]),
    ]);
    let intrinsics = scene.camera.intrinsics;
    scene.camera = Camera::orbit(scene.camera.target, 0.7, 45.0, az);
    scene.camera.intrinsics = intrinsics;
    scene.render().unwrap()
}

fn views() -> &'static (RgbdRender, RgbdRender) {
    static V: OnceLock<(RgbdRender, RgbdRender)> = OnceLock::new();
    V.get_or_init(|| (render_from(180.0), render_from(0.0)))
}

fn request(extra: Vec<pb::RgbdFrame>) -> pb::PlanGraspRequest {
    let (front, _) = views();
    let (u, v) = front.object_pixel(0);
    pb::PlanGraspRequest {
        input: Some(pb::plan_grasp_request::Input::Rgbd(rgbd_frame_proto(
            front, true,
        ))),
        hand: Some(pb::plan_grasp_request::Hand::HandName(HAND.into())),
        options: Some(pb::PlannerOptions {
            seed: Some(5),
            ..Default::default()
        }),
        hints: Some(pb::PlanHints {
            attention_pixel: Some(pb::Pixel { u, v }),
            ..Default::default()
        }),
        extra_views: extra,
        ..Default::default()
    }
}

fn frame_json(r: &RgbdRender) -> serde_json::Value {
    let t = r.camera_to_world.translation.vector;
    let q = r.camera_to_world.rotation;
    json!({
        "color": {"width": r.width, "height": r.height, "encoding": "rgb8", "data": base64(&r.rgb)},
        "depth": {"width": r.width, "height": r.height, "encoding": "16UC1", "data": base64(&r.depth_mm_le())},
        "intrinsics": {"fx": r.intrinsics.fx, "fy": r.intrinsics.fy, "cx": r.intrinsics.cx, "cy": r.intrinsics.cy},
        "camera_to_world": {"position": [t.x, t.y, t.z], "orientation": {"x": q.i, "y": q.j, "z": q.k, "w": q.w}},
    })
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_second_view_completes_the_target_and_both_transports_agree() {
    let server = Server::start_with(&["--max-views", "1"]);
    let (front, back) = views();
    let mut client = server.grpc().await;
    let single = client
        .plan_grasp(request(Vec::new()))
        .await
        .unwrap()
        .into_inner();
    let fused = client
        .plan_grasp(request(vec![rgbd_frame_proto(back, true)]))
        .await
        .unwrap()
        .into_inner();
    let (p1, p2) = (
        single.perception.unwrap(),
        fused.perception.clone().unwrap(),
    );
    assert_eq!(p1.fused_views, 0);
    assert_eq!(p2.fused_views, 1);
    assert!(p2.fused_points > 1000, "{p2:?}");
    assert_eq!(p2.object_points, p1.object_points + p2.fused_points);
    // The can's far side is measured: every contact is on the can, none inferred.
    assert!(!fused.contacts.is_empty());
    for c in &fused.contacts {
        let p = c.position.unwrap();
        let d = front.distance_to_object(0, &nalgebra::Point3::new(p.x, p.y, p.z));
        assert!(d <= 0.004, "contact {d} m off the can");
        assert!(!c.inferred, "no completion with a second view");
    }
    // No point of the bottle joined: the second view adds at most the can's pixels it sees.
    let can_in_back = back.object_mask(0).iter().filter(|m| **m).count() as u64;
    assert!(
        p2.fused_points <= can_in_back,
        "{} points added, the back view sees {can_in_back} of the can",
        p2.fused_points
    );
    assert!(fused.feasible, "{:?}", fused.infeasible_reason);

    // REST: the same views as JSON give the same plan.
    let (u, v) = front.object_pixel(0);
    let body = json!({
        "rgbd": frame_json(front),
        "extra_views": [frame_json(back)],
        "hand_name": HAND,
        "options": {"seed": 5},
        "hints": {"attention_pixel": {"u": u, "v": v}},
    });
    let rest: serde_json::Value = http()
        .post(server.rest_url("/v1/plan"))
        .json(&body)
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    assert_eq!(rest["perception"]["fused_views"], 1);
    assert_eq!(
        rest["perception"]["fused_points"].as_u64(),
        Some(p2.fused_points)
    );
    let rest_contacts = rest["contacts"].as_array().unwrap();
    assert_eq!(rest_contacts.len(), fused.contacts.len());
    for (a, b) in rest_contacts.iter().zip(&fused.contacts) {
        let p = b.position.unwrap();
        let q = &a["position"];
        let (x, y, z) = (
            q["x"].as_f64().unwrap(),
            q["y"].as_f64().unwrap(),
            q["z"].as_f64().unwrap(),
        );
        assert!((x - p.x).abs() < 1e-9 && (y - p.y).abs() < 1e-9 && (z - p.z).abs() < 1e-9);
    }

    // Refusals, each naming the field.
    let mut blind = rgbd_frame_proto(back, false);
    blind.camera_to_world = None;
    let mut unposed_first = request(vec![rgbd_frame_proto(back, true)]);
    if let Some(pb::plan_grasp_request::Input::Rgbd(f)) = &mut unposed_first.input {
        f.camera_to_world = None;
    }
    let mut with_cloud = graspd_e2e::grpc_request(HAND, 1);
    with_cloud.extra_views = vec![rgbd_frame_proto(back, true)];
    for (req, code, field) in [
        (
            request(vec![blind]),
            Code::InvalidArgument,
            "extra_views[0].camera_to_world",
        ),
        (unposed_first, Code::InvalidArgument, "rgbd.camera_to_world"),
        (with_cloud, Code::InvalidArgument, "extra_views"),
        (
            request(vec![
                rgbd_frame_proto(back, true),
                rgbd_frame_proto(back, true),
            ]),
            Code::ResourceExhausted,
            "extra_views",
        ),
    ] {
        let e = client.plan_grasp(req).await.unwrap_err();
        assert_eq!(e.code(), code, "{field}: {}", e.message());
        let got = e
            .metadata()
            .get(FIELD_METADATA_KEY)
            .and_then(|v| v.to_str().ok());
        assert_eq!(got, Some(field), "{}", e.message());
    }
    let mut body = body;
    body["extra_views"][0]
        .as_object_mut()
        .unwrap()
        .remove("camera_to_world");
    let (status, _, field, _) = rest_error(
        http()
            .post(server.rest_url("/v1/plan"))
            .json(&body)
            .send()
            .await
            .unwrap(),
    )
    .await;
    assert_eq!(
        (status, field.as_deref()),
        (400, Some("extra_views[0].camera_to_world"))
    );
    assert_valid_plan_works(&server).await;
}
