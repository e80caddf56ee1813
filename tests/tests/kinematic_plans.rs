//! The shared hands (../shared/testdata/hands) imported at start with `--import-hand`, planned
//! by the real binary on single-view YCB clouds over gRPC: every plan names every joint of the
//! model with an angle inside its limits and carries per-contact residuals (link surface to
//! contact); feasible plans meet their contacts within 5 mm and their final configuration stays
//! clear of the support plane (1 mm tolerance); every hand gets at least one feasible plan. With
//! `candidates` the pre-grasp, squeeze, approach and ranked candidates come back the same over
//! gRPC and REST.

use graspd_api::convert::plan_from_proto;
use graspd_api::json::PlanResponseJson;
use graspd_core::hand::kinematics::KinematicHand;
use graspd_e2e::{Server, base64, http, packed, without_timings};
use graspd_proto::v1 as pb;
use graspd_testkit::view::standard_view;
use graspd_testkit::ycb::Object;

const HANDS: [(&str, &str); 4] = [
    ("shadow_mjcf", "shadow_hand/right_hand.xml"),
    ("allegro", "wonik_allegro/right_hand.xml"),
    ("robotiq_2f85", "robotiq_2f85/2f85.xml"),
    ("barrett_mjcf", "barrett/wam_barrett_gripper.xml"),
];

fn v3(x: f64, y: f64, z: f64) -> pb::Vec3 {
    pb::Vec3 { x, y, z }
}

