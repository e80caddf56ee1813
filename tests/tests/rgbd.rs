//! RGB-D input through the real server (issue 3): frames rendered from the YCB meshes go in over
//! gRPC (raw rgb8 + 16UC1), REST JSON (base64) and REST multipart (PNG files); the target is the
//! hinted object, the ROI lies on it, the contacts are on its mesh, both transports give the same
//! plan, the overlay comes back as a PNG (REST `?format=png`, graspctl --overlay), and bad frames
//! get field-named errors without harming the next request.

use graspd::grpc::status::FIELD_METADATA_KEY;
use graspd_api::convert::plan_from_proto;
use graspd_api::json::PlanResponseJson;
use graspd_core::GraspPlan;
use graspd_core::perception::TargetChoice;
use graspd_e2e::{
    Server, assert_valid_plan_works, base64, binary, http, rest_error, rgbd_frame_proto,
};
use graspd_proto::v1 as pb;
use graspd_testkit::Object;
use graspd_testkit::rgbd::{RgbdRender, RgbdScene, SceneObject};
use serde_json::json;
use std::process::Command;
use std::sync::OnceLock;
use tonic::Code;

const RED: [u8; 3] = [200, 40, 30];
const BLUE: [u8; 3] = [30, 60, 200];
const HAND: &str = "parallel_gripper";

/// A tomato soup can (object 0) and a mustard bottle (object 1) on the table.
fn scene() -> &'static RgbdRender {
    static R: OnceLock<RgbdRender> = OnceLock::new();
    R.get_or_init(|| {
        RgbdScene::on_table(vec![
            SceneObject::new(Object::TomatoSoupCan, 0.0, -0.09, RED),
            SceneObject::new(Object::MustardBottle, 0.03, 0.1, BLUE),
        ])
        .render()
        .unwrap()
    })
}

fn grpc_request(frame: pb::RgbdFrame, pixel: Option<(u32, u32)>) -> pb::PlanGraspRequest {
    pb::PlanGraspRequest {
        input: Some(pb::plan_grasp_request::Input::Rgbd(frame)),
        hand: Some(pb::plan_grasp_request::Hand::HandName(HAND.into())),
        options: Some(pb::PlannerOptions {
            seed: Some(5),
            ..Default::default()
        }),
        hints: Some(pb::PlanHints {
            attention_pixel: pixel.map(|(u, v)| pb::Pixel { u, v }),
            ..Default::default()
        }),
        output: None,
        extra_views: Vec::new(),
    }
}

/// Plans `frame` over gRPC (hinted at `pixel`) and returns the response.
async fn plan_frame(
    server: &Server,
    frame: pb::RgbdFrame,
    pixel: Option<(u32, u32)>,
) -> pb::PlanGraspResponse {
    server
        .grpc()
        .await
        .plan_grasp(grpc_request(frame, pixel))
        .await
        .unwrap()
        .into_inner()
}

fn intrinsics_json(r: &RgbdRender) -> serde_json::Value {
    json!({"fx": r.intrinsics.fx, "fy": r.intrinsics.fy, "cx": r.intrinsics.cx, "cy": r.intrinsics.cy})
}

fn camera_json(r: &RgbdRender) -> serde_json::Value {
    let t = r.camera_to_world.translation.vector;
    let q = r.camera_to_world.rotation;
    json!({"position": [t.x, t.y, t.z], "orientation": {"x": q.i, "y": q.j, "z": q.k, "w": q.w}})
}

fn json_request(r: &RgbdRender, pixel: (u32, u32)) -> serde_json::Value {
    json!({
        "rgbd": {
            "color": {"width": r.width, "height": r.height, "encoding": "rgb8", "data": base64(&r.rgb)},
            "depth": {"width": r.width, "height": r.height, "encoding": "16UC1", "data": base64(&r.depth_mm_le())},
            "intrinsics": intrinsics_json(r),
            "camera_to_world": camera_json(r),
        },
        "hand_name": HAND,
        "options": {"seed": 5},
        "hints": {"attention_pixel": {"u": pixel.0, "v": pixel.1}},
    })
}

