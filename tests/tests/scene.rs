//! The plan as a 3D scene through the real binary (issue 20): `POST /v1/plan?format=glb`, gRPC
//! `output.scene_glb` and `graspctl plan --glb` give the same binary glTF, which the `gltf` crate
//! loads and validates: the cloud, the contacts and — for an imported hand with kinematics — the
//! hand's pieces at the pre-grasp, grasp and squeeze; a parametric hand's scene has no hand.

use graspd_e2e::{Server, binary, grpc_request, http, json_request, refused_naming};
use graspd_proto::v1 as pb;
use std::process::Command;

fn node_names(glb: &[u8]) -> Vec<String> {
    let gltf = gltf::Gltf::from_slice(glb).expect("a valid glTF");
    gltf.nodes()
        .map(|n| n.name().unwrap_or_default().to_string())
        .collect()
}

async fn rest_glb(server: &Server, body: &serde_json::Value) -> Vec<u8> {
    let response = http()
        .post(server.rest_url("/v1/plan?format=glb"))
        .json(body)
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["content-type"], "model/gltf-binary");
    response.bytes().await.unwrap().to_vec()
}

#[tokio::test]
async fn the_plan_as_a_gltf_scene_over_rest_grpc_and_graspctl() {
    let model = graspd_testkit::testdata_dir().join("hands/robotiq_2f85/2f85.xml");
    let server = Server::start_with(&[
        "--import-hand",
        &format!("robotiq_2f85={}", model.display()),
    ]);

    // A hand with kinematics: the hand's pieces in the three configurations.
    let glb = rest_glb(&server, &json_request("robotiq_2f85", 2)).await;
    assert!(glb.starts_with(b"glTF"));
    let names = node_names(&glb);
    for name in [
        "cloud",
        "support_plane",
        "contacts",
        "contact_normals",
        "opposition",
    ] {
        assert!(names.iter().any(|n| n == name), "{name}: {names:?}");
    }
    for configuration in ["pregrasp/", "grasp/", "squeeze/"] {
        assert!(
            names
                .iter()
                .filter(|n| n.starts_with(configuration))
                .count()
                >= 5,
            "{configuration}: {names:?}"
        );
    }

    // gRPC gives the same bytes for the same request; without the option, none.
    let mut request = grpc_request("robotiq_2f85", 2);
    request.output = Some(pb::OutputOptions {
        scene_glb: true,
        ..Default::default()
    });
    let mut grpc = server.grpc().await;
    let plan = grpc.plan_grasp(request.clone()).await.unwrap().into_inner();
    assert_eq!(plan.scene_glb, glb);
    request.output = None;
    let plain = grpc.plan_grasp(request).await.unwrap().into_inner();
    assert!(plain.scene_glb.is_empty());

    // graspctl writes it.
    let dir = std::env::temp_dir().join(format!("graspd-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("plan.glb");
    let cloud = dir.join("cloud.pcd");
    let points = graspd_e2e::cylinder(2000);
    let cloud_text: String = format!(
        "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA ascii\n",
        n = points.len()
    ) + &points
        .iter()
        .map(|p| format!("{} {} {}\n", p.x, p.y, p.z))
        .collect::<String>();
    std::fs::write(&cloud, cloud_text).unwrap();
    let status = Command::new(binary("graspctl", "GRASPCTL_BIN"))
        .env_remove("GRASPD_SERVER")
        .env_remove("GRASPD_TOKEN")
        .args(["--server", &server.grpc_url(), "plan", "--cloud"])
        .arg(&cloud)
        .args([
            "--hand",
            "robotiq_2f85",
            "--support-plane",
            "0,0,1,0",
            "--glb",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let written = std::fs::read(&out).unwrap();
    assert!(node_names(&written).iter().any(|n| n.starts_with("grasp/")));
    std::fs::remove_dir_all(&dir).ok();

    // A parametric hand: the scene without a hand.
    let names = node_names(&rest_glb(&server, &json_request("barrett", 1)).await);
    assert!(names.iter().any(|n| n == "cloud"));
    assert!(!names.iter().any(|n| n.starts_with("grasp/")), "{names:?}");

    // An unknown format is refused naming it.
    let response = http()
        .post(server.rest_url("/v1/plan?format=obj"))
        .json(&json_request("barrett", 1))
        .send()
        .await
        .unwrap();
    let message = refused_naming(response, "format").await;
    assert!(message.contains("glb"), "{message}");
}
