//! PlanReach over gRPC and POST /v1/reach against the real binary on loopback (issue 18 part 4):
//! both transports give the same trajectory, round the same obstacle, ending on the grasp;
//! bad requests are refused naming the field, and the server still answers after them.

use graspd_e2e::{Server, assert_valid_plan_works, base64, http, refused_naming};
use graspd_proto::v1 as pb;
use serde_json::json;
use tonic::Code;

fn v(x: f64, y: f64, z: f64) -> pb::Vec3 {
    pb::Vec3 { x, y, z }
}

fn pose(p: pb::Vec3, q: (f64, f64, f64, f64)) -> pb::Pose {
    pb::Pose {
        position: Some(p),
        orientation: Some(pb::Quaternion {
            x: q.0,
            y: q.1,
            z: q.2,
            w: q.3,
        }),
    }
}

/// From 40 cm above the table to a top grasp at (0.5, 0.2, 0.1), round a post in the way.
fn grpc_request() -> pb::PlanReachRequest {
    pb::PlanReachRequest {
        start: Some(pose(v(0.0, 0.0, 0.4), (0.0, 0.0, 0.0, 1.0))),
        goal: Some(pose(v(0.5, 0.2, 0.1), (1.0, 0.0, 0.0, 0.0))),
        approach: Some(v(0.0, 0.0, -1.0)),
        obstacles: vec![pb::Obstacle {
            centre: Some(v(0.25, 0.1, 0.3)),
            half_extents: Some(v(0.04, 0.04, 0.15)),
            orientation: None,
        }],
        support_plane: Some(pb::Plane {
            normal: Some(v(0.0, 0.0, 1.0)),
            offset: 0.0,
        }),
        hand_radius: Some(0.04),
        ..Default::default()
    }
}

