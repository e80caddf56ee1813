//! Hand kinematics of the shared hand models (issue 6): forward kinematics against MuJoCo 3.17's
//! `mj_kinematics` (fixture recorded by `scripts/fk_reference.py`), inverse kinematics, and the
//! hand descriptions derived from the trees.

use graspd_core::GraspType;
use graspd_core::cloud::Plane;
use graspd_core::hand::kinematics::{
    ContactTarget, GeomShape, HandOverrides, IkOptions, JointKind, KinematicHand, KinematicTree,
    PalmFreedom, mjcf,
};
use nalgebra::{Point3, Vector3};
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

const SHARED_HANDS: [(&str, usize); 4] = [
    ("shadow_hand/right_hand.xml", 5),
    ("wonik_allegro/right_hand.xml", 4),
    ("robotiq_2f85/2f85.xml", 2),
    ("barrett/wam_barrett_gripper.xml", 3),
];

/// The servos' torque limits come from each shared MJCF's actuators (`Joint::effort`, read by
/// hand from the files): the Shadow's finger servos 1 N·m (the class default), its thumb base
/// 3 and proximal 2, its coupled middle and distal joints 1 each through their fixed tendon
/// (coefficients 1); the Barrett's 3 N·m (`forcelimited`); the Allegro's unlimited (`kp` only).
#[test]
fn servo_torque_limits_are_read_from_the_actuators() {
    let effort = |file: &str, joint: &str| {
        let t = load(file);
        t.joints[t.joint_index(joint).unwrap()].effort
    };
    let shadow = "shadow_hand/right_hand.xml";
    for (joint, limit) in [
        ("rh_FFJ3", 1.0),
        ("rh_FFJ2", 1.0),
        ("rh_FFJ1", 1.0),
        ("rh_LFJ5", 1.0),
        ("rh_THJ5", 3.0),
        ("rh_THJ4", 2.0),
        ("rh_THJ1", 1.0),
        ("rh_WRJ2", 10.0),
    ] {
        assert_eq!(effort(shadow, joint), Some(limit), "{joint}");
    }
    let barrett = "barrett/wam_barrett_gripper.xml";
    assert_eq!(effort(barrett, "wam/bhand/thumb/med_joint"), Some(3.0));
    assert_eq!(effort(barrett, "wam/bhand/index/dist_joint"), Some(3.0));
    let allegro = load("wonik_allegro/right_hand.xml");
    assert!(allegro.joints.iter().all(|j| j.effort.is_none()));
}