#[tokio::test]
async fn shared_hands_plan_on_ycb_views_with_joints_inside_limits() {
    let dir = graspd_testkit::testdata_dir().join("hands");
    let flags: Vec<String> = HANDS
        .iter()
        .flat_map(|(name, file)| {
            [
                "--import-hand".to_string(),
                format!("{name}={}", dir.join(file).display()),
            ]
        })
        .collect();
    let flags: Vec<&str> = flags.iter().map(String::as_str).collect();
    let server = Server::start_with(&flags);
    let mut grpc = server.grpc().await;
    for (name, file) in HANDS {
        let model = KinematicHand::from_mjcf_file(dir.join(file)).unwrap();
        let mut feasible = 0;
        for object in [
            Object::MustardBottle,
            Object::ChipsCan,
            Object::TomatoSoupCan,
            Object::Apple,
        ] {
            let view = standard_view(object, 2000, 1);
            let vp = view.viewpoint;
            let pl = view.support_plane;
            let request = pb::PlanGraspRequest {
                input: Some(pb::plan_grasp_request::Input::Cloud(pb::PointCloud {
                    points: packed(&view.object_cloud().points),
                    normals: Vec::new(),
                    frame_id: "world".into(),
                })),
                hand: Some(pb::plan_grasp_request::Hand::HandName(name.into())),
                options: Some(pb::PlannerOptions {
                    seed: Some(1),
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
            };
            let plan = grpc
                .plan_grasp(request)
                .await
                .unwrap_or_else(|e| panic!("{name} {object}: {e}"))
                .into_inner();
            let what = format!("{name} on {object}");
            assert_eq!(plan.joints.len(), model.tree.joints.len(), "{what}");
            for (j, joint) in plan.joints.iter().zip(&model.tree.joints) {
                assert_eq!(j.name, joint.name, "{what}");
                let (lo, hi) = joint.limits();
                assert!(
                    j.angle >= lo - 1e-9 && j.angle <= hi + 1e-9,
                    "{what}: {} = {} outside [{lo}, {hi}]",
                    j.name,
                    j.angle
                );
            }
            for c in &plan.contacts {
                assert!(
                    c.ik_residual.is_some(),
                    "{what}: {} without a residual",
                    c.finger
                );
            }
            let collision = plan.collision.unwrap();
            println!(
                "{what}: feasible={} residuals={:?} final_plane_clearance={:?} reason={:?}",
                plan.feasible,
                plan.contacts
                    .iter()
                    .map(|c| c.ik_residual)
                    .collect::<Vec<_>>(),
                collision.final_plane_clearance,
                plan.infeasible_reason
            );
            if plan.feasible {
                feasible += 1;
                for c in &plan.contacts {
                    assert!(c.ik_residual.is_none_or(|r| r <= 0.005), "{what}: {c:?}");
                }
                let clearance = collision.final_plane_clearance.unwrap();
                assert!(
                    clearance >= -0.001,
                    "{what}: {clearance} m through the table"
                );
                // A linked gripper's second finger may push the object before both touch; the
                // plan then says so, and at the grasp it is inside the object's points by that.
                let pushes = plan
                    .warnings
                    .iter()
                    .any(|w| w.contains("linked fingers push"));
                assert!(
                    collision.final_points_in_collision < 3 || pushes,
                    "{what}: {collision:?}"
                );
            } else {
                assert!(plan.infeasible_reason.is_some(), "{what}");
            }
        }
        assert!(
            feasible >= 1,
            "{name}: no feasible plan on the four objects"
        );
    }
}

/// `candidates = 3` for the Allegro hand on the tomato soup can: the plan carries its pre-grasp
/// and squeeze joints, a unit approach and up to three ranked candidates, the first being the
/// plan itself; REST answers the same plan as gRPC, field for field.
#[tokio::test]
async fn candidates_pregrasp_and_squeeze_come_back_the_same_over_grpc_and_rest() {
    let dir = graspd_testkit::testdata_dir().join("hands");
    let import = format!(
        "allegro={}",
        dir.join("wonik_allegro/right_hand.xml").display()
    );
    let server = Server::start_with(&["--import-hand", &import]);
    let view = standard_view(Object::TomatoSoupCan, 2000, 1);
    let points: Vec<_> = view
        .object_cloud()
        .points
        .iter()
        .map(|p| p.map(|v| v as f32 as f64))
        .collect();
    let bytes = packed(&points);
    let vp = view.viewpoint.map(|v| v as f32 as f64);
    let request = pb::PlanGraspRequest {
        input: Some(pb::plan_grasp_request::Input::Cloud(pb::PointCloud {
            points: bytes.clone(),
            normals: Vec::new(),
            frame_id: "world".into(),
        })),
        hand: Some(pb::plan_grasp_request::Hand::HandName("allegro".into())),
        options: Some(pb::PlannerOptions {
            seed: Some(2),
            candidates: Some(3),
            ..Default::default()
        }),
        hints: Some(pb::PlanHints {
            support_plane: Some(pb::Plane {
                normal: Some(v3(0.0, 0.0, 1.0)),
                offset: 0.0,
            }),
            viewpoint: Some(v3(vp.x, vp.y, vp.z)),
            ..Default::default()
        }),
        output: None,
        extra_views: Vec::new(),
    };
    let reply = server
        .grpc()
        .await
        .plan_grasp(request)
        .await
        .unwrap()
        .into_inner();
    assert_eq!(reply.pregrasp_joints.len(), reply.joints.len());
    assert_eq!(reply.squeeze_joints.len(), reply.joints.len());
    let a = reply.approach.unwrap();
    assert!(((a.x * a.x + a.y * a.y + a.z * a.z).sqrt() - 1.0).abs() < 1e-9);
    assert!((1..=3).contains(&reply.candidates.len()));
    assert_eq!(reply.candidates[0].joints, reply.joints);
    assert_eq!(reply.candidates[0].squeeze_joints, reply.squeeze_joints);
    let grpc = plan_from_proto(reply).unwrap();
    let json = serde_json::json!({
        "cloud": {"points": base64(&bytes)},
        "hand_name": "allegro",
        "options": {"seed": 2, "candidates": 3},
        "hints": {"support_plane": {"normal": [0, 0, 1], "offset": 0}, "viewpoint": [vp.x, vp.y, vp.z]},
    });
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&json)
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let rest: serde_json::Value = response.json().await.unwrap();
    assert!(rest["candidates"].as_array().is_some_and(|c| !c.is_empty()));
    assert!(
        rest["squeeze_joints"]
            .as_array()
            .is_some_and(|j| !j.is_empty())
    );
    let from_grpc = serde_json::to_value(PlanResponseJson::from(&grpc)).unwrap();
    assert_eq!(without_timings(rest), without_timings(from_grpc));
}
