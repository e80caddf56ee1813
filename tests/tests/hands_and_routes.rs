//! ListHands / GetHand round trips over gRPC and REST, registration without a model, health and
//! unknown routes.

use graspd_api::convert::hand_from_proto;
use graspd_core::HandDescription;
use graspd_e2e::{Server, http, rest_error};
use graspd_proto::v1 as pb;
use tonic::Code;

#[tokio::test]
async fn list_and_get_hands_agree_across_transports() {
    let server = Server::start();
    let mut grpc = server.grpc().await;
    let listed = grpc
        .list_hands(pb::ListHandsRequest {})
        .await
        .unwrap()
        .into_inner();
    let grpc_hands: Vec<HandDescription> = listed
        .hands
        .into_iter()
        .map(|h| hand_from_proto(h, "hand").unwrap())
        .collect();
    let names: Vec<&str> = grpc_hands.iter().map(|h| h.name.as_str()).collect();
    assert_eq!(names, ["barrett", "parallel_gripper", "shadow"]);

    let rest: serde_json::Value = http()
        .get(server.rest_url("/v1/hands"))
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    let rest_hands: Vec<HandDescription> = serde_json::from_value(rest["hands"].clone()).unwrap();
    assert_eq!(rest_hands, grpc_hands);

    for hand in &grpc_hands {
        let got = grpc
            .get_hand(pb::GetHandRequest {
                name: hand.name.clone(),
            })
            .await
            .unwrap()
            .into_inner();
        assert_eq!(&hand_from_proto(got.hand.unwrap(), "hand").unwrap(), hand);
        assert_eq!(got.realisable_types.len(), hand.realisable_types().len());

        let rest: serde_json::Value = http()
            .get(server.rest_url(&format!("/v1/hands/{}", hand.name)))
            .send()
            .await
            .unwrap()
            .json()
            .await
            .unwrap();
        let rest_hand: HandDescription = serde_json::from_value(rest["hand"].clone()).unwrap();
        assert_eq!(&rest_hand, hand);
        let types: Vec<String> = hand
            .realisable_types()
            .iter()
            .map(|t| t.name().to_string())
            .collect();
        assert_eq!(rest["realisable_types"], serde_json::json!(types));
    }
}

#[tokio::test]
async fn unknown_hand_is_not_found_and_names_the_field() {
    let server = Server::start();
    let e = server
        .grpc()
        .await
        .get_hand(pb::GetHandRequest { name: "foo".into() })
        .await
        .unwrap_err();
    assert_eq!(e.code(), Code::NotFound);
    assert!(
        e.message().contains("name: unknown hand 'foo'"),
        "{}",
        e.message()
    );
    assert!(e.message().contains("barrett, parallel_gripper, shadow"));

    let response = http()
        .get(server.rest_url("/v1/hands/foo"))
        .send()
        .await
        .unwrap();
    let (status, code, field, message) = rest_error(response).await;
    assert_eq!((status, code.as_str()), (404, "not_found"));
    assert_eq!(field.as_deref(), Some("name"));
    assert!(message.contains("unknown hand 'foo'"));
}

/// RegisterHand and POST /v1/hands without a model name the missing field.
#[tokio::test]
async fn registration_without_a_model_names_the_field() {
    let server = Server::start();
    let e = server
        .grpc()
        .await
        .register_hand(pb::RegisterHandRequest::default())
        .await
        .unwrap_err();
    assert_eq!(e.code(), Code::InvalidArgument);
    assert!(e.message().starts_with("model: missing"), "{}", e.message());
    let (status, code, field, _) = rest_error(
        http()
            .post(server.rest_url("/v1/hands"))
            .json(&serde_json::json!({}))
            .send()
            .await
            .unwrap(),
    )
    .await;
    assert_eq!((status, code.as_str()), (400, "invalid_argument"));
    assert_eq!(field.as_deref(), Some("model"));
}

#[tokio::test]
async fn health_and_unknown_routes() {
    let server = Server::start();
    let response = http()
        .get(server.rest_url("/healthz"))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let body: serde_json::Value = response.json().await.unwrap();
    assert_eq!(body, serde_json::json!({"status": "ok"}));

    let response = http()
        .get(server.rest_url("/v2/nothing"))
        .send()
        .await
        .unwrap();
    let (status, code, _, message) = rest_error(response).await;
    assert_eq!((status, code.as_str()), (404, "not_found"));
    assert!(message.contains("/v2/nothing"));
}