fn hand(file: &str) -> KinematicHand {
    let path = hands_dir().join(file);
    KinematicHand::from_mjcf_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The description derived from each shared hand validates, has the hand's finger count, marks
/// the real thumb, and measures a plausible aperture (the Robotiq 2F-85's stroke is 85 mm; the
/// pad centres sit 4 mm behind the pad surfaces).
/// Forward kinematics with one or two joints changed from an earlier pass equals a full pass bit
/// for bit, for every joint of every shared hand (the squeeze's finite differences and the
/// closing sweep rely on it).
#[test]
fn forward_with_one_joint_changed_equals_a_full_pass() {
    for file in [
        "shadow_hand/right_hand.xml",
        "wonik_allegro/right_hand.xml",
        "robotiq_2f85/2f85.xml",
        "barrett/wam_barrett_gripper.xml",
    ] {
        let tree = load(file);
        let q = tree.mid_configuration();
        let base = tree.forward(&q).unwrap();
        for j in 0..tree.joints.len() {
            let mut qh = q.clone();
            qh[j] += 0.01;
            let full = tree.forward(&qh).unwrap();
            let changed = tree.forward_changed(&qh, &base, j).unwrap();
            assert_eq!(full.body_poses, changed.body_poses, "{file}: joint {j}");
            assert_eq!(full.joint_axes, changed.joint_axes, "{file}: joint {j}");
            // With the next joint changed too (two fingers closing at once).
            let k = (j + 1) % tree.joints.len();
            qh[k] -= 0.02;
            let full2 = tree.forward(&qh).unwrap();
            let from = tree.forward_from(&qh, &base, &[j, k]).unwrap();
            assert_eq!(full2.body_poses, from.body_poses, "{file}: joints {j}, {k}");
            // A joint's change moves its own body.
            let b = tree.joints[j].body;
            if tree.joints[j].kind == JointKind::Hinge {
                assert_ne!(
                    base.body_poses[b], changed.body_poses[b],
                    "{file}: joint {j}"
                );
            }
        }
    }
}

#[test]
fn derived_descriptions_validate() {
    let thumbs = ["thdistal", "th", "right", "thumb"];
    for ((file, fingers), thumb) in SHARED_HANDS.into_iter().zip(thumbs) {
        let h = hand(file);
        let d = h.describe().unwrap_or_else(|e| panic!("{file}: {e}"));
        d.validate().unwrap();
        assert_eq!(d.fingers.len(), fingers, "{file}");
        let thumbs: Vec<&str> = d
            .fingers
            .iter()
            .filter(|f| f.thumb)
            .map(|f| f.name.as_str())
            .collect();
        assert_eq!(thumbs, [thumb], "{file}");
        let g = &d.geometry;
        eprintln!(
            "{file}: palm '{}', fingers {:?}, a_max {:.3} m, a_min {:.3} m, h_max {:.3} m, \
             palm {:.3}×{:.3}×{:.3} m, finger width {:.3} m, types {:?}",
            h.tree.bodies[h.palm].name,
            d.fingers
                .iter()
                .map(|f| f.name.as_str())
                .collect::<Vec<_>>(),
            g.max_aperture,
            g.min_aperture,
            g.max_height,
            g.palm_length,
            g.palm_width,
            g.palm_thickness,
            g.finger_width,
            d.realisable_types()
        );
        assert!(
            g.max_height > 0.03 && g.max_height < 0.3,
            "{file}: h_max {}",
            g.max_height
        );
        if fingers == 2 {
            // The 2F-85 opens 85 mm between its pads (Robotiq's datasheet); their centres are
            // 93 mm apart.
            assert!(
                (g.max_aperture - 0.085).abs() < 0.003,
                "{file}: a_max {}",
                g.max_aperture
            );
            assert_eq!(d.realisable_types(), [GraspType::Pinch]);
        } else {
            assert!(
                g.max_aperture > 0.1 && g.max_aperture < 0.35,
                "{file}: a_max {}",
                g.max_aperture
            );
            assert_eq!(d.realisable_types().len(), 6, "{file}");
        }
        // The reach bound that lets IK give up early really bounds the sampled reach.
        for (f, k) in d.fingers.iter().zip(&h.fingers) {
            assert!(
                f.length <= k.reach + 1e-9,
                "{file}.{}: {} > {}",
                f.name,
                f.length,
                k.reach
            );
        }
        // Deterministic: the same model gives the same description.
        assert_eq!(hand(file).describe().unwrap(), d);
    }
    // The Barrett's spread fingers and the Allegro's/Shadow's thumb: tripod uses the thumb and
    // the two fingers nearest it; precision every finger.
    let shadow = hand(SHARED_HANDS[0].0).describe().unwrap();
    let tripod = shadow.resolve_forced(GraspType::Tripod).unwrap();
    assert_eq!(tripod.contact_count(), 3);
    assert_eq!(
        shadow
            .resolve_forced(GraspType::Precision)
            .unwrap()
            .contact_count(),
        5
    );
}

/// IK reaches the fingertip positions of random (constraint-respecting) configurations from the
/// home pose within 2 mm, inside the joint limits, and calls a target 1 m away unreachable.
#[test]
fn inverse_kinematics_reaches_reachable_targets() {
    let mut summary = Vec::new();
    for (file, _) in SHARED_HANDS {
        let h = hand(file);
        let home = h.tree.home_configuration();
        let configs = h.sample_configurations(25, 77);
        assert_eq!(configs.len(), 25, "{file}");
        let (mut solved, mut total, mut worst) = (0, 0, 0.0f64);
        for q in &configs {
            let tips = h.fingertips(q).unwrap();
            for (f, target) in tips.iter().enumerate() {
                let ik = h.inverse(f, target, &home).unwrap();
                total += 1;
                worst = worst.max(ik.residual);
                if ik.reachable && ik.residual <= 0.002 {
                    solved += 1;
                }
                for (j, v) in h.tree.joints.iter().zip(&ik.joints) {
                    let (lo, hi) = j.limits();
                    assert!(
                        *v >= lo - 1e-12 && *v <= hi + 1e-12,
                        "{file}: {} = {v}",
                        j.name
                    );
                }
                // The reported residual is the true distance.
                let reached = h.fingertips(&ik.joints).unwrap()[f];
                assert!(((reached - target).norm() - ik.residual).abs() < 1e-9);
            }
        }
        summary.push(format!(
            "{file}: {solved}/{total} within 2 mm, worst residual {worst:.2e} m"
        ));
        assert_eq!(solved, total, "{file}: worst residual {worst}");
        for f in 0..h.fingers.len() {
            let far = h.fingertips(&home).unwrap()[f] + Vector3::new(0.0, 0.0, 1.0);
            let ik = h.inverse(f, &far, &home).unwrap();
            assert!(
                !ik.reachable && ik.residual > 0.8,
                "{file}: finger {f}: {}",
                ik.residual
            );
        }
    }
    eprintln!("IK:\n  {}", summary.join("\n  "));
}

/// Several contacts at once: residual per contact, reachable only when all are.
#[test]
fn inverse_contacts_reports_each_contact() {
    let h = hand(SHARED_HANDS[3].0);
    let home = h.tree.home_configuration();
    let q = &h.sample_configurations(1, 5)[0];
    let tips = h.fingertips(q).unwrap();
    let mut targets: Vec<ContactTarget> = tips
        .iter()
        .enumerate()
        .map(|(finger, p)| ContactTarget {
            finger,
            position: *p,
        })
        .collect();
    let ik = h
        .inverse_contacts(&targets, &home, &IkOptions::default())
        .unwrap();
    assert!(ik.reachable, "{:?}", ik.residuals);
    assert_eq!(ik.residuals.len(), 3);
    targets[1].position.z += 1.0;
    let ik = h
        .inverse_contacts(&targets, &home, &IkOptions::default())
        .unwrap();
    assert!(!ik.reachable);
    assert!(ik.residuals[0] <= 0.002 && ik.residuals[1] > 0.8 && ik.residuals[2] <= 0.002);
    targets[2].finger = 0;
    let e = h
        .inverse_contacts(&targets, &home, &IkOptions::default())
        .unwrap_err();
    assert_eq!(e.field, "contacts[2].finger");
}

/// The Robotiq 2F-85's linkage: the coupler chains are not fingers, the closures hold after
/// projection, and random independent joint values violate them.
#[test]
fn robotiq_linkage_is_one_finger_per_side() {
    let h = hand(SHARED_HANDS[2].0);
    assert_eq!(h.tree.loop_closures.len(), 2);
    assert_eq!(h.tree.couplings.len(), 1);
    let tips: Vec<&str> = h
        .fingers
        .iter()
        .map(|f| h.tree.bodies[f.tip].name.as_str())
        .collect();
    assert_eq!(tips, ["right_silicone_pad", "left_silicone_pad"]);
    for q in h.sample_configurations(20, 3) {
        assert!(h.tree.constraint_violation(&q).unwrap() <= 1e-3);
    }
    let raw = &fixture().hands["robotiq_2f85"].samples[0].qpos;
    assert!(h.tree.constraint_violation(raw).unwrap() > 1e-3);
    assert!(
        h.tree
            .constraint_violation(&h.tree.home_configuration())
            .unwrap()
            < 1e-9
    );
}

/// The 2F-85's drivers held anywhere in their range, the rest of the linkage projected from
/// the open hand: the closures hold to 0.1 µm, the drivers stay where they were held and every
/// joint inside its limits — also where a passive joint rests on a limit on the way (closed).
#[test]
fn robotiq_linkage_follows_its_drivers_across_the_range() {
    let h = hand(SHARED_HANDS[2].0);
    let joint = |name: &str| h.tree.joints.iter().position(|j| j.name == name).unwrap();
    let drivers = [joint("right_driver_joint"), joint("left_driver_joint")];
    for k in 0..=8 {
        let v = 0.1 * k as f64;
        let mut q = h.tree.home_configuration();
        for &d in &drivers {
            q[d] = v;
        }
        let violation = h
            .tree
            .project_constraints_holding(&mut q, &drivers)
            .unwrap();
        assert!(violation < 1e-7, "driver at {v}: violation {violation:e}");
        for &d in &drivers {
            assert_eq!(q[d], v);
        }
        for (j, x) in h.tree.joints.iter().zip(&q) {
            let (lo, hi) = j.limits();
            assert!(
                (lo..=hi).contains(x),
                "{} = {x} outside [{lo}, {hi}]",
                j.name
            );
        }
    }
}

/// Names given by the caller win over the detection rules.
#[test]
fn overrides_pick_palm_fingers_and_thumb() {
    let tree = load(SHARED_HANDS[1].0);
    let o = HandOverrides {
        palm: Some("palm".into()),
        fingertips: Some(vec!["th_tip".into(), "ff_tip".into(), "rf_tip".into()]),
        thumb: Some("rf".into()),
        name: Some("allegro3".into()),
    };
    let h = KinematicHand::from_tree(tree.clone(), &o).unwrap();
    let names: Vec<&str> = h.fingers.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["th", "ff", "rf"]);
    assert_eq!(h.thumb, 2);
    let d = h.describe().unwrap();
    assert_eq!(d.name, "allegro3");
    assert!(d.fingers[2].thumb);
    let bad = HandOverrides {
        thumb: Some("pinky".into()),
        ..Default::default()
    };
    assert_eq!(
        KinematicHand::from_tree(tree.clone(), &bad)
            .unwrap_err()
            .field,
        "hand.thumb"
    );
    let bad = HandOverrides {
        fingertips: Some(vec!["nope".into(), "ff_tip".into()]),
        ..Default::default()
    };
    assert_eq!(
        KinematicHand::from_tree(tree, &bad).unwrap_err().field,
        "hand.fingertips"
    );
}

