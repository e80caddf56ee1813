//! The committed sample clouds in `examples/` read back as what `make-clouds` says they are.

use graspd_core::cloud::PointCloud;
use graspd_core::cloud::io::{read_pcd, read_ply};
use graspd_testkit::{Object, standard_view, workspace_root};

fn example(name: &str) -> Vec<u8> {
    let path = workspace_root().join("examples").join(name);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(bytes.len() < 200_000, "{name} is {} bytes", bytes.len());
    bytes
}

/// Same points up to float32 rounding (the files store float32).
fn assert_same(file: &PointCloud, fresh: &PointCloud, name: &str) {
    assert_eq!(file.len(), fresh.len(), "{name}");
    for (a, b) in file.points.iter().zip(&fresh.points) {
        assert!(
            (a - b).norm() < 1e-6,
            "{name}: {a} vs {b}; rerun make-clouds"
        );
    }
}

#[test]
fn examples_match_the_generator() {
    let can = standard_view(Object::TomatoSoupCan, 2000, 1);
    let ply = example("tomato_soup_can.ply");
    assert!(ply.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
    assert_same(&read_ply(&ply).unwrap(), &can.cloud, "tomato_soup_can.ply");

    let banana = standard_view(Object::Banana, 2000, 1);
    let pcd = example("banana.pcd");
    assert!(String::from_utf8_lossy(&pcd).contains("\nDATA ascii\n"));
    assert_same(&read_pcd(&pcd).unwrap(), &banana.cloud, "banana.pcd");

    let json: serde_json::Value = serde_json::from_slice(&example("tomato_soup_can.json")).unwrap();
    let points = json["cloud"]["points"].as_array().unwrap();
    assert_eq!(points.len(), 2000);
    for (p, q) in points.iter().zip(&can.cloud.points) {
        for k in 0..3 {
            assert!((p[k].as_f64().unwrap() - q[k]).abs() <= 0.5e-4 + 1e-12);
        }
    }
    assert_eq!(json["hand_name"], "parallel_gripper");
    assert_eq!(json["options"]["seed"], 1);
    assert_eq!(
        json["hints"]["support_plane"]["normal"],
        serde_json::json!([0, 0, 1])
    );
    let vp = &json["hints"]["viewpoint"];
    for k in 0..3 {
        assert!((vp[k].as_f64().unwrap() - can.viewpoint[k]).abs() <= 0.5e-4 + 1e-12);
    }
}