/// The checks every plan of the soup can must pass.
fn assert_plan_on_the_can(plan: &GraspPlan, r: &RgbdRender, what: &str) {
    let p = plan.perception.as_ref().expect("a perception report");
    assert_eq!((p.width, p.height), (r.width, r.height), "{what}");
    assert_eq!(p.objects, 2, "{what}: both objects are found");
    assert_eq!(p.target_source, TargetChoice::Pixel, "{what}");
    let truth = r.object_mask(0);
    let [u0, v0, u1, v1] = p.roi;
    let in_box = |k: usize| {
        let (u, v) = ((k % r.width) as u32, (k / r.width) as u32);
        (u0..u1).contains(&u) && (v0..v1).contains(&v)
    };
    let covered = (0..truth.len()).filter(|&k| truth[k] && in_box(k)).count();
    let total = truth.iter().filter(|t| **t).count();
    assert!(
        covered as f64 >= 0.9 * total as f64,
        "{what}: the ROI box {:?} holds {covered} of the can's {total} pixels",
        p.roi
    );
    assert!(
        p.roi_pixels > 1000 && p.object_points > 1000,
        "{what}: {p:?}"
    );
    assert_eq!(
        plan.type_source,
        graspd_core::planning::TypeSource::Model,
        "{what}: the built-in grasp-type model decides by default"
    );
    let d = r.distance_to_object(0, &plan.attention_point);
    assert!(d <= 0.003, "{what}: attention point {d} m off the can");
    let [au, av] = p.attention_pixel.expect("the hinted pixel");
    let (hu, hv) = r.object_pixel(0);
    assert!((au - hu as f64).abs() <= 3.0 && (av - hv as f64).abs() <= 3.0);
    assert!(!plan.contacts.is_empty());
    // Seen contacts on the can; those on the completed side near it.
    for c in &plan.contacts {
        let d = r.distance_to_object(0, &c.position);
        let limit = if c.inferred {
            graspd_testkit::ycb::MAX_INFERRED_OFF
        } else {
            0.003
        };
        assert!(d <= limit, "{what}: contact {d} m off the can");
    }
    assert_eq!(
        plan.plane_source,
        graspd_core::planning::PlaneSource::Detected
    );
    let plane = plan.support_plane.expect("the table");
    assert!(
        plane.normal.z > 0.999 && plane.offset.abs() < 0.003,
        "{plane:?}"
    );
    assert!(plan.feasible, "{what}: {:?}", plan.infeasible_reason);
}

/// A frame as a ROS camera driver publishes it — `bgra8` colour, big-endian `16UC1` depth
/// padded to a longer row, intrinsics as `CameraInfo.K` — plans exactly like the plain frame
/// (issue 20).
#[tokio::test]
async fn a_frame_in_ros_layouts_plans_like_the_plain_one() {
    let server = Server::start();
    let r = scene();
    let pixel = Some(r.object_pixel(0));
    let mut plain = plan_frame(&server, rgbd_frame_proto(r, true), pixel).await;
    let mut ros = rgbd_frame_proto(r, true);
    let color = ros.color.as_mut().unwrap();
    color.encoding = "bgra8".into();
    color.data = r
        .rgb
        .chunks_exact(3)
        .flat_map(|p| [p[2], p[1], p[0], 255])
        .collect();
    let depth = ros.depth.as_mut().unwrap();
    let row = 2 * r.width;
    depth.is_bigendian = true;
    depth.step = (row + 6) as u32;
    depth.data = depth
        .data
        .chunks_exact(row)
        .flat_map(|line| {
            let mut be: Vec<u8> = line.chunks_exact(2).flat_map(|b| [b[1], b[0]]).collect();
            be.extend_from_slice(&[0xEE; 6]);
            be
        })
        .collect();
    let k = ros.intrinsics.as_mut().unwrap();
    *k = pb::CameraIntrinsics {
        k: vec![k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0],
        ..Default::default()
    };
    let mut ros = plan_frame(&server, ros, pixel).await;
    for p in [&mut plain, &mut ros] {
        p.timings = None;
        p.perception.as_mut().unwrap().timings = None;
        for s in [&mut p.stage1, &mut p.stage2].into_iter().flatten() {
            s.seconds = 0.0;
        }
    }
    assert_eq!(ros, plain);
}