/// Lowest signed height along `n` of the model's collision geometry (every body: the mounted
/// model includes its wrist or flange), computed straight from the geoms (mesh vertices, box
/// corners, sphere/capsule/cylinder support points), independently of parry.
fn lowest_along(h: &KinematicHand, q: &[f64], n: &Vector3<f64>) -> f64 {
    let fk = h.tree.forward(q).unwrap();
    let root_in_hand = (fk.body_poses[h.palm] * h.hand_frame()).inverse();
    let mut lowest = f64::INFINITY;
    for (b, body) in h.tree.bodies.iter().enumerate() {
        for g in body.geoms.iter().filter(|g| g.collision) {
            let pose = root_in_hand * fk.body_poses[b] * g.pose;
            let d = pose.rotation.inverse() * -n; // direction of the support point, geom frame
            let support = |p: Point3<f64>| (pose * p).coords.dot(n);
            let v = match &g.shape {
                GeomShape::Mesh { vertices, .. } => vertices
                    .iter()
                    .map(|p| support(*p))
                    .fold(f64::INFINITY, f64::min),
                GeomShape::Box { half_extents: e } => support(Point3::new(
                    e.x * d.x.signum(),
                    e.y * d.y.signum(),
                    e.z * d.z.signum(),
                )),
                GeomShape::Sphere { radius } => support(Point3::origin()) - radius,
                GeomShape::Capsule {
                    radius,
                    half_length,
                } => support(Point3::new(0.0, 0.0, half_length * d.z.signum())) - radius,
                GeomShape::Cylinder {
                    radius,
                    half_length,
                } => {
                    let radial = Vector3::new(d.x, d.y, 0.0);
                    let radial = radial.try_normalize(1e-12).unwrap_or_else(Vector3::zeros);
                    support(Point3::from(
                        radial * *radius + Vector3::z() * (*half_length * d.z.signum()),
                    ))
                }
                s => panic!("unexpected {s:?}"),
            };
            lowest = lowest.min(v);
        }
    }
    lowest
}

