//! The graspctl binary against a running server.

use graspd_core::cloud::io::write_ply_ascii;
use graspd_e2e::{Server, binary, cylinder, http};
use graspd_testkit::view::standard_view;
use graspd_testkit::ycb::Object;
use std::process::{Command, Output};

fn graspctl(server: &Server, args: &[&str]) -> Output {
    Command::new(binary("graspctl", "GRASPCTL_BIN"))
        .env_remove("GRASPD_SERVER")
        .env_remove("GRASPD_TOKEN")
        .arg("--server")
        .arg(server.grpc_url())
        .args(args)
        .output()
        .expect("run graspctl")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn cloud_file(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("graspd-e2e-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, write_ply_ascii(&cylinder(2000), None)).unwrap();
    path
}

#[test]
fn hands_lists_and_shows() {
    let server = Server::start();
    let out = graspctl(&server, &["hands"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    for name in ["barrett", "parallel_gripper", "shadow"] {
        assert!(stdout.contains(name), "{stdout}");
    }
    let out = graspctl(&server, &["hands", "barrett"]);
    assert!(out.status.success());
    assert!(text(&out.stdout).contains("small_wrap  same as large_wrap"));
    let out = graspctl(&server, &["hands", "nope"]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("unknown hand 'nope'"));
}

/// `hands NAME --synergies`: an imported hand's posture synergies as a summary and as JSON; a
/// built-in hand (no joints) is refused naming why.
#[test]
fn hands_show_the_posture_synergies() {
    let gripper = graspd_testkit::testdata_dir().join("hands/robotiq_2f85/2f85.xml");
    let import = format!("robotiq_2f85={}", gripper.display());
    let server = Server::start_with(&["--import-hand", &import]);
    let out = graspctl(&server, &["hands", "robotiq_2f85", "--synergies"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("hand            robotiq_2f85"), "{stdout}");
    assert!(stdout.contains("  e1 "), "{stdout}");
    assert!(stdout.contains("  pinch "), "{stdout}");
    let out = graspctl(&server, &["--json", "hands", "robotiq_2f85", "--synergies"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let joints = json["joints"].as_array().unwrap().len();
    assert_eq!(json["mean"].as_array().unwrap().len(), joints);
    let e1 = &json["components"][0];
    assert_eq!(e1["direction"].as_array().unwrap().len(), joints);
    assert!(e1["explained"].as_f64().unwrap() > 0.9, "{e1}");
    assert_eq!(json["centres"][0]["grasp_type"], "pinch");
    let out = graspctl(&server, &["hands", "shadow", "--synergies"]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("no kinematics"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn plan_prints_a_summary_and_json() {
    let server = Server::start();
    let cloud = cloud_file("cylinder.ply");
    let cloud = cloud.to_str().unwrap();
    let out = graspctl(
        &server,
        &[
            "plan",
            "--cloud",
            cloud,
            "--hand",
            "shadow",
            "--seed",
            "3",
            "--support-plane",
            "0,0,1,0",
            "--grasp-type",
            "tripod",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    for needle in [
        "grasp type      tripod (source: request)",
        "opposition      TT-FT",
        "hand pose",
        "pre-grasp pose",
        "quality         S (GII)",
        "stage 1",
        "timings",
    ] {
        assert!(stdout.contains(needle), "missing '{needle}' in\n{stdout}");
    }

    let out = graspctl(
        &server,
        &[
            "--json",
            "plan",
            "--cloud",
            cloud,
            "--hand",
            "barrett",
            "--viewpoint",
            "0,-0.5,0.4",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("--json prints JSON");
    assert_eq!(json["hand"], "barrett");
    assert!(json["contacts"].as_array().is_some_and(|c| !c.is_empty()));

    let out = graspctl(
        &server,
        &[
            "plan",
            "--cloud",
            cloud,
            "--hand",
            "parallel_gripper",
            "--grasp-type",
            "tripod",
        ],
    );
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("InvalidArgument") && stderr.contains("hints.grasp_type"),
        "{stderr}"
    );

    let out = graspctl(
        &server,
        &["plan", "--cloud", "/nonexistent.ply", "--hand", "shadow"],
    );
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("/nonexistent.ply"));
}

/// `--mode learned_quality` (issue 18): the imported 2F-85 plans a soup can's single view with
/// the built-in grasp-quality network, and the summary says what the search found; an unknown
/// mode is refused before anything is sent.
#[test]
fn plan_with_the_learned_quality() {
    let gripper = graspd_testkit::testdata_dir().join("hands/robotiq_2f85/2f85.xml");
    let import = format!("robotiq_2f85={}", gripper.display());
    let server = Server::start_with(&["--import-hand", &import]);
    let view = standard_view(Object::TomatoSoupCan, 2000, 2);
    let path = cloud_file("soup_can.ply");
    std::fs::write(&path, write_ply_ascii(&view.object_cloud().points, None)).unwrap();
    let (pl, vp) = (view.support_plane, view.viewpoint);
    let plane = format!(
        "{},{},{},{}",
        pl.normal.x, pl.normal.y, pl.normal.z, pl.offset
    );
    let viewpoint = format!("{},{},{}", vp.x, vp.y, vp.z);
    let plan = |extra: &[&str]| {
        let mut args = vec![
            "plan",
            "--cloud",
            path.to_str().unwrap(),
            "--hand",
            "robotiq_2f85",
            "--seed",
            "3",
            "--support-plane",
            &plane,
            "--viewpoint",
            &viewpoint,
        ];
        args.extend_from_slice(extra);
        graspctl(&server, &args)
    };
    let out = plan(&["--mode", "learned_quality"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    for needle in [
        "mode learned_quality",
        "learned quality P(success)",
        "network calls of",
    ] {
        assert!(stdout.contains(needle), "missing '{needle}' in\n{stdout}");
    }
    // The dual-stage plan has no learned quality to report.
    let out = plan(&[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("mode dual_stage") && !stdout.contains("learned quality"),
        "{stdout}"
    );
    let out = plan(&["--mode", "best"]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("unknown planner mode 'best'"),
        "{}",
        text(&out.stderr)
    );
}

const TACTILE_RECORDING: &str = "tactile/biotac_slide/mat5/mat5_1_bio.csv";

#[tokio::test]
async fn stabilize_replays_a_recording_with_one_setpoint_per_frame_like_analyze() {
    let server = Server::start();
    let path = graspd_testkit::testdata_dir().join(TACTILE_RECORDING);
    let csv = path.to_str().unwrap();
    let out = graspctl(
        &server,
        &["--json", "stabilize", "--csv", csv, "--fast", "--pretared"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let lines: Vec<serde_json::Value> = text(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON setpoint per line"))
        .collect();
    let rows = std::fs::read_to_string(&path).unwrap().lines().count() - 1;
    assert_eq!(lines.len(), rows);
    assert!(text(&out.stderr).contains(&format!("{rows} frames")));

    // The same session through POST /v1/tactile/analyze gives the same per-frame results.
    let analyzed: serde_json::Value = http()
        .post(server.rest_url("/v1/tactile/analyze?pretared=true"))
        .header("content-type", "text/csv")
        .body(std::fs::read(&path).unwrap())
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    for (i, mut line) in lines.into_iter().enumerate() {
        assert_eq!(line["frame_index"], i);
        line.as_object_mut().unwrap().remove("frame_index");
        assert_eq!(line, analyzed["frames"][i], "frame {i}");
    }

    // The summary: frames, the event split, and the hint that raw forces need a gain.
    let out = graspctl(
        &server,
        &["stabilize", "--csv", csv, "--fast", "--pretared"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let summary = text(&out.stdout);
    assert!(summary.contains(&format!("{rows} frames")), "{summary}");
    assert!(summary.contains("events     non-contact"), "{summary}");
    assert!(summary.contains("--calibration-gain"), "{summary}");
    let out = graspctl(
        &server,
        &[
            "stabilize",
            "--csv",
            csv,
            "--fast",
            "--pretared",
            "--calibration-gain",
            "0.01",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(!text(&out.stdout).contains("--calibration-gain"));
}

#[test]
fn stabilize_reports_a_layout_that_does_not_fit_the_recording() {
    let server = Server::start();
    let path = graspd_testkit::testdata_dir().join(TACTILE_RECORDING);
    let out = graspctl(
        &server,
        &[
            "stabilize",
            "--csv",
            path.to_str().unwrap(),
            "--fast",
            "--layout",
            "biotac_sp",
        ],
    );
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert!(stderr.contains("InvalidArgument"), "{stderr}");
    assert!(stderr.contains("electrodes"), "{stderr}");
    let out = graspctl(&server, &["stabilize", "--csv", "/nonexistent.csv"]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("cannot read /nonexistent.csv"));
}

#[test]
fn the_token_reaches_a_protected_server() {
    let server = Server::start_with(&["--auth-token", "graspctl-token"]);
    let out = graspctl(&server, &["hands"]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("Unauthenticated"),
        "{}",
        text(&out.stderr)
    );
    let out = graspctl(&server, &["--token", "graspctl-token", "hands"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("shadow"));
    let cloud = cloud_file("token.ply");
    let out = graspctl(
        &server,
        &[
            "--token",
            "graspctl-token",
            "plan",
            "--cloud",
            cloud.to_str().unwrap(),
            "--hand",
            "parallel_gripper",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
}

/// `graspctl tactile calibrate` on a folder of labelled recordings (a `labels.csv` naming each
/// folder's material), then `stabilize --calibration` on a recording it was not fitted on
/// names that material; the calibration is listed and deleted.
#[test]
fn tactile_calibrate_then_stabilize_with_the_calibration() {
    let server = Server::start();
    let slide = graspd_testkit::testdata_dir().join("tactile/biotac_slide");
    let dir = std::env::temp_dir().join(format!("graspd-e2e-calibrate-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for mat in ["mat17", "mat20"] {
        std::fs::create_dir_all(dir.join(mat)).unwrap();
        for sample in 1..=2 {
            for kind in ["bio", "cw", "cv"] {
                let file = format!("{mat}_{sample}_{kind}.csv");
                std::fs::copy(slide.join(mat).join(&file), dir.join(mat).join(&file)).unwrap();
            }
        }
    }
    std::fs::write(
        dir.join("labels.csv"),
        "# folder,material\nmat17,foam\nmat20,metal\n",
    )
    .unwrap();
    let out = graspctl(
        &server,
        &[
            "tactile",
            "calibrate",
            dir.to_str().unwrap(),
            "--name",
            "slide",
            "--pretared",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let summary = text(&out.stdout);
    assert!(summary.starts_with("slide: 19 electrodes"), "{summary}");
    assert!(summary.contains("4 recordings"), "{summary}");
    assert!(summary.contains("(in memory only)"), "{summary}");
    assert!(
        summary.contains("foam ") && summary.contains("metal "),
        "{summary}"
    );

    let out = graspctl(&server, &["--json", "tactile", "calibrations"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let listed: serde_json::Value = serde_json::from_str(text(&out.stdout).trim()).unwrap();
    assert_eq!(listed["calibrations"][0]["name"], "slide", "{listed}");
    assert_eq!(
        listed["calibrations"][0]["material_windows"][1]["label"],
        "metal"
    );
    assert!(
        listed["calibrations"][0]["event_windows"]["slip"]
            .as_u64()
            .unwrap()
            > 0
    );

    let held_out = slide.join("mat20/mat20_15_bio.csv");
    let out = graspctl(
        &server,
        &[
            "--json",
            "stabilize",
            "--csv",
            held_out.to_str().unwrap(),
            "--fast",
            "--pretared",
            "--calibration",
            "slide",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let materials: Vec<String> = text(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .map(|v| v["fingers"][0]["material"].as_str().unwrap().to_string())
        .filter(|m| m != "unknown")
        .collect();
    let metal = materials.iter().filter(|m| *m == "metal").count();
    assert!(
        materials.len() > 400 && metal as f64 >= 0.9 * materials.len() as f64,
        "{metal} of {}",
        materials.len()
    );

    let out = graspctl(&server, &["tactile", "delete", "slide"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = graspctl(&server, &["tactile", "delete", "slide"]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("NotFound"),
        "{}",
        text(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `graspctl tactile calibrate --all-csv` on a copy of BioTac SP direction-of-slip sequences
/// (electrodes only, files not named `*_bio.csv`) labelled by folder with an event
/// (`t,,contact`, `n,,slip,north`, `s,,slip,south`): the calibration is electrodes only and
/// counts both events and the directions.
#[test]
fn tactile_calibrate_an_electrodes_only_sensor_by_event() {
    let server = Server::start();
    let dos = graspd_testkit::testdata_dir().join("tactile/biotac_sp/dos_basic");
    let dir = std::env::temp_dir().join(format!("graspd-e2e-calibrate-sp-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut copied = 0;
    for label in ["t", "n", "s"] {
        std::fs::create_dir_all(dir.join(label)).unwrap();
        let mut files: Vec<_> = std::fs::read_dir(dos.join(label))
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .collect();
        files.sort();
        for f in files.iter().take(6) {
            std::fs::copy(f, dir.join(label).join(f.file_name().unwrap())).unwrap();
            copied += 1;
        }
    }
    std::fs::write(
        dir.join("labels.csv"),
        "t,,contact\nn,,slip,north\ns,,slip,south\n",
    )
    .unwrap();
    let calibrate = |extra: &[&str]| {
        let mut args = vec![
            "tactile",
            "calibrate",
            dir.to_str().unwrap(),
            "--name",
            "sp",
        ];
        args.extend_from_slice(extra);
        graspctl(&server, &args)
    };
    // The files are not *_bio.csv: without --all-csv there is nothing to fit.
    let out = calibrate(&[]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("--all-csv"),
        "{}",
        text(&out.stderr)
    );
    let out = calibrate(&["--all-csv"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let summary = text(&out.stdout);
    assert!(
        summary.starts_with("sp: 24 electrodes (electrodes only)"),
        "{summary}"
    );
    assert!(
        summary.contains(&format!("{copied} recordings")),
        "{summary}"
    );
    assert!(summary.contains("material windows: none"), "{summary}");
    assert!(
        summary.contains("non-contact 0, contact ") && !summary.contains("slip 0\n"),
        "{summary}"
    );
    assert!(
        summary.contains("slip direction windows: north ") && summary.contains(", south "),
        "{summary}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