#[tokio::test]
async fn an_rgbd_frame_plans_the_hinted_object_alike_over_grpc_and_rest() {
    let server = Server::start();
    let r = scene();
    let pixel = r.object_pixel(0);
    let grpc = plan_frame(&server, rgbd_frame_proto(r, true), Some(pixel)).await;
    assert!(grpc.attention.as_ref().unwrap().pixel.is_some());
    let grpc = plan_from_proto(grpc).unwrap();
    assert_plan_on_the_can(&grpc, r, "gRPC");

    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&json_request(r, pixel))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let rest: PlanResponseJson = response.json().await.unwrap();
    let rp = rest.perception.as_ref().unwrap();
    let gp = grpc.perception.as_ref().unwrap();
    assert_eq!(
        (rp.roi.u_min, rp.roi.v_min, rp.roi.u_max, rp.roi.v_max),
        (gp.roi[0], gp.roi[1], gp.roi[2], gp.roi[3])
    );
    assert_eq!(rp.object_points, gp.object_points);
    assert_eq!(rest.grasp_type, grpc.grasp_type);
    assert_eq!(rest.contacts.len(), grpc.contacts.len());
    for (a, b) in rest.contacts.iter().zip(&grpc.contacts) {
        assert!(
            (a.position.point() - b.position).norm() < 1e-9,
            "{a:?} vs {b:?}"
        );
    }

    // Without a hint the most salient object is the target, and no attention pixel is reported.
    let plan = plan_frame(&server, rgbd_frame_proto(r, true), None).await;
    let p = plan.perception.unwrap();
    assert_eq!(p.target_source, "saliency");
    // The built-in model places the attention pixel by mean shift on map s* inside the ROI.
    let a = plan
        .attention
        .unwrap()
        .pixel
        .expect("an attention pixel from the model");
    let roi = p.roi.unwrap();
    assert!(
        (roi.u_min..=roi.u_max).contains(&a.u) && (roi.v_min..=roi.v_max).contains(&a.v),
        "{a:?} outside {roi:?}"
    );
}

#[tokio::test]
async fn without_onnx_runtime_or_with_model_none_the_geometric_rule_decides() {
    let r = scene();
    let pixel = r.object_pixel(0);
    for (args, warning) in [
        (
            &["--onnxruntime", "/nonexistent/libonnxruntime.so.1.31.1"][..],
            Some("the built-in grasp-type model is not loaded"),
        ),
        (&["--grasp-type-model", "none"][..], None),
    ] {
        let server = Server::start_with_logs(&[args, &["--log", "info"]].concat());
        let plan = plan_frame(&server, rgbd_frame_proto(r, true), Some(pixel)).await;
        let plan = plan_from_proto(plan).unwrap();
        assert_eq!(
            plan.type_source,
            graspd_core::planning::TypeSource::GeometricRule,
            "{args:?}"
        );
        assert!(plan.feasible, "{args:?}: {:?}", plan.infeasible_reason);
        let logs = server.logs().join("\n");
        match warning {
            Some(w) => assert!(logs.contains(w), "{args:?}: {logs}"),
            None => assert!(logs.contains("no grasp-type model"), "{args:?}: {logs}"),
        }
    }
}