/// The posed convex pieces agree with the raw geoms on the lowest point toward the support plane
/// (hulls keep the extreme vertices), and points inside the pieces count as inside while points
/// 1 m away do not.
#[test]
fn collision_model_is_posed_by_forward_kinematics() {
    let pose = nalgebra::Isometry3::translation(0.1, -0.2, 0.3);
    for (file, _) in SHARED_HANDS {
        let h = hand(file);
        let model = h.collision_model().unwrap();
        assert!(!model.pieces.is_empty(), "{file}");
        for q in h.sample_configurations(5, 11) {
            let posed = model.posed(&h, &q, &pose).unwrap();
            for n in [
                Vector3::z(),
                -Vector3::z(),
                Vector3::x(),
                Vector3::new(0.3, -0.5, 0.8).normalize(),
            ] {
                let plane = Plane::through(&Point3::new(0.0, 0.0, -0.5), n);
                let expected = lowest_along(&h, &q, &(pose.rotation.inverse() * n))
                    + (pose.translation.vector - Vector3::new(0.0, 0.0, -0.5)).dot(&n);
                let got = posed.plane_clearance(&plane);
                assert!((got - expected).abs() < 1e-6, "{file}: {got} vs {expected}");
            }
            // An interior point of every piece: its origin (primitives) or the mean of its hull
            // vertices, posed by FK and the hand pose.
            let fk = h.tree.forward(&q).unwrap();
            let root_in_world = pose * (fk.body_poses[h.palm] * h.hand_frame()).inverse();
            let inner: Vec<Point3<f64>> = model
                .pieces
                .iter()
                .map(|p| {
                    let local = match p.shape.as_convex_polyhedron() {
                        Some(c) => {
                            let s = c
                                .points()
                                .iter()
                                .fold(Vector3::zeros(), |a, v| a + Vector3::new(v.x, v.y, v.z));
                            Point3::from(s / c.points().len() as f64)
                        }
                        None => Point3::origin(),
                    };
                    root_in_world * fk.body_poses[p.body] * p.pose * local
                })
                .collect();
            assert_eq!(
                posed.points_inside(&inner, 1e-4, usize::MAX),
                inner.len(),
                "{file}"
            );
            assert_eq!(
                posed.points_inside(&inner, 1e-4, 3),
                3.min(inner.len()),
                "{file}"
            );
            let far: Vec<Point3<f64>> = inner
                .iter()
                .map(|p| p + Vector3::new(1.0, 0.0, 0.0))
                .collect();
            assert_eq!(posed.points_inside(&far, 0.002, usize::MAX), 0, "{file}");
        }
    }
}

