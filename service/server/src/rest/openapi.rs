//! `GET /openapi.json`: the OpenAPI 3.1 document of the REST routes, generated from the handlers'
//! `#[utoipa::path]` attributes and the DTOs of [`super::json`] (`ToSchema`).
//! The domain types that the JSON carries as they are are described in [`super::schemas`]; the
//! multipart bodies beside their handlers.

use super::json;
use axum::Json;
use std::sync::OnceLock;
use utoipa::openapi::OpenApi as Document;
use utoipa::openapi::security::{HttpAuthScheme, HttpBuilder, SecurityRequirement, SecurityScheme};
use utoipa::{Modify, OpenApi};

/// The document, built once.
pub fn document() -> &'static Document {
    static DOC: OnceLock<Document> = OnceLock::new();
    DOC.get_or_init(ApiDoc::openapi)
}

/// `GET /openapi.json`.
#[utoipa::path(
    get,
    path = "/openapi.json",
    tag = "operations",
    security(()),
    responses((status = 200, description = "This OpenAPI 3.1 document", content_type = "application/json", body = Object))
)]
pub async fn openapi_json() -> Json<&'static Document> {
    Json(document())
}

#[derive(OpenApi)]
#[openapi(
    info(
        title = "graspd REST API",
        description = "Grasp planning (point clouds, RGB-D frames), the hand catalog and tactile stabilization. The same operations as the gRPC package graspd.v1, in JSON with the proto's snake_case field names. Every non-2xx answer has the body {\"error\": {\"code\", \"field\", \"message\"}} (ErrorJson). See docs/api.md and the README's API section.",
    ),
    paths(
        super::plan::plan,
        super::reach::reach,
        super::hands::list,
        super::hands::get,
        super::hands::synergies,
        super::hands::register,
        super::stabilize::stabilize,
        super::tactile::analyze,
        super::calibrations::calibrate,
        super::calibrations::list,
        super::calibrations::get,
        super::calibrations::delete,
        super::health,
        super::ready,
        super::metrics_text,
        openapi_json,
        super::console::index,
        super::console::file,
    ),
    components(schemas(json::ErrorJson, json::StabilizeMessageJson)),
    modifiers(&Security),
    tags(
        (name = "plan", description = "Grasp planning"),
        (name = "hands", description = "The hand catalog"),
        (name = "tactile", description = "Tactile stabilization"),
        (name = "operations", description = "Probes, metrics, this document and the web console; open without a token"),
    )
)]
struct ApiDoc;

/// The bearer scheme. It applies only when the server is configured with tokens
/// (`--auth-token`, `auth_tokens`, `auth_tokens_file`); the probes, `/metrics` and `/openapi.json` are always open.
struct Security;

impl Modify for Security {
    fn modify(&self, openapi: &mut Document) {
        let components = openapi.components.get_or_insert_with(Default::default);
        components.add_security_scheme(
            "bearer",
            SecurityScheme::Http(
                HttpBuilder::new()
                    .scheme(HttpAuthScheme::Bearer)
                    .description(Some(
                        "`authorization: Bearer <token>`: required only when the server is configured with tokens; otherwise every route is open. Refused with 401 and the error body.",
                    ))
                    .build(),
            ),
        );
        // Optional: either the bearer token or nothing (a server without tokens).
        openapi.security = Some(vec![
            SecurityRequirement::new("bearer", Vec::<String>::new()),
            SecurityRequirement::default(),
        ]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_document_lists_every_route_and_the_domain_schemas() {
        let doc = serde_json::to_value(document()).unwrap();
        assert!(doc["openapi"].as_str().unwrap().starts_with("3.1"));
        for path in [
            "/v1/plan",
            "/v1/hands",
            "/v1/hands/{name}",
            "/v1/hands/{name}/synergies",
            "/v1/stabilize",
            "/v1/tactile/analyze",
            "/healthz",
            "/readyz",
            "/metrics",
            "/openapi.json",
        ] {
            assert!(doc["paths"][path].is_object(), "{path}");
        }
        let schemas = &doc["components"]["schemas"];
        assert_eq!(
            schemas["GraspType"]["enum"][0], "large_wrap",
            "{}",
            schemas["GraspType"]
        );
        assert_eq!(schemas["HandPart"]["enum"][0], "TT");
        assert!(schemas["StageStats"]["properties"]["iterations"]["type"] == "integer");
        assert!(schemas["Quality"]["properties"]["gii"]["type"] == "number");
        for name in [
            "PlanRequestJson",
            "PlanResponseJson",
            "ErrorJson",
            "PlannerOptions",
            "HandDescription",
            "FrameResult",
            "Vec3Input",
            "Vec3List",
        ] {
            assert!(schemas[name].is_object(), "{name} missing");
        }
    }
}
