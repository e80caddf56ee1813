//! Tactile calibrations end to end (issue 16): Calibrate over gRPC on real BioTac recordings
//! (../shared/testdata/tactile/biotac_slide, measurement only) with a calibrations directory;
//! after a restart on that directory the calibration is listed over REST and a session naming
//! it reports the material of a recording it was not fitted on; bad calibration inputs are
//! refused naming the field and store nothing; a session that does not fit the calibration is
//! refused naming the field; DELETE removes it from disk.

use graspd_api::convert;
use graspd_api::request::{CalibrationUpload, RecordingUpload};
use graspd_core::tactile::TareConfig;
use graspd_e2e::{Server, http, refused_naming, rest_error};
use graspd_proto::v1 as pb;
use graspd_proto::v1::tactile_stabilizer_client::TactileStabilizerClient;
use serde_json::json;
use std::path::PathBuf;
use tonic::Code;

fn read(mat: &str, sample: usize, kind: &str) -> String {
    let path = graspd_testkit::testdata_dir()
        .join("tactile/biotac_slide")
        .join(mat)
        .join(format!("{mat}_{sample}_{kind}.csv"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

/// Samples 1–3 of a foam (mat17) and of the metal (mat20), labelled, with the arm's files.
fn upload(name: &str) -> CalibrationUpload {
    let mut recordings = Vec::new();
    for (mat, material) in [("mat17", "foam/styrofoam"), ("mat20", "metal")] {
        for sample in 1..=3 {
            recordings.push(RecordingUpload {
                material: Some(material.into()),
                bio_csv: read(mat, sample, "bio"),
                cw_csv: Some(read(mat, sample, "cw")),
                cv_csv: Some(read(mat, sample, "cv")),
                event: None,
                slip_direction: None,
            });
        }
    }
    CalibrationUpload {
        name: name.into(),
        replace: false,
        window_length: None,
        stride: None,
        tare: TareConfig::pretared(),
        recordings,
    }
}

fn calibrations_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("graspd-calibrations-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn listing(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.filter_map(|e| e.ok()?.file_name().into_string().ok())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// A REST analyze (multipart) of the recording `bio` with `session`: the response body, after
/// checking it is 200.
async fn analyze_csv(
    server: &Server,
    bio: String,
    session: serde_json::Value,
) -> serde_json::Value {
    let form = reqwest::multipart::Form::new()
        .part(
            "bio_csv",
            reqwest::multipart::Part::text(bio).file_name("held_out_bio.csv"),
        )
        .text("session", session.to_string());
    let response = http()
        .post(server.rest_url("/v1/tactile/analyze"))
        .multipart(form)
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    response.json().await.unwrap()
}

/// The materials a REST analyze of `bio` with the calibration reports, over frames in contact.
async fn analyze_materials(server: &Server, calibration: &str, bio: &str) -> Vec<String> {
    let session = json!({
        "fingers": [{"name": "ff", "layout": "biotac", "tare": {"pretared": true}}],
        "detector": {"calibration": calibration},
    });
    let body = analyze_csv(server, bio.to_string(), session).await;
    body["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["fingers"][0]["material"].as_str().unwrap().to_string())
        .filter(|m| m != "unknown")
        .collect()
}

#[tokio::test]
async fn a_calibration_is_fitted_stored_reloaded_and_names_the_material() {
    let dir = calibrations_dir("round-trip");
    let flags = ["--calibrations-dir", dir.to_str().unwrap()];
    {
        let server = Server::start_with(&flags);
        let mut grpc = TactileStabilizerClient::connect(server.grpc_url())
            .await
            .unwrap();
        let info = grpc
            .calibrate(convert::calibrate_request_to_proto(&upload("slide")))
            .await
            .unwrap()
            .into_inner();
        assert!(info.persisted);
        assert_eq!(
            (info.electrodes, info.window_length, info.stride),
            (19, 32, 3)
        );
        assert_eq!(info.recordings, 6);
        let labels: Vec<&str> = info
            .material_windows
            .iter()
            .map(|l| l.label.as_str())
            .collect();
        assert_eq!(labels, ["foam/styrofoam", "metal"]);
        assert!(
            info.material_windows.iter().all(|l| l.windows > 500),
            "{info:?}"
        );
        assert_eq!(info.event_windows.len(), 3);
        assert_eq!(listing(&dir), ["slide.json"]);
        let e = grpc
            .calibrate(convert::calibrate_request_to_proto(&upload("slide")))
            .await
            .unwrap_err();
        assert_eq!(e.code(), Code::AlreadyExists, "{}", e.message());
    }
    let server = Server::start_with(&flags);
    let listed: serde_json::Value = http()
        .get(server.rest_url("/v1/tactile/calibrations"))
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    assert_eq!(listed["calibrations"][0]["name"], "slide", "{listed}");
    assert_eq!(
        listed["calibrations"][0]["material_windows"][1]["label"],
        "metal"
    );
    // Held-out samples of each material: the calibration's answer in contact.
    for (mat, want) in [("mat20", "metal"), ("mat17", "foam")] {
        let materials = analyze_materials(&server, "slide", &read(mat, 15, "bio")).await;
        let right = materials.iter().filter(|m| *m == want).count();
        assert!(
            materials.len() > 400,
            "{mat}: {} frames with a material",
            materials.len()
        );
        assert!(
            right as f64 >= 0.9 * materials.len() as f64,
            "{mat}: {right} of {} frames {want}",
            materials.len()
        );
    }
    let response = http()
        .delete(server.rest_url("/v1/tactile/calibrations/slide"))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 204);
    assert!(listing(&dir).is_empty(), "{:?}", listing(&dir));
    let (status, _, field, message) = rest_error(
        http()
            .get(server.rest_url("/v1/tactile/calibrations/slide"))
            .send()
            .await
            .unwrap(),
    )
    .await;
    assert_eq!((status, field.as_deref()), (404, Some("name")), "{message}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[tokio::test]
async fn bad_calibrations_and_sessions_that_do_not_fit_are_refused_naming_the_field() {
    let dir = calibrations_dir("bad");
    let server = Server::start_with(&["--calibrations-dir", dir.to_str().unwrap()]);
    let post = |body: serde_json::Value| {
        http()
            .post(server.rest_url("/v1/tactile/calibrations"))
            .json(&body)
            .send()
    };
    let bio = read("mat20", 1, "bio");
    let rec = |material: &str| json!({"material": material, "bio_csv": bio});
    for (body, want_field, want_text) in [
        (
            json!({"name": "x", "recordings": [rec("wood"), rec("metal")]}),
            "recordings[0].material",
            "unknown material 'wood'",
        ),
        (
            json!({"name": "x", "recordings": [rec("metal/a"), rec("metal/b")]}),
            "recordings[].material",
            "one class only (metal)",
        ),
        (
            json!({"name": "x", "recordings": [rec("foam"), {"material": "metal", "bio_csv": "timestamp,tdc,tac,pdc,pac1,ele1\n1,2,3,4,5,6,\n"}]}),
            "recordings[1].readings[0].electrodes",
            "1 electrodes",
        ),
        (
            json!({"name": "x", "recordings": [rec("foam"), {"material": "metal", "bio_csv": bio, "cw_csv": "timestamp,fx,fy,fz,tx,ty,tz\n"}]}),
            "recordings[1].cw_csv",
            "both",
        ),
        (
            json!({"name": "x", "recordings": [rec("foam"), {"material": "metal", "bio_csv": bio, "event": "slide"}]}),
            "recordings[1].event",
            "unknown event 'slide'",
        ),
        (
            json!({"name": "x", "recordings": [rec("foam"), {"material": "metal", "bio_csv": bio, "slip_direction": "up"}]}),
            "recordings[1].slip_direction",
            "unknown slip direction 'up'",
        ),
        (
            json!({"name": "x", "recordings": [rec("foam"), {"material": "metal", "bio_csv": bio, "event": "slip", "cw_csv": "timestamp,fx,fy,fz,tx,ty,tz\n", "cv_csv": "timestamp,x,y,z,a,b,c\n"}]}),
            "recordings[1].event",
            "not both",
        ),
        (
            json!({"name": "x", "recordings": [rec("foam"), {"material": "metal", "bio_csv": "ff_e1,ff_e2\n3000,2900\n"}]}),
            "recordings[1].bio_csv",
            "one calibration is of one sensor",
        ),
        (
            json!({"name": "../x", "recordings": [rec("foam"), rec("metal")]}),
            "name",
            "not a valid",
        ),
        (
            json!({"name": "x", "recordings": []}),
            "recordings",
            "no recordings",
        ),
        (
            json!({"name": "x", "window_length": 1_000_000_000u64, "recordings": [rec("foam"), rec("metal")]}),
            "window_length",
            "must be 1 to 1024",
        ),
    ] {
        let (status, code, field, message) = rest_error(post(body).await.unwrap()).await;
        assert_eq!(
            (status, code.as_str(), field.as_deref()),
            (400, "invalid_argument", Some(want_field)),
            "{message}"
        );
        assert!(message.contains(want_text), "{want_field}: {message}");
    }
    assert!(listing(&dir).is_empty(), "{:?}", listing(&dir));
    // A valid one, then sessions that do not fit it.
    let response = post(json!({"name": "slide", "tare": {"pretared": true}, "recordings": [rec("foam"), rec("metal")]}))
        .await
        .unwrap();
    assert_eq!(response.status(), 201);
    let mut grpc = TactileStabilizerClient::connect(server.grpc_url())
        .await
        .unwrap();
    for (session, want_field) in [
        (
            json!({"detector": {"calibration": "nope"}}),
            "session.detector.calibration",
        ),
        (
            json!({"detector": {"calibration": "slide"}, "stride": 2}),
            "session.window_length",
        ),
        (
            json!({"detector": {"calibration": "slide"}, "fingers": [{"name": "ff", "layout": "biotac"}]}),
            "session.fingers[0].tare",
        ),
        (
            json!({"detector": {"calibration": "slide"}, "fingers": [{"name": "ff", "layout": "biotac_sp", "tare": {"pretared": true}}]}),
            "session.fingers[0].layout",
        ),
        (
            json!({"detector": {"calibration": "slide"}, "fingers": [{"name": "ff", "layout": "biotac", "tare": {"pretared": true}, "electrodes_only": true}]}),
            "session.fingers[0].electrodes_only",
        ),
        (
            json!({"fingers": [{"name": "ff", "layout": "biotac", "tare": {"pretared": true}}, {"name": "th", "layout": "biotac", "tare": {"pretared": true}, "calibration": "nope"}]}),
            "session.fingers[1].calibration",
        ),
        (
            json!({"fingers": [{"name": "ff", "layout": "biotac", "calibration": "slide"}]}),
            "session.fingers[0].tare",
        ),
    ] {
        let mut s =
            json!({"fingers": [{"name": "ff", "layout": "biotac", "tare": {"pretared": true}}]});
        for (k, v) in session.as_object().unwrap() {
            s[k] = v.clone();
        }
        let response = http()
            .post(server.rest_url("/v1/tactile/analyze"))
            .json(&json!({"session": s, "frames": []}))
            .send()
            .await
            .unwrap();
        refused_naming(response, want_field).await;
    }
    // The same rule over gRPC: a stream naming an unknown calibration.
    let (tx, rx) = tokio::sync::mpsc::channel(1);
    tx.send(pb::StabilizeRequest {
        kind: Some(pb::stabilize_request::Kind::Session(pb::TactileSession {
            fingers: vec![pb::TactileFinger {
                name: "ff".into(),
                layout: Some(pb::tactile_finger::Layout::LayoutName("biotac".into())),
                tare: Some(pb::TareSettings {
                    pretared: true,
                    ..Default::default()
                }),
                electrodes_only: false,
                calibration: None,
            }],
            detector: Some(pb::TactileDetector {
                kind: Some(pb::tactile_detector::Kind::Calibration("nope".into())),
            }),
            ..Default::default()
        })),
    })
    .await
    .unwrap();
    let e = grpc
        .stabilize(tonic::codegen::tokio_stream::wrappers::ReceiverStream::new(
            rx,
        ))
        .await
        .unwrap_err();
    assert_eq!(e.code(), Code::InvalidArgument);
    assert!(
        e.message()
            .starts_with("session.detector.calibration: unknown calibration 'nope' (known: slide)"),
        "{}",
        e.message()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The BioTac SP direction-of-slip recordings (../shared/testdata/tactile/biotac_sp/dos_basic,
/// measurement only): electrodes only, no time stamps.
fn dos(label: &str, object: &str, k: usize) -> String {
    let dir = graspd_testkit::testdata_dir()
        .join("tactile/biotac_sp/dos_basic")
        .join(label);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| Some(e.ok()?.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(object))
        })
        .collect();
    files.sort();
    std::fs::read_to_string(&files[k]).unwrap()
}

/// A sensor that gives only its electrodes: a calibration fitted over REST on real BioTac SP
/// held touches (event contact) and slides (event slip) of three objects is electrodes only;
/// a session of an electrodes_only finger naming it reports slip on a slide of the fourth
/// object in more of its frames than on a held touch of it, and names a direction (the slides
/// were labelled north, south and clockwise) in every slipping frame.
#[tokio::test]
async fn an_electrodes_only_calibration_tells_slides_from_touches() {
    let server = Server::start();
    let mut recordings = Vec::new();
    for object in ["case", "hd", "sponge"] {
        for k in 0..4 {
            recordings.push(json!({"bio_csv": dos("t", object, k), "event": "contact"}));
            for label in ["n", "s", "cw"] {
                recordings.push(json!({
                    "bio_csv": dos(label, object, k),
                    "event": "slip",
                    "slip_direction": label,
                }));
            }
        }
    }
    let response = http()
        .post(server.rest_url("/v1/tactile/calibrations"))
        .json(&json!({"name": "sp", "recordings": recordings}))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 201);
    let info: serde_json::Value = response.json().await.unwrap();
    assert_eq!(
        (&info["electrodes"], &info["electrodes_only"]),
        (&json!(24), &json!(true)),
        "{info}"
    );
    assert_eq!(info["material_windows"], json!([]), "{info}");
    let directions: Vec<&str> = info["direction_windows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["label"].as_str().unwrap())
        .collect();
    assert_eq!(directions, ["clockwise", "north", "south"], "{info}");
    let slip_frames = |csv: String| {
        let server = &server;
        async move {
            let session = json!({
                "fingers": [{"name": "ff", "layout": "biotac_sp", "electrodes_only": true}],
                "detector": {"calibration": "sp"},
            });
            let body = analyze_csv(server, csv, session).await;
            let frames = body["frames"].as_array().unwrap();
            let slip = frames
                .iter()
                .filter(|f| f["fingers"][0]["event"] == "slip")
                .count();
            // A slipping frame names a direction; no other does.
            for f in frames {
                let finger = &f["fingers"][0];
                assert_eq!(
                    finger["event"] == "slip",
                    finger["slip_direction"].is_string(),
                    "{finger}"
                );
            }
            (slip, frames.len())
        }
    };
    // The same calibration named by the finger itself, the session's detector left to its
    // default: only a calibration names a direction.
    let session = json!({"fingers": [{"name": "ff", "layout": "biotac_sp", "electrodes_only": true, "calibration": "sp"}]});
    let body = analyze_csv(&server, dos("n", "pen", 1), session).await;
    let named = body["frames"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["fingers"][0]["slip_direction"].is_string())
        .count();
    assert!(named > 0, "no frame named a direction");
    let (touch, n) = slip_frames(dos("t", "pen", 0)).await;
    let (slide, m) = slip_frames(dos("n", "pen", 0)).await;
    assert!(n > 200 && m > 200, "{n} and {m} frames");
    assert!(
        slide > touch,
        "slip in {slide} of {m} slide frames, {touch} of {n} touch frames"
    );
}
