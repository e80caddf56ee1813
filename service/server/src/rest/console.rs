//! The web console (issue 20): `GET /` is a page that plans on a cloud file and shows the plan
//! in 3D — the scene of `POST /v1/plan?format=glb` drawn with three.js, the figures of the JSON
//! plan beside it. Its files (`service/server/console/`, three.js 0.187.0 from npm with its MIT
//! licence) are built into the binary: a deployment needs no network, and nothing is fetched from
//! a CDN. The page and its files are open without a token (they hold no data); the page sends
//! the token the user types with its API calls.

use axum::extract::Path;
use axum::http::StatusCode;
use axum::http::header::{CACHE_CONTROL, CONTENT_TYPE};
use axum::response::{IntoResponse, Response};

/// The console's files by their path under `/console/`, with their content type.
const FILES: &[(&str, &str, &[u8])] = &[
    (
        "console.js",
        "text/javascript",
        include_bytes!("../../console/console.js"),
    ),
    (
        "console.css",
        "text/css",
        include_bytes!("../../console/console.css"),
    ),
    (
        "example.ply",
        "application/octet-stream",
        include_bytes!("../../../../examples/tomato_soup_can.ply"),
    ),
    (
        "vendor/three/three.module.js",
        "text/javascript",
        include_bytes!("../../console/vendor/three/three.module.js"),
    ),
    (
        "vendor/three/three.core.js",
        "text/javascript",
        include_bytes!("../../console/vendor/three/three.core.js"),
    ),
    (
        "vendor/three/LICENSE",
        "text/plain; charset=utf-8",
        include_bytes!("../../console/vendor/three/LICENSE"),
    ),
    (
        "vendor/three/addons/controls/OrbitControls.js",
        "text/javascript",
        include_bytes!("../../console/vendor/three/addons/controls/OrbitControls.js"),
    ),
    (
        "vendor/three/addons/loaders/GLTFLoader.js",
        "text/javascript",
        include_bytes!("../../console/vendor/three/addons/loaders/GLTFLoader.js"),
    ),
    (
        "vendor/three/addons/utils/BufferGeometryUtils.js",
        "text/javascript",
        include_bytes!("../../console/vendor/three/addons/utils/BufferGeometryUtils.js"),
    ),
    (
        "vendor/three/addons/utils/SkeletonUtils.js",
        "text/javascript",
        include_bytes!("../../console/vendor/three/addons/utils/SkeletonUtils.js"),
    ),
];

const INDEX: &[u8] = include_bytes!("../../console/index.html");

/// The console page.
#[utoipa::path(
    get,
    path = "/",
    tag = "operations",
    summary = "The web console",
    security(()),
    responses((status = 200, description = "The console page: plan on a PLY/PCD cloud and look at the plan in 3D", content_type = "text/html", body = String))
)]
pub async fn index() -> Response {
    (
        [
            (CONTENT_TYPE, "text/html; charset=utf-8"),
            (CACHE_CONTROL, "no-cache"),
        ],
        INDEX,
    )
        .into_response()
}

/// One of the console's files.
#[utoipa::path(
    get,
    path = "/console/{path}",
    tag = "operations",
    summary = "A file of the web console",
    security(()),
    params(("path" = String, Path, description = "console.js, console.css, example.ply or vendor/three/…")),
    responses(
        (status = 200, description = "The file"),
        (status = 404, description = "No such file of the console"),
    )
)]
pub async fn file(Path(path): Path<String>) -> Response {
    match FILES.iter().find(|(p, _, _)| *p == path) {
        Some((_, content_type, bytes)) => (
            [
                (CONTENT_TYPE, *content_type),
                (CACHE_CONTROL, "max-age=3600"),
            ],
            *bytes,
        )
            .into_response(),
        None => (StatusCode::NOT_FOUND, "no such file of the console").into_response(),
    }
}
