//! Hand kinematics of the shared hand models (issue 6): forward kinematics against MuJoCo 3.17's
//! `mj_kinematics` (fixture recorded by `scripts/fk_reference.py`), inverse kinematics, and the
//! hand descriptions derived from the trees.

use graspd_core::hand::kinematics::{JointKind, KinematicTree, mjcf};
use serde::Deserialize;
use std::collections::HashMap;
use std::path::PathBuf;

#[derive(Deserialize)]
struct Fixture {
    mujoco: String,
    hands: HashMap<String, FixtureHand>,
}

#[derive(Deserialize)]
struct FixtureHand {
    file: String,
    joints: Vec<FixtureJoint>,
    bodies: Vec<String>,
    sites: Vec<String>,
    samples: Vec<Sample>,
}

#[derive(Deserialize)]
struct FixtureJoint {
    name: String,
    #[serde(rename = "type")]
    kind: String,
    range: Option<[f64; 2]>,
}

#[derive(Deserialize)]
struct Sample {
    qpos: Vec<f64>,
    xpos: Vec<[f64; 3]>,
    site_xpos: Vec<[f64; 3]>,
}

fn fixture() -> Fixture {
    serde_json::from_str(include_str!("fixtures/fk_reference.json")).expect("fixture parses")
}

fn hands_dir() -> PathBuf {
    graspd_testkit::testdata_dir().join("hands")
}

fn load(file: &str) -> KinematicTree {
    let path = hands_dir().join(file);
    mjcf::read_mjcf_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Every body and site of every shared hand lands within 1 mm of MuJoCo's position, for 20
/// random joint configurations each, and the joint list and limits match MuJoCo's compiled ones.
#[test]
fn forward_kinematics_matches_mujoco_within_1mm() {
    let fx = fixture();
    assert_eq!(fx.mujoco, "3.17.0");
    assert_eq!(fx.hands.len(), 4);
    let mut report = Vec::new();
    for (name, h) in &fx.hands {
        let tree = load(&h.file);
        let names: Vec<&str> = tree.joints.iter().map(|j| j.name.as_str()).collect();
        let expected: Vec<&str> = h.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names, expected, "{name}: joint order");
        for (j, f) in tree.joints.iter().zip(&h.joints) {
            let kind = match j.kind {
                JointKind::Hinge => "hinge",
                JointKind::Slide => "slide",
            };
            assert_eq!(kind, f.kind, "{name}.{}", j.name);
            match (j.range, f.range) {
                (Some((lo, hi)), Some([flo, fhi])) => assert!(
                    (lo - flo).abs() < 1e-6 && (hi - fhi).abs() < 1e-6,
                    "{name}.{}: range ({lo}, {hi}) vs MuJoCo ({flo}, {fhi})",
                    j.name
                ),
                (a, b) => assert!(
                    a.is_none() && b.is_none(),
                    "{name}.{}: limited differs",
                    j.name
                ),
            }
        }
        let body_ix: Vec<usize> = h
            .bodies
            .iter()
            .map(|b| {
                tree.body_index(b)
                    .unwrap_or_else(|| panic!("{name}: body {b} missing"))
            })
            .collect();
        let site_ix: Vec<(usize, usize)> = h
            .sites
            .iter()
            .map(|s| {
                tree.bodies
                    .iter()
                    .enumerate()
                    .find_map(|(bi, b)| {
                        b.sites.iter().position(|x| &x.name == s).map(|si| (bi, si))
                    })
                    .unwrap_or_else(|| panic!("{name}: site {s} missing"))
            })
            .collect();
        let mut worst: f64 = 0.0;
        for s in &h.samples {
            let fk = tree.forward(&s.qpos).unwrap();
            for (k, &bi) in body_ix.iter().enumerate() {
                let p = fk.body_poses[bi].translation.vector;
                let r = s.xpos[k];
                let d = ((p.x - r[0]).powi(2) + (p.y - r[1]).powi(2) + (p.z - r[2]).powi(2)).sqrt();
                worst = worst.max(d);
            }
            for (k, &(bi, si)) in site_ix.iter().enumerate() {
                let p = fk.body_poses[bi]
                    * nalgebra::Point3::from(tree.bodies[bi].sites[si].pose.translation.vector);
                let r = s.site_xpos[k];
                let d = ((p.x - r[0]).powi(2) + (p.y - r[1]).powi(2) + (p.z - r[2]).powi(2)).sqrt();
                worst = worst.max(d);
            }
        }
        report.push(format!(
            "{name}: worst {:.3e} m over {} samples",
            worst,
            h.samples.len()
        ));
        assert!(worst <= 1e-3, "{name}: FK differs from MuJoCo by {worst} m");
    }
    report.sort();
    eprintln!("FK vs MuJoCo 3.17:\n  {}", report.join("\n  "));
}