/// Fingers and palm together: contacts produced by a random configuration seen from a hand frame
/// moved by 1 cm and 0.1 rad are reached within 2 mm, with the correction inside its bounds; a
/// Robotiq pinch shifted 15 mm across the jaws, which the fingers alone cannot follow, is reached
/// by moving the palm.
#[test]
fn inverse_kinematics_with_the_palm_pose() {
    let shift = nalgebra::Isometry3::new(
        Vector3::new(0.006, -0.005, 0.006),
        Vector3::new(0.05, -0.06, 0.05),
    );
    let freedom = PalmFreedom::default();
    let opts = IkOptions::default();
    for (file, _) in SHARED_HANDS {
        let h = hand(file);
        let home = h.tree.home_configuration();
        for q in h.sample_configurations(6, 21) {
            let targets: Vec<ContactTarget> = h
                .fingertips(&q)
                .unwrap()
                .iter()
                .enumerate()
                .map(|(finger, p)| ContactTarget {
                    finger,
                    position: shift * p,
                })
                .collect();
            let ik = h
                .inverse_with_palm(&targets, &home, &opts, &freedom)
                .unwrap();
            assert!(ik.reachable, "{file}: {:?}", ik.residuals);
            assert!(
                ik.palm_correction.translation.vector.norm() <= freedom.max_translation + 1e-12
            );
            assert!(ik.palm_correction.rotation.angle() <= freedom.max_rotation + 1e-12);
            // The residuals are true distances for the returned joints and palm correction.
            let tips = h.fingertips(&ik.joints).unwrap();
            for (t, r) in targets.iter().zip(&ik.residuals) {
                let d = (t.position - ik.palm_correction * tips[t.finger]).norm();
                assert!((d - r).abs() < 1e-9);
            }
        }
    }
    let h = hand(SHARED_HANDS[2].0);
    let home = h.tree.home_configuration();
    let q = &h.sample_configurations(1, 4)[0];
    let across = Vector3::new(0.0, 0.015, 0.0);
    let targets: Vec<ContactTarget> = h
        .fingertips(q)
        .unwrap()
        .iter()
        .enumerate()
        .map(|(finger, p)| ContactTarget {
            finger,
            position: p + across,
        })
        .collect();
    let alone = h.inverse_contacts(&targets, &home, &opts).unwrap();
    assert!(
        !alone.reachable && alone.residuals.iter().all(|r| *r > 0.01),
        "{:?}",
        alone.residuals
    );
    let ik = h
        .inverse_with_palm(&targets, &home, &opts, &freedom)
        .unwrap();
    assert!(ik.reachable, "{:?}", ik.residuals);
    // The palm did the moving (a shift or a tilt about the jaw axis both serve).
    let tips = h.fingertips(&ik.joints).unwrap();
    for p in &tips {
        assert!((ik.palm_correction * p - p).norm() > 0.01);
    }
}
