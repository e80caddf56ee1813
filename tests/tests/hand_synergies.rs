//! A hand's posture synergies over both transports (issue 19 part 1): the real binary, a shared
//! MJCF hand imported at start, `GET /v1/hands/{name}/synergies` and `GetHandSynergies` give the
//! same posture space, a unit, ordered, reconstructing one over the model's joints; a hand
//! without kinematics and an unknown hand are refused naming `name`, and the server goes on;
//! asked again, the hand has the same space.

use graspd_core::hand::kinematics::KinematicHand;
use graspd_e2e::{Server, http, refused_naming, rest_error};
use graspd_proto::v1 as pb;
use tonic::Code;

const HAND: (&str, &str) = ("barrett_mjcf", "barrett/wam_barrett_gripper.xml");

#[tokio::test]
async fn synergies_of_an_imported_hand_agree_over_grpc_and_rest() {
    let file = graspd_testkit::testdata_dir().join("hands").join(HAND.1);
    let import = format!("{}={}", HAND.0, file.display());
    let server = Server::start_with(&["--import-hand", &import]);
    let model = KinematicHand::from_mjcf_file(&file).unwrap();
    let joints: Vec<String> = model.tree.joints.iter().map(|j| j.name.clone()).collect();

    let mut grpc = server.grpc().await;
    let got = grpc
        .get_hand_synergies(pb::GetHandSynergiesRequest {
            name: HAND.0.into(),
        })
        .await
        .unwrap()
        .into_inner();
    assert_eq!(got.hand, HAND.0);
    assert_eq!(got.joints, joints);
    assert_eq!(got.mean.len(), joints.len());
    assert!(got.postures >= 2 && got.postures <= got.plans, "{got:?}");
    assert!(!got.components.is_empty() && !got.centres.is_empty());
    let mut explained = 0.0;
    for (k, c) in got.components.iter().enumerate() {
        let norm: f64 = c.direction.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-9, "component {k} has length {norm}");
        if k > 0 {
            assert!(got.components[k - 1].variance >= c.variance);
        }
        for d in &got.components[..k] {
            let dot: f64 = d
                .direction
                .iter()
                .zip(&c.direction)
                .map(|(a, b)| a * b)
                .sum();
            assert!(dot.abs() < 1e-9, "components not orthogonal: {dot}");
        }
        explained += c.explained;
    }
    assert!((explained - 1.0).abs() < 1e-9, "{explained}");
    for c in &got.centres {
        assert_eq!(c.amplitudes.len(), got.components.len());
        assert!(c.postures >= 1);
    }

    let rest: serde_json::Value = http()
        .get(server.rest_url(&format!("/v1/hands/{}/synergies", HAND.0)))
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    assert_eq!(rest["joints"], serde_json::json!(got.joints));
    assert_eq!(rest["mean"], serde_json::json!(got.mean));
    assert_eq!(rest["postures"], got.postures);
    assert_eq!(rest["plans"], got.plans);
    assert_eq!(rest["seed"], 0);
    let rest_components = rest["components"].as_array().unwrap();
    assert_eq!(rest_components.len(), got.components.len());
    for (r, g) in rest_components.iter().zip(&got.components) {
        assert_eq!(r["direction"], serde_json::json!(g.direction));
        assert_eq!(r["explained"], serde_json::json!(g.explained));
    }
    let types: Vec<&str> = rest["centres"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["grasp_type"].as_str().unwrap())
        .collect();
    assert_eq!(types.len(), got.centres.len());
    assert!(
        types.iter().all(|t| {
            [
                "large_wrap",
                "small_wrap",
                "power",
                "pinch",
                "precision",
                "tripod",
            ]
            .contains(t)
        }),
        "{types:?}"
    );

    // The built-in hands are parametric (no joints); an unknown hand is not there.
    let message = refused_naming(
        http()
            .get(server.rest_url("/v1/hands/shadow/synergies"))
            .send()
            .await
            .unwrap(),
        "name",
    )
    .await;
    assert!(message.contains("no kinematics"), "{message}");
    let (status, code, field, _) = rest_error(
        http()
            .get(server.rest_url("/v1/hands/no_such_hand/synergies"))
            .send()
            .await
            .unwrap(),
    )
    .await;
    assert_eq!(
        (status, code.as_str(), field.as_deref()),
        (404, "not_found", Some("name"))
    );
    let e = grpc
        .get_hand_synergies(pb::GetHandSynergiesRequest {
            name: "shadow".into(),
        })
        .await
        .unwrap_err();
    assert_eq!(e.code(), Code::InvalidArgument, "{e}");
    let e = grpc
        .get_hand_synergies(pb::GetHandSynergiesRequest {
            name: "no_such_hand".into(),
        })
        .await
        .unwrap_err();
    assert_eq!(e.code(), Code::NotFound, "{e}");

    // One answer per hand: the same again (kept; that a replaced hand's are fitted anew is
    // register_hand.rs's test).
    let again = grpc
        .get_hand_synergies(pb::GetHandSynergiesRequest {
            name: HAND.0.into(),
        })
        .await
        .unwrap()
        .into_inner();
    assert_eq!(again, got);
}
