//! The plan as a GLB scene (issue 20): for each shared hand, a plan on a YCB view written as
//! binary glTF loads in the `gltf` crate (which validates the document), carries the cloud, the
//! contacts and the opposition, and each hand piece's node sits where the plan's root pose and
//! joints put it (forward kinematics computed here, independently of the writer), at the
//! pre-grasp, grasp and squeeze.

use graspd_core::hand::kinematics::KinematicHand;
use graspd_core::plan_scene::{plan_scene, to_glb};
use graspd_core::planning::{
    GraspPlan, KinematicModel, PlanHints, PlanInput, PlannerOptions, plan,
};
use graspd_testkit::view::standard_view;
use graspd_testkit::ycb::Object;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use std::collections::HashMap;
use std::sync::Arc;

const SHARED_HANDS: [&str; 4] = [
    "shadow_hand/right_hand.xml",
    "wonik_allegro/right_hand.xml",
    "robotiq_2f85/2f85.xml",
    "barrett/wam_barrett_gripper.xml",
];

fn joint_vector(model: &KinematicModel, joints: &[(String, f64)]) -> Vec<f64> {
    model
        .hand
        .tree
        .joints
        .iter()
        .map(|j| joints.iter().find(|(n, _)| *n == j.name).unwrap().1)
        .collect()
}

fn node_pose(node: &gltf::Node) -> Isometry3<f64> {
    let (t, r, s) = node.transform().decomposed();
    assert_eq!(s, [1.0, 1.0, 1.0]);
    Isometry3::from_parts(
        Translation3::new(t[0] as f64, t[1] as f64, t[2] as f64),
        UnitQuaternion::new_unchecked(Quaternion::new(
            r[3] as f64,
            r[0] as f64,
            r[1] as f64,
            r[2] as f64,
        )),
    )
}

#[test]
fn each_shared_hands_plan_loads_as_gltf_with_its_links_where_the_plan_puts_them() {
    for file in SHARED_HANDS {
        let path = graspd_testkit::testdata_dir().join("hands").join(file);
        let model =
            Arc::new(KinematicModel::new(KinematicHand::from_mjcf_file(&path).unwrap()).unwrap());
        let view = standard_view(Object::TomatoSoupCan, 2000, 1);
        let cloud = view.object_cloud();
        let p: GraspPlan = plan(PlanInput {
            cloud: cloud.clone(),
            hand: model.describe().unwrap(),
            hints: PlanHints {
                support_plane: Some(view.support_plane),
                viewpoint: Some(view.viewpoint),
                ..Default::default()
            },
            options: PlannerOptions {
                seed: 1,
                ..Default::default()
            },
            kinematics: Some(model.clone()),
            grasp_quality: None,
        })
        .unwrap();
        let glb = to_glb(&plan_scene(&cloud.points, &p, Some(&model)));
        let gltf = gltf::Gltf::from_slice(&glb).unwrap_or_else(|e| panic!("{file}: {e}"));
        let nodes: HashMap<String, gltf::Node> = gltf
            .nodes()
            .map(|n| (n.name().unwrap().to_string(), n))
            .collect();
        let count = |name: &str| {
            let mesh = nodes[name].mesh().unwrap();
            let primitive = mesh.primitives().next().unwrap();
            primitive.get(&gltf::Semantic::Positions).unwrap().count()
        };
        assert_eq!(count("cloud"), cloud.points.len(), "{file}");
        assert_eq!(count("contacts"), p.contacts.len(), "{file}");
        assert_eq!(count("opposition"), 2, "{file}");
        assert!(nodes.contains_key("support_plane"), "{file}");

        let tree = &model.hand.tree;
        let root = p.root_pose.unwrap().isometry();
        let pre_root = p.pregrasp_pose.isometry() * p.hand_pose.isometry().inverse() * root;
        for (configuration, joints, root) in [
            ("pregrasp", &p.pregrasp_joints, pre_root),
            ("grasp", &p.joints, root),
            ("squeeze", &p.squeeze_joints, root),
        ] {
            let fk = tree.forward(&joint_vector(&model, joints)).unwrap();
            for (k, piece) in model.collision.pieces.iter().enumerate() {
                let name = format!("{configuration}/{}/{k}", tree.bodies[piece.body].name);
                let node = nodes
                    .get(&name)
                    .unwrap_or_else(|| panic!("{file}: no node {name}"));
                let expected = root * fk.body_poses[piece.body] * piece.pose;
                let got = node_pose(node);
                assert!(
                    (got.translation.vector - expected.translation.vector).norm() < 1e-5
                        && got.rotation.angle_to(&expected.rotation) < 1e-5,
                    "{file}: {name} at {got:?}, expected {expected:?}"
                );
                let triangles = node.mesh().unwrap().primitives().next().unwrap();
                assert_eq!(triangles.mode(), gltf::mesh::Mode::Triangles);
            }
        }
    }
}
