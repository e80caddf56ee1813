//! `GET /openapi.json` against the real server: an OpenAPI 3.1 document that describes exactly
//! the routes the router serves, open without a token, whose plan schemas name the key fields
//! and agree with a real plan answer.

use graspd_e2e::{Server, http, json_request};
use serde_json::Value;
use std::collections::BTreeSet;

/// Every REST route and its methods. A route added to the router must be added here and to the
/// document: the test compares this list, the router's source and the document both ways.
const ROUTES: &[(&str, &str)] = &[
    ("POST", "/v1/plan"),
    ("POST", "/v1/reach"),
    ("GET", "/v1/hands"),
    ("POST", "/v1/hands"),
    ("GET", "/v1/hands/{name}"),
    ("GET", "/v1/hands/{name}/synergies"),
    ("GET", "/v1/stabilize"),
    ("POST", "/v1/tactile/analyze"),
    ("GET", "/v1/tactile/calibrations"),
    ("POST", "/v1/tactile/calibrations"),
    ("GET", "/v1/tactile/calibrations/{name}"),
    ("DELETE", "/v1/tactile/calibrations/{name}"),
    ("GET", "/healthz"),
    ("GET", "/readyz"),
    ("GET", "/metrics"),
    ("GET", "/openapi.json"),
    ("GET", "/"),
    ("GET", "/console/{path}"),
];

const TOKEN: &str = "openapi-test-token";

fn listed() -> BTreeSet<(String, String)> {
    ROUTES
        .iter()
        .map(|(m, p)| (m.to_string(), p.to_string()))
        .collect()
}

/// The `.route("path", get(..).post(..))` calls of the router's source.
fn routes_in_source() -> BTreeSet<(String, String)> {
    let source = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../service/server/src/rest/mod.rs"),
    )
    .expect("the router's source");
    let mut routes = BTreeSet::new();
    for call in source.split(".route(").skip(1) {
        // axum's catch-all `{*name}` is OpenAPI's `{name}`.
        let path = call
            .split('"')
            .nth(1)
            .expect("a quoted path")
            .replace("{*", "{");
        // The method router: up to the end of the call (the next `.route(`/`.fallback(`).
        let methods = call.split(".fallback(").next().unwrap_or(call);
        let bytes = methods.as_bytes();
        for method in ["get", "post", "put", "delete", "patch", "head", "options"] {
            let needle = format!("{method}(");
            let mut from = 0;
            while let Some(i) = methods[from..].find(&needle) {
                let at = from + i;
                let before = at.checked_sub(1).map(|j| bytes[j]);
                if !matches!(before, Some(b) if b.is_ascii_alphanumeric() || b == b'_' || b == b':')
                {
                    routes.insert((method.to_ascii_uppercase(), path.clone()));
                }
                from = at + needle.len();
            }
        }
    }
    routes
}

fn routes_in_document(doc: &Value) -> BTreeSet<(String, String)> {
    let mut routes = BTreeSet::new();
    for (path, item) in doc["paths"].as_object().expect("paths") {
        for method in ["get", "post", "put", "delete", "patch", "head", "options"] {
            if item.get(method).is_some() {
                routes.insert((method.to_ascii_uppercase(), path.clone()));
            }
        }
    }
    routes
}

fn schema<'a>(doc: &'a Value, name: &str) -> &'a Value {
    let s = &doc["components"]["schemas"][name];
    assert!(s.is_object(), "schema {name} missing");
    s
}

fn property_names(schema: &Value) -> BTreeSet<String> {
    schema["properties"]
        .as_object()
        .expect("properties")
        .keys()
        .cloned()
        .collect()
}

async fn fetch_document(server: &Server) -> Value {
    // Open without a token, like the probes and /metrics.
    let response = http()
        .get(server.rest_url("/openapi.json"))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let content_type = response.headers()["content-type"]
        .to_str()
        .unwrap()
        .to_string();
    assert!(
        content_type.starts_with("application/json"),
        "{content_type}"
    );
    response.json().await.expect("JSON")
}