#[tokio::test]
async fn multipart_pngs_give_the_overlay_with_format_png_and_graspctl_writes_it() {
    let server = Server::start();
    let r = scene();
    let pixel = r.object_pixel(0);
    let request = json!({
        "rgbd": {"intrinsics": intrinsics_json(r), "camera_to_world": camera_json(r)},
        "hand_name": HAND,
        "hints": {"attention_pixel": {"u": pixel.0, "v": pixel.1}},
    });
    let form = || {
        reqwest::multipart::Form::new()
            .part(
                "color",
                reqwest::multipart::Part::bytes(r.color_png()).file_name("rgb.png"),
            )
            .part(
                "depth",
                reqwest::multipart::Part::bytes(r.depth_png()).file_name("depth.png"),
            )
            .text("request", request.to_string())
    };
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .multipart(form())
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let plan: PlanResponseJson = response.json().await.unwrap();
    assert_eq!(plan.perception.unwrap().target_source, TargetChoice::Pixel);

    let response = http()
        .post(server.rest_url("/v1/plan?format=png"))
        .multipart(form())
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["content-type"], "image/png");
    let png = response.bytes().await.unwrap();
    let overlay = image::load_from_memory(&png).unwrap().to_rgb8();
    assert_eq!(
        (overlay.width() as usize, overlay.height() as usize),
        (r.width, r.height)
    );
    // The ROI box is drawn in yellow around the can; far from it the image is nearly unchanged
    // (the heat map of s* is blended in, and the built-in model gives the background a low
    // probability).
    let yellow = overlay.pixels().filter(|p| p.0 == [255, 220, 0]).count();
    assert!(yellow > 100, "{yellow} yellow pixels");
    let corner = overlay.get_pixel(5, 5).0;
    for (c, o) in corner.iter().zip(&r.rgb[15..18]) {
        assert!(c.abs_diff(*o) <= 10, "{corner:?} vs {:?}", &r.rgb[15..18]);
    }

    let dir = std::env::temp_dir().join(format!("graspd-rgbd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (rgb_path, depth_path, out) = (
        dir.join("rgb.png"),
        dir.join("depth.png"),
        dir.join("overlay.png"),
    );
    std::fs::write(&rgb_path, r.color_png()).unwrap();
    std::fs::write(&depth_path, r.depth_png()).unwrap();
    let k = r.intrinsics;
    let output = Command::new(binary("graspctl", "GRASPCTL_BIN"))
        .env_remove("GRASPD_SERVER")
        .args(["--server", &server.grpc_url(), "plan", "--hand", HAND])
        .arg("--rgb")
        .arg(&rgb_path)
        .arg("--depth")
        .arg(&depth_path)
        .arg("--intrinsics")
        .arg(format!("{},{},{},{}", k.fx, k.fy, k.cx, k.cy))
        .arg("--pixel")
        .arg(format!("{},{}", pixel.0, pixel.1))
        .arg("--overlay")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let written = image::open(&out).unwrap();
    assert_eq!(written.width() as usize, r.width);
    let _ = std::fs::remove_dir_all(&dir);
}