fn json_request() -> serde_json::Value {
    json!({
        "start": {"position": [0.0, 0.0, 0.4], "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}},
        "goal": {"position": {"x": 0.5, "y": 0.2, "z": 0.1}, "orientation": {"x": 1.0, "y": 0.0, "z": 0.0, "w": 0.0}},
        "approach": [0.0, 0.0, -1.0],
        "obstacles": [{"centre": [0.25, 0.1, 0.3], "half_extents": [0.04, 0.04, 0.15]}],
        "support_plane": {"normal": [0.0, 0.0, 1.0], "offset": 0.0},
        "hand_radius": 0.04
    })
}

#[tokio::test]
async fn both_transports_plan_the_same_reach_round_the_obstacle() {
    let server = Server::start();
    let g = server
        .grpc()
        .await
        .plan_reach(grpc_request())
        .await
        .unwrap()
        .into_inner();
    // 1.5 s of reach and 0.6 s of approach at 10 ms, and the start.
    assert_eq!(g.samples.len(), 211);
    let last = g.samples.last().unwrap();
    let p = last.pose.as_ref().unwrap().position.as_ref().unwrap();
    assert!((p.x - 0.5).abs() < 1e-9 && (p.y - 0.2).abs() < 1e-9 && (p.z - 0.1).abs() < 1e-9);
    assert!((last.time - 2.1).abs() < 1e-9);
    assert!(g.obstacle_clearance.unwrap() >= 0.01, "{g:?}");
    assert_eq!(g.closest_obstacle, Some(0));
    assert!(g.reach_error < 0.005);
    assert!(g.table_clearance.unwrap() > 0.0);

    let r: serde_json::Value = http()
        .post(server.rest_url("/v1/reach"))
        .json(&json_request())
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    let samples = r["samples"].as_array().unwrap();
    assert_eq!(samples.len(), g.samples.len());
    for (a, b) in samples.iter().zip(&g.samples) {
        let p = b.pose.as_ref().unwrap().position.as_ref().unwrap();
        let q = &a["pose"]["position"];
        assert_eq!(
            (q["x"].as_f64(), q["y"].as_f64(), q["z"].as_f64()),
            (Some(p.x), Some(p.y), Some(p.z))
        );
        assert_eq!(a["time"].as_f64(), Some(b.time));
    }
    assert_eq!(r["obstacle_clearance"].as_f64(), g.obstacle_clearance);
    assert_eq!(r["closest_obstacle"], 0);
}

/// A change that spoils a good request.
type Edit = Box<dyn Fn(&mut pb::PlanReachRequest)>;

#[tokio::test]
async fn bad_reaches_are_refused_naming_the_field() {
    let server = Server::start();
    let mut grpc = server.grpc().await;
    let cases: Vec<(&str, Edit)> = vec![
        ("start", Box::new(|r| r.start = None)),
        (
            "goal.orientation",
            Box::new(|r| r.goal.as_mut().unwrap().orientation = Some(pb::Quaternion::default())),
        ),
        (
            "start",
            Box::new(|r| r.obstacles[0].centre = Some(v(0.0, 0.0, 0.4))),
        ),
        (
            "obstacles[0].half_extents",
            Box::new(|r| r.obstacles[0].half_extents = Some(v(0.1, -0.1, 0.1))),
        ),
        (
            "options.time_step",
            Box::new(|r| {
                r.options = Some(pb::ReachOptions {
                    time_step: 0.0005,
                    ..Default::default()
                })
            }),
        ),
        (
            "support_plane",
            Box::new(|r| r.support_plane.as_mut().unwrap().normal = Some(v(0.0, 0.0, 0.0))),
        ),
        (
            "goal",
            Box::new(|r| r.goal.as_mut().unwrap().position = Some(v(0.5, 0.2, -0.2))),
        ),
    ];
    for (field, edit) in &cases {
        let mut r = grpc_request();
        edit(&mut r);
        let e = grpc.plan_reach(r).await.unwrap_err();
        assert_eq!(e.code(), Code::InvalidArgument, "{field}: {e:?}");
        assert!(
            e.message().starts_with(&format!("{field}: ")),
            "{field}: {}",
            e.message()
        );
    }
    let rest_cases = [
        ("goal", "/obstacles/0/centre", json!([0.5, 0.2, 0.1])),
        ("options.horizon", "/options", json!({"horizon": 1000})),
        ("hand_radius", "/hand_radius", json!("big")),
    ];
    for (field, at, value) in rest_cases {
        let mut body = json_request();
        match body.pointer_mut(at) {
            Some(slot) => *slot = value,
            None => body[&at[1..]] = value,
        }
        let response = http()
            .post(server.rest_url("/v1/reach"))
            .json(&body)
            .send()
            .await
            .unwrap();
        refused_naming(response, field).await;
    }
    assert_valid_plan_works(&server).await;
    assert!(grpc.plan_reach(grpc_request()).await.is_ok());
}

/// A frame from 1.2 m straight above the table (200 × 150, f = 200 px): a post 8 × 8 × 35 cm
/// at (0.25, 0.1) and the grasp's block 8 × 8 × 10 cm at (0.5, 0.2), seen from the top.
fn scene_frame() -> pb::RgbdFrame {
    let (w, h, f) = (200u32, 150u32, 200.0);
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let mut depth = Vec::with_capacity((w * h * 2) as usize);
    for v in 0..h {
        for u in 0..w {
            let at = |d: f64| {
                (
                    0.25 + d * (u as f64 - cx) / f,
                    0.1 - d * (v as f64 - cy) / f,
                )
            };
            let on = |d: f64, x0: f64, y0: f64| {
                let (x, y) = at(d);
                (x - x0).abs() <= 0.04 && (y - y0).abs() <= 0.04
            };
            let mm: u16 = if on(0.85, 0.25, 0.1) {
                850
            } else if on(1.1, 0.5, 0.2) {
                1100
            } else {
                1200
            };
            depth.extend_from_slice(&mm.to_le_bytes());
        }
    }
    pb::RgbdFrame {
        color: Some(pb::Image {
            width: w,
            height: h,
            encoding: "rgb8".into(),
            step: w * 3,
            data: vec![128; (w * h * 3) as usize],
            is_bigendian: false,
        }),
        depth: Some(pb::Image {
            width: w,
            height: h,
            encoding: "16UC1".into(),
            step: w * 2,
            data: depth,
            is_bigendian: false,
        }),
        intrinsics: Some(pb::CameraIntrinsics {
            fx: f,
            fy: f,
            cx,
            cy,
            k: Vec::new(),
        }),
        depth_scale: 0.001,
        // Camera z down, x along the world's x: turned 180° about x.
        camera_to_world: Some(pose(v(0.25, 0.1, 1.2), (1.0, 0.0, 0.0, 0.0))),
    }
}

#[tokio::test]
async fn the_scenes_other_objects_are_obstacles() {
    let server = Server::start();
    let mut grpc = server.grpc().await;
    // The post seen in the frame, not sent as a box; the table found in it too.
    let mut r = grpc_request();
    r.obstacles.clear();
    r.support_plane = None;
    r.scene = Some(scene_frame());
    let seen = grpc.plan_reach(r).await.unwrap().into_inner();
    // Only the post is an obstacle (the block is the grasp's object).
    assert_eq!(seen.closest_obstacle, Some(0), "{seen:?}");
    let c = seen.obstacle_clearance.unwrap();
    println!(
        "the post seen in the frame: clearance {:.1} mm, {:.1} ms in the server",
        c * 1e3,
        seen.server_ms
    );
    assert!(c >= 0.01, "{c}");
    assert!(seen.table_clearance.unwrap() > 0.0);
    // Without the frame the reach runs into the post: it is the frame that kept it away.
    let mut blind = grpc_request();
    blind.obstacles.clear();
    let blind = grpc.plan_reach(blind).await.unwrap().into_inner();
    let post = (0.25, 0.1, 0.175, 0.04, 0.04, 0.175);
    let closest = blind
        .samples
        .iter()
        .map(|s| {
            let p = s.pose.as_ref().unwrap().position.as_ref().unwrap();
            let d = [
                ((p.x - post.0).abs() - post.3).max(0.0),
                ((p.y - post.1).abs() - post.4).max(0.0),
                ((p.z - post.2).abs() - post.5).max(0.0),
            ];
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() - 0.04
        })
        .fold(f64::INFINITY, f64::min);
    println!("without the frame: {:.1} mm", closest * 1e3);
    assert!(
        closest < 0.0,
        "the unobstructed reach misses the post ({closest} m)"
    );
    // The same over REST, the images in base64.
    let f = scene_frame();
    let image = |i: &pb::Image| {
        json!({"width": i.width, "height": i.height, "encoding": i.encoding, "step": i.step,
               "data": base64(&i.data)})
    };
    let k = f.intrinsics.as_ref().unwrap();
    let mut body = json_request();
    body.as_object_mut().unwrap().remove("obstacles");
    body.as_object_mut().unwrap().remove("support_plane");
    body["scene"] = json!({
        "color": image(f.color.as_ref().unwrap()),
        "depth": image(f.depth.as_ref().unwrap()),
        "intrinsics": {"fx": k.fx, "fy": k.fy, "cx": k.cx, "cy": k.cy},
        "depth_scale": 0.001,
        "camera_to_world": {"position": [0.25, 0.1, 1.2], "orientation": {"x": 1.0, "y": 0.0, "z": 0.0, "w": 0.0}}
    });
    let rest: serde_json::Value = http()
        .post(server.rest_url("/v1/reach"))
        .json(&body)
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    assert_eq!(rest["obstacle_clearance"].as_f64(), Some(c), "{rest}");
    assert_eq!(
        rest["samples"].as_array().unwrap().len(),
        seen.samples.len()
    );
    // A frame without intrinsics is refused naming them.
    let mut bad = grpc_request();
    let mut frame = scene_frame();
    frame.intrinsics = None;
    bad.scene = Some(frame);
    let e = grpc.plan_reach(bad).await.unwrap_err();
    assert_eq!(e.code(), Code::InvalidArgument);
    assert!(
        e.message().starts_with("scene.intrinsics"),
        "{}",
        e.message()
    );
}