#[tokio::test]
async fn the_document_describes_every_route_and_agrees_with_a_real_plan() {
    let server = Server::start_with(&["--auth-token", TOKEN]);
    let doc = fetch_document(&server).await;

    let version = doc["openapi"].as_str().expect("openapi");
    assert!(version.starts_with("3."), "{version}");
    assert!(version.starts_with("3.1"), "{version}");
    assert!(doc["info"]["title"].is_string());

    // The routes: the list here, the router's source and the document agree both ways.
    let listed = listed();
    let source = routes_in_source();
    let documented = routes_in_document(&doc);
    assert_eq!(
        source, listed,
        "the router serves routes this test does not list (or the reverse)"
    );
    assert_eq!(
        documented, listed,
        "the document and the router's routes differ"
    );
    // The server really serves each listed route (none falls to the not-found fallback).
    for (method, path) in ROUTES {
        let url = server.rest_url(&path.replace("{name}", "shadow"));
        let request = match *method {
            "GET" => http().get(url),
            "POST" => http().post(url).json(&serde_json::json!({})),
            "DELETE" => http().delete(url),
            other => panic!("{other}"),
        };
        let response = request.bearer_auth(TOKEN).send().await.unwrap();
        let status = response.status();
        let body = response.text().await.unwrap_or_default();
        assert!(
            !(status == 404 && body.contains("no route")),
            "{method} {path}: {status} {body}"
        );
    }

    // Bearer: declared, and optional (a server without tokens needs none).
    assert_eq!(
        doc["components"]["securitySchemes"]["bearer"]["scheme"], "bearer",
        "{}",
        doc["components"]["securitySchemes"]
    );
    let security = doc["security"].as_array().expect("global security");
    assert!(security.iter().any(|r| r.get("bearer").is_some()));
    assert!(
        security
            .iter()
            .any(|r| r.as_object().is_some_and(|o| o.is_empty()))
    );

    // The plan route's content and answers.
    let plan = &doc["paths"]["/v1/plan"]["post"];
    for content_type in ["application/json", "multipart/form-data"] {
        assert!(
            plan["requestBody"]["content"][content_type].is_object(),
            "plan request {content_type}"
        );
    }
    for content_type in ["application/json", "image/png"] {
        assert!(
            plan["responses"]["200"]["content"][content_type].is_object(),
            "plan 200 {content_type}"
        );
    }
    for status in ["400", "401", "404", "413", "503", "504"] {
        assert_eq!(
            plan["responses"][status]["content"]["application/json"]["schema"]["$ref"],
            "#/components/schemas/ErrorJson",
            "plan {status}"
        );
    }
    assert!(
        plan["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["name"] == "format" && p["in"] == "query")
    );
    let multipart = schema(&doc, "PlanUpload");
    for part in ["cloud", "color", "depth", "request"] {
        assert!(
            multipart["properties"][part].is_object(),
            "multipart part {part}"
        );
    }
    assert!(doc["paths"]["/v1/stabilize"]["get"]["responses"]["101"].is_object());
    for content_type in ["application/json", "text/csv", "multipart/form-data"] {
        assert!(
            doc["paths"]["/v1/tactile/analyze"]["post"]["requestBody"]["content"][content_type]
                .is_object(),
            "analyze {content_type}"
        );
    }

    // Key fields of the plan schemas and the error schema.
    let request = property_names(schema(&doc, "PlanRequestJson"));
    for field in ["rgbd", "cloud", "hand_name", "hints", "output"] {
        assert!(request.contains(field), "PlanRequestJson lacks {field}");
    }
    let response_schema = schema(&doc, "PlanResponseJson");
    let declared = property_names(response_schema);
    for field in ["grasp_type", "contacts", "perception"] {
        assert!(declared.contains(field), "PlanResponseJson lacks {field}");
    }
    let error = schema(&doc, "ErrorJson");
    assert_eq!(error["required"], serde_json::json!(["error"]));
    let detail = schema(&doc, "ErrorDetailJson");
    assert_eq!(
        property_names(detail),
        ["code", "field", "message"].map(String::from).into()
    );

    // A real plan answer carries every required property and no undeclared one.
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .bearer_auth(TOKEN)
        .json(&json_request("shadow", 5))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    let answer: Value = response.json().await.unwrap();
    let answered: BTreeSet<String> = answer.as_object().unwrap().keys().cloned().collect();
    let required: BTreeSet<String> = response_schema["required"]
        .as_array()
        .expect("required")
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    assert!(required.contains("grasp_type") && required.contains("contacts"));
    let missing: Vec<_> = required.difference(&answered).collect();
    assert!(missing.is_empty(), "required but not answered: {missing:?}");
    let undeclared: Vec<_> = answered.difference(&declared).collect();
    assert!(
        undeclared.is_empty(),
        "answered but not declared: {undeclared:?}"
    );

    // An error answer has the declared shape.
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .bearer_auth(TOKEN)
        .json(&serde_json::json!({"hand_name": "shadow"}))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 400);
    let body: Value = response.json().await.unwrap();
    let keys: BTreeSet<String> = body["error"].as_object().unwrap().keys().cloned().collect();
    assert_eq!(keys, property_names(detail));
}