#[tokio::test]
async fn bad_frames_and_image_hints_get_field_named_errors() {
    let server = Server::start_with(&["--max-image-pixels", "400000"]);
    let r = scene();
    let good = rgbd_frame_proto(r, true);
    let mut cases: Vec<(&str, pb::PlanGraspRequest, Code)> = Vec::new();
    let mut f = good.clone();
    f.depth.as_mut().unwrap().width = 320;
    cases.push(("rgbd.depth", grpc_request(f, None), Code::InvalidArgument));
    let mut f = good.clone();
    f.color.as_mut().unwrap().encoding = "yuv422".into();
    cases.push((
        "rgbd.color.encoding",
        grpc_request(f, None),
        Code::InvalidArgument,
    ));
    let mut f = good.clone();
    let png = r.color_png();
    let c = f.color.as_mut().unwrap();
    c.encoding = "png".into();
    c.data = png[..png.len() / 2].to_vec();
    cases.push((
        "rgbd.color.data",
        grpc_request(f, None),
        Code::InvalidArgument,
    ));
    let mut f = good.clone();
    f.intrinsics.as_mut().unwrap().fx = 0.0;
    cases.push((
        "rgbd.intrinsics.fx",
        grpc_request(f, None),
        Code::InvalidArgument,
    ));
    let mut f = good.clone();
    let d = f.depth.as_mut().unwrap();
    d.data = vec![0; d.data.len()];
    cases.push((
        "rgbd.depth.data",
        grpc_request(f, None),
        Code::InvalidArgument,
    ));
    let mut f = good.clone();
    f.depth.as_mut().unwrap().data.truncate(1000);
    cases.push((
        "rgbd.depth.data",
        grpc_request(f, None),
        Code::InvalidArgument,
    ));
    cases.push((
        "hints.attention_pixel",
        grpc_request(good.clone(), Some((5000, 3))),
        Code::InvalidArgument,
    ));
    let mut req = grpc_request(good.clone(), None);
    req.hints.as_mut().unwrap().region = Some(pb::RegionBox {
        u_min: 10,
        v_min: 10,
        u_max: 10,
        v_max: 20,
    });
    cases.push(("hints.region", req, Code::InvalidArgument));
    let mut f = good.clone();
    f.camera_to_world.as_mut().unwrap().orientation = Some(pb::Quaternion::default());
    cases.push((
        "rgbd.camera_to_world.orientation",
        grpc_request(f, None),
        Code::InvalidArgument,
    ));
    let mut f = good.clone();
    for img in [f.color.as_mut().unwrap(), f.depth.as_mut().unwrap()] {
        img.width = 1280;
        img.height = 960;
    }
    cases.push(("rgbd", grpc_request(f, None), Code::ResourceExhausted));
    for (field, request, code) in cases {
        let e = server
            .grpc()
            .await
            .plan_grasp(request)
            .await
            .expect_err(field);
        assert_eq!(e.code(), code, "{field}: {}", e.message());
        let got = e
            .metadata()
            .get(FIELD_METADATA_KEY)
            .and_then(|v| v.to_str().ok());
        assert_eq!(got, Some(field), "{}", e.message());
    }

    // REST: the same frame errors, the query and the multipart parts.
    let pixel = r.object_pixel(0);
    let mut body = json_request(r, pixel);
    body["rgbd"]["depth"]["encoding"] = json!("16UC3");
    let mut no_intrinsics = json_request(r, pixel);
    no_intrinsics["rgbd"]
        .as_object_mut()
        .unwrap()
        .remove("intrinsics");
    let mut not_base64 = json_request(r, pixel);
    not_base64["rgbd"]["color"]["data"] = json!("%%%");
    for (url, body, status, field) in [
        ("/v1/plan", body, 400, "rgbd.depth.encoding"),
        ("/v1/plan", no_intrinsics, 400, "rgbd.intrinsics"),
        ("/v1/plan", not_base64, 400, "rgbd.color.data"),
        // A bad query with a 1.6 MB body: the server reads the body before it answers, so the
        // client gets the 400 rather than a broken pipe while still writing.
        ("/v1/plan?format=gif", json_request(r, pixel), 400, "format"),
        (
            "/v1/plan?format=png",
            graspd_e2e::json_request("shadow", 0),
            400,
            "format",
        ),
    ] {
        let response = http()
            .post(server.rest_url(url))
            .json(&body)
            .send()
            .await
            .unwrap();
        let (got, _, got_field, message) = rest_error(response).await;
        assert_eq!(
            (got, got_field.as_deref()),
            (status, Some(field)),
            "{message}"
        );
    }
    let mut cloud_with_pixel = graspd_e2e::json_request("shadow", 0);
    cloud_with_pixel["hints"]["attention_pixel"] = json!({"u": 3, "v": 4});
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&cloud_with_pixel)
        .send()
        .await
        .unwrap();
    let (got, _, got_field, message) = rest_error(response).await;
    assert_eq!(
        (got, got_field.as_deref()),
        (400, Some("hints.attention_pixel")),
        "{message}"
    );
    let form = reqwest::multipart::Form::new().part(
        "color",
        reqwest::multipart::Part::bytes(r.color_png()).file_name("rgb.png"),
    );
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .multipart(form)
        .send()
        .await
        .unwrap();
    let (got, _, got_field, message) = rest_error(response).await;
    assert_eq!(
        (got, got_field.as_deref()),
        (400, Some("rgbd")),
        "{message}"
    );

    // The server still plans, from a cloud and from the frame.
    assert_valid_plan_works(&server).await;
    let plan = plan_frame(&server, good, Some(pixel)).await;
    assert_plan_on_the_can(&plan_from_proto(plan).unwrap(), r, "after the errors");
}

#[path = "../../service/core/tests/common/onnx_builder.rs"]
mod onnx_builder;

