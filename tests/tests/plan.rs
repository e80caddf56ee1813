//! Planning through the real server: a valid plan via gRPC, REST JSON and multipart upload, and
//! the same plan through both transports for the same seed.

use graspd_api::convert::plan_from_proto;
use graspd_api::json::PlanResponseJson;
use graspd_core::GraspType;
use graspd_core::cloud::io::write_ply_binary;
use graspd_e2e::{Server, cylinder, grpc_request, http, json_request, without_timings};
use graspd_proto::v1 as pb;

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6
}

#[tokio::test]
async fn same_request_and_seed_give_the_same_plan_over_grpc_and_rest() {
    let server = Server::start();
    for (hand, seed) in [("shadow", 7), ("barrett", 3), ("parallel_gripper", 11)] {
        let grpc = server
            .grpc()
            .await
            .plan_grasp(grpc_request(hand, seed))
            .await
            .unwrap_or_else(|e| panic!("{hand}: {e}"))
            .into_inner();
        let grpc = plan_from_proto(grpc).unwrap();
        let response = http()
            .post(server.rest_url("/v1/plan"))
            .json(&json_request(hand, seed))
            .send()
            .await
            .unwrap();
        assert_eq!(response.status(), 200);
        let rest_value: serde_json::Value = response.json().await.unwrap();
        let rest: PlanResponseJson = serde_json::from_value(rest_value.clone()).unwrap();

        assert_eq!(rest.hand, hand);
        assert_eq!(rest.grasp_type, grpc.grasp_type, "{hand}");
        assert_eq!(rest.seed, seed);
        assert_eq!(rest.contacts.len(), grpc.contacts.len(), "{hand}");
        for (r, g) in rest.contacts.iter().zip(&grpc.contacts) {
            assert_eq!((r.finger.as_str(), r.part), (g.finger.as_str(), g.part));
            assert!(
                close(r.position.x, g.position.x)
                    && close(r.position.y, g.position.y)
                    && close(r.position.z, g.position.z),
                "{hand}: contact {r:?} vs {g:?}"
            );
        }
        let (rp, gp) = (&rest.hand_pose, &grpc.hand_pose);
        let gq = gp.orientation;
        assert!(
            close(rp.position.x, gp.position.x)
                && close(rp.position.y, gp.position.y)
                && close(rp.position.z, gp.position.z)
                && close(rp.orientation.x, gq.i)
                && close(rp.orientation.y, gq.j)
                && close(rp.orientation.z, gq.k)
                && close(rp.orientation.w, gq.w),
            "{hand}: pose {rp:?} vs {gp:?}"
        );
        // Everything but the wall-clock times is identical.
        let grpc_value = serde_json::to_value(PlanResponseJson::from(&grpc)).unwrap();
        assert_eq!(
            without_timings(rest_value),
            without_timings(grpc_value),
            "{hand}"
        );
    }
}

#[tokio::test]
async fn a_valid_grpc_plan_carries_the_whole_answer() {
    let server = Server::start();
    let mut request = grpc_request("shadow", 5);
    request.hints.as_mut().unwrap().grasp_type = pb::GraspType::Tripod as i32;
    let response = server
        .grpc()
        .await
        .plan_grasp(request)
        .await
        .unwrap()
        .into_inner();
    assert_eq!(response.type_probabilities.len(), 6);
    assert_eq!(response.plane_source, "request");
    let plan = plan_from_proto(response).unwrap();
    assert_eq!(plan.grasp_type, GraspType::Tripod);
    assert_eq!(plan.requested_type, GraspType::Tripod);
    assert_eq!(plan.contacts.len(), 3, "shadow's tripod has three contacts");
    assert!((plan.hand_pose.orientation.norm() - 1.0).abs() < 1e-9);
    assert!(plan.quality.gii.is_finite());
    assert!(plan.feasible || plan.infeasible_reason.is_some());
    assert!(plan.stage1.iterations > 0 && plan.stage2.iterations > 0);
    assert!(plan.timings.total > 0.0);
}

#[tokio::test]
async fn rest_accepts_json_arrays_and_multipart_uploads() {
    let server = Server::start();
    let points = cylinder(2000);
    let arrays: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
    let mut body = json_request("barrett", 2);
    body["cloud"]["points"] = serde_json::json!(arrays);
    let from_arrays: serde_json::Value = http()
        .post(server.rest_url("/v1/plan"))
        .json(&body)
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    assert_eq!(from_arrays["hand"], "barrett", "{from_arrays}");

    let form = reqwest::multipart::Form::new()
        .part(
            "cloud",
            reqwest::multipart::Part::bytes(write_ply_binary(&points, None)).file_name("cylinder.ply"),
        )
        .text(
            "request",
            r#"{"hand_name":"barrett","options":{"seed":2},"hints":{"support_plane":{"normal":[0,0,1],"offset":0}}}"#,
        );
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .multipart(form)
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let from_file: serde_json::Value = response.json().await.unwrap();
    // The file carries float32 like the base64 and array forms: the same plan.
    assert_eq!(without_timings(from_file), without_timings(from_arrays));
}

#[tokio::test]
async fn plans_are_deterministic_for_a_seed() {
    let server = Server::start();
    let mut grpc = server.grpc().await;
    let a = grpc
        .plan_grasp(grpc_request("shadow", 42))
        .await
        .unwrap()
        .into_inner();
    let b = grpc
        .plan_grasp(grpc_request("shadow", 42))
        .await
        .unwrap()
        .into_inner();
    assert_eq!(a.contacts, b.contacts);
    assert_eq!(a.hand_pose, b.hand_pose);
}