/// A 1×1-convolution grasp-type model on the normalised colour (ImageNet mean/std): the power
/// logit is 4·(R − B), the precision logit 4·(B − R), the others −5 everywhere — so red pixels
/// say power, blue ones precision.
fn colour_model_file(name: &str, types: usize) -> std::path::PathBuf {
    let mut weights = vec![vec![0.0f32; 3]; types];
    let mut bias = vec![-5.0f32; types];
    weights[2] = vec![4.0, 0.0, -4.0];
    bias[2] = 0.0;
    weights[4] = vec![-4.0, 0.0, 4.0];
    bias[4] = 0.0;
    let bytes = onnx_builder::conv1x1_model(3, &weights, &bias, 1, None, None).build();
    let dir = std::env::temp_dir().join(format!("graspd-model-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

#[tokio::test]
async fn a_grasp_type_model_decides_the_type_over_the_roi_and_places_the_attention_point() {
    let model = colour_model_file("colour.onnx", 6);
    let server = Server::start_with(&["--grasp-type-model", model.to_str().unwrap()]);
    let r = scene();
    for (object, hint, expected) in [
        (
            0,
            (Some(r.object_pixel(0)), None),
            graspd_core::GraspType::Power,
        ),
        (1, (None, Some(1)), graspd_core::GraspType::Precision),
    ] {
        let mut request = grpc_request(rgbd_frame_proto(r, true), hint.0);
        request.hand = Some(pb::plan_grasp_request::Hand::HandName("shadow".into()));
        if hint.1.is_some() {
            // A box around the bottle only.
            let truth = r.object_mask(1);
            let (mut lo, mut hi) = ((u32::MAX, u32::MAX), (0, 0));
            for (k, _) in truth.iter().enumerate().filter(|(_, t)| **t) {
                let (u, v) = ((k % r.width) as u32, (k / r.width) as u32);
                lo = (lo.0.min(u), lo.1.min(v));
                hi = (hi.0.max(u + 1), hi.1.max(v + 1));
            }
            request.hints.as_mut().unwrap().region = Some(pb::RegionBox {
                u_min: lo.0,
                v_min: lo.1,
                u_max: hi.0,
                v_max: hi.1,
            });
        }
        request.output = Some(pb::OutputOptions {
            probability_maps_max_side: 32,
            ..Default::default()
        });
        let plan = server
            .grpc()
            .await
            .plan_grasp(request)
            .await
            .unwrap()
            .into_inner();
        let plan = plan_from_proto(plan).unwrap();
        assert_eq!(plan.type_source, graspd_core::planning::TypeSource::Model);
        assert_eq!(plan.grasp_type, expected, "{:?}", plan.type_scores);
        // Eq 4.3: the ROI lies on one object, whose pixels all say the same.
        let p = plan.type_scores;
        assert!(p[expected.index()] > 0.99, "{p:?}");
        for (s, v) in p.iter().enumerate() {
            if s != 2 && s != 4 {
                assert!((v - sigmoid(-5.0)).abs() < 1e-6, "type {s}: {v}");
            }
        }
        let d = r.distance_to_object(object, &plan.attention_point);
        assert!(d <= 0.003, "attention point {d} m off object {object}");
        let report = plan.perception.unwrap();
        let maps = report.probability_maps.expect("the maps were asked for");
        assert_eq!((maps.width, maps.height), (32, 24));
        assert_eq!(maps.values.len(), 6 * 32 * 24);
        // The table is grey: R ≈ B there, so neither colour type is sure of it.
        let corner = |s: usize| maps.values[s * 32 * 24 + 23 * 32];
        assert!(
            corner(2) < 0.9 && corner(4) < 0.9,
            "{} {}",
            corner(2),
            corner(4)
        );
        assert!((corner(0) as f64 - sigmoid(-5.0)).abs() < 1e-6);
    }
    // A hand that realises neither: s* is its most probable realisable type.
    let mut request = grpc_request(rgbd_frame_proto(r, true), Some(r.object_pixel(0)));
    request.hand = Some(pb::plan_grasp_request::Hand::HandName(HAND.into()));
    let plan = plan_from_proto(
        server
            .grpc()
            .await
            .plan_grasp(request)
            .await
            .unwrap()
            .into_inner(),
    )
    .unwrap();
    assert_eq!(plan.type_source, graspd_core::planning::TypeSource::Model);
    assert_eq!(plan.requested_type, graspd_core::GraspType::Power);
    assert_eq!(plan.grasp_type, graspd_core::GraspType::Pinch);
}

#[test]
fn a_model_that_breaks_the_contract_stops_the_start() {
    let model = colour_model_file("five.onnx", 5);
    let output = Command::new(binary("graspd", "GRASPD_BIN"))
        .args(["--grpc-addr", "127.0.0.1:0", "--rest-addr", "127.0.0.1:0"])
        .arg("--grasp-type-model")
        .arg(&model)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(
        stderr.contains("[1, 5, Ho, Wo]") && stderr.contains("[1, 6, H, W]"),
        "{stderr}"
    );
    let output = Command::new(binary("graspd", "GRASPD_BIN"))
        .args(["--grpc-addr", "127.0.0.1:0", "--rest-addr", "127.0.0.1:0"])
        .args(["--grasp-type-model", "/nonexistent/model.onnx"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(stderr.contains("/nonexistent/model.onnx"), "{stderr}");
}
