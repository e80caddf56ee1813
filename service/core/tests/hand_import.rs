//! MJCF and URDF import (issue 6): the features the readers support, checked on small models with
//! hand-computed poses, and every kind of bad input answered by a `FieldError` that says what is
//! wrong.

use graspd_core::FieldError;
use graspd_core::hand::kinematics::{JointKind, KinematicHand, mjcf, urdf};
use nalgebra::Point3;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};

/// A fresh directory under the system temp dir for files a test writes.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("graspd-import-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn near(a: Point3<f64>, b: [f64; 3]) -> bool {
    (a - Point3::from(b)).norm() < 1e-9
}

fn position(
    tree: &graspd_core::hand::kinematics::KinematicTree,
    q: &[f64],
    body: &str,
) -> Point3<f64> {
    let fk = tree.forward(q).unwrap();
    Point3::from(
        fk.body_poses[tree.body_index(body).unwrap()]
            .translation
            .vector,
    )
}

const MJCF_MAIN: &str = r#"<mujoco model="two_finger">
  <compiler angle="degree" meshdir="parts"/>
  <include file="defaults.xml"/>
  <asset><mesh name="pad" file="pad.stl" scale="0.001 0.001 0.001"/></asset>
  <worldbody>
    <body name="palm" childclass="hand">
      <body name="a" pos="0.1 0 0" euler="0 0 90">
        <joint name="ja"/>
        <body name="a_tip" pos="0.05 0 0"><geom type="mesh" mesh="pad"/></body>
      </body>
      <body name="b" pos="-0.1 0 0" axisangle="0 0 1 180">
        <joint name="jb" class="slider"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.04" size="0.01"/>
        <site name="b_site" pos="0 0 0.02"/>
      </body>
    </body>
  </worldbody>
</mujoco>"#;

const MJCF_DEFAULTS: &str = r#"<mujoco>
  <default>
    <default class="hand">
      <joint axis="0 0 1" range="0 90"/>
      <default class="slider"><joint type="slide" axis="1 0 0" range="0 0.02"/></default>
    </default>
  </default>
</mujoco>"#;

/// A binary STL with one triangle (mm).
fn stl_bytes() -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&[0u8; 12]);
    for v in [[0f32, -10., 0.], [20., 10., 0.], [0., 10., 5.]] {
        for c in v {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    b.extend_from_slice(&[0u8; 2]);
    b
}

fn write_mjcf_model(dir: &Path, main: &str) -> PathBuf {
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    std::fs::write(dir.join("parts/pad.stl"), stl_bytes()).unwrap();
    std::fs::write(dir.join("defaults.xml"), MJCF_DEFAULTS).unwrap();
    let p = dir.join("hand.xml");
    std::fs::write(&p, main).unwrap();
    p
}

/// `<include>`, nested default classes through `childclass`, degrees for hinge limits and
/// `euler`/`axisangle` but not for slide limits, `fromto`, sites and scaled STL meshes.
#[test]
fn mjcf_features_are_read_with_mujoco_semantics() {
    let dir = scratch("mjcf");
    let tree = mjcf::read_mjcf_file(&write_mjcf_model(&dir, MJCF_MAIN)).unwrap();
    let ja = &tree.joints[tree.joint_index("ja").unwrap()];
    assert_eq!(ja.kind, JointKind::Hinge);
    let (lo, hi) = ja.range.unwrap();
    assert!(lo.abs() < 1e-12 && (hi - FRAC_PI_2).abs() < 1e-12);
    let jb = &tree.joints[tree.joint_index("jb").unwrap()];
    assert_eq!((jb.kind, jb.range), (JointKind::Slide, Some((0.0, 0.02))));
    // a: at (0.1, 0, 0), turned 90° by euler and 90° more by ja → a_tip 0.05 back along −x.
    assert!(near(
        position(&tree, &[FRAC_PI_2, 0.01], "a_tip"),
        [0.05, 0.0, 0.0]
    ));
    assert!(near(
        position(&tree, &[0.0, 0.01], "a_tip"),
        [0.1, 0.05, 0.0]
    ));
    // b: turned 180° about z, so its +x slide moves it toward −x.
    assert!(near(position(&tree, &[0.0, 0.01], "b"), [-0.11, 0.0, 0.0]));
    let b = &tree.bodies[tree.body_index("b").unwrap()];
    assert!(near(
        Point3::from(b.sites[0].pose.translation.vector),
        [0.0, 0.0, 0.02]
    ));
    match &b.geoms[0].shape {
        graspd_core::hand::kinematics::GeomShape::Capsule {
            radius,
            half_length,
        } => assert_eq!((*radius, *half_length), (0.01, 0.02)),
        s => panic!("{s:?}"),
    }
    let tip = &tree.bodies[tree.body_index("a_tip").unwrap()];
    match &tip.geoms[0].shape {
        graspd_core::hand::kinematics::GeomShape::Mesh { vertices, .. } => {
            assert_eq!(vertices.len(), 3);
            assert!(near(vertices[1], [0.02, 0.01, 0.0]));
        }
        s => panic!("{s:?}"),
    }
    // As a hand: palm with two jointed branches, the mesh's box centre as a_tip's contact point.
    let hand = KinematicHand::from_mjcf_file(dir.join("hand.xml")).unwrap();
    assert_eq!(hand.tree.bodies[hand.palm].name, "palm");
    assert_eq!(hand.fingers.len(), 2);
    assert!(near(hand.fingers[0].tip_point, [0.01, 0.0, 0.0025]));
}

const URDF_TRI: &str = r#"<robot name="tri">
  <link name="base"><collision><geometry><box size="0.08 0.06 0.02"/></geometry></collision></link>
  <link name="f1"/><link name="f1_tip"/>
  <link name="f2"/><link name="f2_tip"/>
  <link name="th"/><link name="th_tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="f1"/>
    <origin xyz="0.03 0.02 0.05"/><axis xyz="0 1 0"/><limit lower="0" upper="1.5"/></joint>
  <joint name="j1_tip" type="fixed"><parent link="f1"/><child link="f1_tip"/><origin xyz="0 0 0.06"/></joint>
  <joint name="j2" type="revolute"><parent link="base"/><child link="f2"/>
    <origin xyz="0.03 -0.02 0.05"/><axis xyz="0 1 0"/><limit lower="0" upper="1.5"/></joint>
  <joint name="j2_tip" type="fixed"><parent link="f2"/><child link="f2_tip"/><origin xyz="0 0 0.06"/></joint>
  <joint name="jt" type="continuous"><parent link="base"/><child link="th"/>
    <origin xyz="-0.03 0 0.05" rpy="0 0 1.5707963267948966"/><axis xyz="0 1 0"/></joint>
  <joint name="jt_tip" type="fixed"><parent link="th"/><child link="th_tip"/><origin xyz="0 0 0.06"/></joint>
</robot>"#;

/// URDF origins (xyz, rpy as R = Rz·Ry·Rx), axes in the child frame, revolute and continuous
/// joints, fixed joints folded into the tree; the derived description validates.
#[test]
fn urdf_tree_forward_kinematics_and_description() {
    let tree = urdf::parse_urdf(URDF_TRI, Path::new("."), "tri.urdf").unwrap();
    let names: Vec<&str> = tree.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["j1", "j2", "jt"]);
    assert_eq!(tree.joints[2].range, None);
    let q = [FRAC_PI_2, 0.0, FRAC_PI_2];
    assert!(near(position(&tree, &q, "f1_tip"), [0.09, 0.02, 0.05]));
    assert!(near(position(&tree, &q, "f2_tip"), [0.03, -0.02, 0.11]));
    // th: frame turned 90° about z, so its y axis is the root's −x; +90° takes the tip to +y.
    assert!(near(position(&tree, &q, "th_tip"), [-0.03, 0.06, 0.05]));
    let hand = KinematicHand::from_urdf_str(URDF_TRI, ".").unwrap();
    let d = hand.describe().unwrap();
    let fingers: Vec<(&str, bool)> = d
        .fingers
        .iter()
        .map(|f| (f.name.as_str(), f.thumb))
        .collect();
    assert_eq!(fingers, [("f1", false), ("f2", false), ("th", true)]);
    assert!(d.geometry.max_aperture > 0.05 && d.geometry.max_aperture < 0.25);
    // A continuous joint samples and solves over [−π, π].
    assert_eq!(hand.tree.joints[2].limits(), (-PI, PI));
}

/// Actuator force limits become each joint's `effort` with MuJoCo's semantics: `forcerange`
/// from the element or its default class, × `gear` (its first of up to six numbers); through
/// a fixed tendon × the joint's coefficient; a joint's own `actuatorfrcrange` caps its
/// actuators; `forcelimited="false"` and an unactuated joint leave it unlimited (None). A URDF
/// joint's `<limit effort>` is its.
#[test]
fn actuator_force_limits_are_each_joints_effort() {
    let xml = r#"<mujoco>
  <default>
    <position forcerange="-1 1"/>
    <default class="strong"><position forcerange="-3 2" gear="2 0 0 0 0 0"/></default>
  </default>
  <worldbody><body name="palm">
    <body name="a" pos="0 0 0.05"><joint name="ja" axis="0 1 0" range="0 1"/><geom size="0.01"/>
      <body name="b" pos="0 0 0.04"><joint name="jb" axis="0 1 0" range="0 1"/><geom size="0.01"/>
        <body name="c" pos="0 0 0.03"><joint name="jc" axis="0 1 0" range="0 1"/><geom size="0.01"/></body>
      </body>
    </body>
    <body name="d" pos="0.03 0 0.05">
      <joint name="jd" axis="0 1 0" range="0 1" actuatorfrcrange="-0.5 0.5"/><geom size="0.01"/>
    </body>
    <body name="e" pos="-0.03 0 0.05"><joint name="je" axis="0 1 0" range="0 1"/><geom size="0.01"/></body>
    <body name="f" pos="-0.06 0 0.05"><joint name="jf" axis="0 1 0" range="0 1"/><geom size="0.01"/></body>
  </body></worldbody>
  <tendon><fixed name="t"><joint joint="jb" coef="1"/><joint joint="jc" coef="-0.5"/></fixed></tendon>
  <actuator>
    <position joint="ja" class="strong"/>
    <position tendon="t"/>
    <position joint="jd" forcerange="-4 4"/>
    <motor joint="je" forcelimited="false" forcerange="-1 1"/>
  </actuator>
</mujoco>"#;
    let tree = mjcf::parse_mjcf(xml, Path::new("."), "test.xml").unwrap();
    let efforts: Vec<Option<f64>> = tree.joints.iter().map(|j| j.effort).collect();
    assert_eq!(
        efforts,
        [Some(6.0), Some(1.0), Some(0.5), Some(0.5), None, None]
    );
    // Two actuators on one joint add their limits.
    let twice = xml.replace(
        r#"<position joint="jd" forcerange="-4 4"/>"#,
        r#"<position joint="jf" forcerange="-4 4"/><motor joint="jf" forcerange="-1 1"/>"#,
    );
    let tree = mjcf::parse_mjcf(&twice, Path::new("."), "test.xml").unwrap();
    assert_eq!(tree.joints[5].effort, Some(5.0));
    // Bad input names what is wrong.
    let e = mjcf_err(&xml.replace(r#"<position joint="ja""#, r#"<position joint="nope""#));
    assert!(
        e.message.contains("joint 'nope' is not in the model"),
        "{e}"
    );
    let e = mjcf_err(&xml.replace(
        r#"joint="jd" forcerange="-4 4""#,
        r#"joint="jd" forcerange="4 -4""#,
    ));
    assert!(e.message.contains("forcerange must be low high"), "{e}");
    let e = mjcf_err(&xml.replace(
        r#"forcelimited="false" forcerange="-1 1""#,
        r#"forcelimited="true""#,
    ));
    assert!(
        e.message.contains("forcelimited without a forcerange"),
        "{e}"
    );
    // URDF: `effort` on the limit; none given, or 0, is no limit.
    let urdf = URDF_TRI.replacen(r#"upper="1.5"/>"#, r#"upper="1.5" effort="2.5"/>"#, 1);
    let tree = urdf::parse_urdf(&urdf, Path::new("."), "tri.urdf").unwrap();
    let efforts: Vec<Option<f64>> = tree.joints.iter().map(|j| j.effort).collect();
    assert_eq!(efforts, [Some(2.5), None, None]);
}

fn mjcf_err(xml: &str) -> FieldError {
    mjcf::parse_mjcf(xml, Path::new("."), "test.xml").unwrap_err()
}

fn urdf_err(xml: &str) -> FieldError {
    urdf::parse_urdf(xml, Path::new("."), "test.urdf").unwrap_err()
}

fn hand_err(xml: &str) -> FieldError {
    KinematicHand::from_mjcf_str(xml, ".").unwrap_err()
}

#[test]
fn malformed_xml_is_refused_with_its_position() {
    let e = mjcf_err("<mujoco><worldbody><body></worldbody></mujoco>");
    assert_eq!(e.field, "hand.mjcf");
    assert!(e.message.contains("malformed XML"), "{e}");
    assert!(e.message.contains("test.xml"), "{e}");
    let e = urdf_err("<robot><link name='a'></robot");
    assert_eq!(e.field, "hand.urdf");
    assert!(e.message.contains("malformed XML"), "{e}");
    assert!(mjcf_err("<robot/>").message.contains("<mujoco>"));
    assert!(urdf_err("<mujoco/>").message.contains("<robot>"));
    let e = mjcf_err("<mujoco><worldbody><body pos='1 2'/></worldbody></mujoco>");
    assert!(
        e.message.contains("pos='1 2'") && e.message.contains(":1:"),
        "{e}"
    );
    let e = mjcf_err("<mujoco><worldbody><body><joint type='ball'/></body></worldbody></mujoco>");
    assert!(e.message.contains("ball"), "{e}");
    let e = mjcf_err("<mujoco><worldbody><body><geom class='nope'/></body></worldbody></mujoco>");
    assert!(e.message.contains("unknown default class 'nope'"), "{e}");
    // Absurd nesting is refused before the readers recurse over it.
    let deep = format!(
        "<mujoco><worldbody>{}{}</worldbody></mujoco>",
        "<body>".repeat(5000),
        "</body>".repeat(5000)
    );
    assert!(mjcf_err(&deep).message.contains("nested deeper than"));
}

#[test]
fn missing_meshes_and_includes_are_named() {
    let dir = scratch("missing");
    let main = MJCF_MAIN.replace("file=\"pad.stl\"", "file=\"gone.stl\"");
    let e = mjcf::read_mjcf_file(&write_mjcf_model(&dir, &main)).unwrap_err();
    assert_eq!(e.field, "hand.mjcf.asset.mesh[pad].file");
    assert!(
        e.message.contains("gone.stl") && e.message.contains("not found"),
        "{e}"
    );
    let main = MJCF_MAIN.replace("defaults.xml", "absent.xml");
    let e = mjcf::read_mjcf_file(&write_mjcf_model(&dir, &main)).unwrap_err();
    assert!(
        e.message.contains("absent.xml") && e.message.contains("not found"),
        "{e}"
    );
    // A file that includes itself.
    std::fs::write(
        dir.join("loop.xml"),
        "<mujoco><include file='loop.xml'/></mujoco>",
    )
    .unwrap();
    let e = mjcf::read_mjcf_file(&dir.join("loop.xml")).unwrap_err();
    assert!(e.message.contains("more than once"), "{e}");
    // A mesh file that is not a mesh.
    std::fs::write(dir.join("parts/pad.stl"), b"not a mesh").unwrap();
    std::fs::write(dir.join("hand.xml"), MJCF_MAIN).unwrap();
    let e = mjcf::read_mjcf_file(&dir.join("hand.xml")).unwrap_err();
    assert_eq!(e.field, "hand.mjcf.asset.mesh[pad]");
    let e = urdf::parse_urdf(
        "<robot name='r'><link name='a'><collision><geometry><mesh filename='package://p/m.stl'/>\
         </geometry></collision></link></robot>",
        &dir,
        "r.urdf",
    )
    .unwrap_err();
    assert_eq!(e.field, "hand.urdf.link[a].mesh");
    assert!(e.message.contains("package://p/m.stl"), "{e}");
}

#[test]
fn trees_without_fingers_are_refused() {
    let e = hand_err(
        "<mujoco><worldbody><body name='palm'><geom size='0.1'/></body></worldbody></mujoco>",
    );
    assert_eq!(e.field, "hand.fingers");
    assert!(e.message.contains("no fingers"), "{e}");
    // One jointed chain is one finger: not a hand.
    let e = hand_err(
        "<mujoco><worldbody><body name='palm'><body name='f'><joint/><body name='t'/></body>\
         <body name='cam'/></body></worldbody></mujoco>",
    );
    assert_eq!(e.field, "hand.fingers");
    let e =
        KinematicHand::from_urdf_str("<robot name='r'><link name='a'/></robot>", ".").unwrap_err();
    assert_eq!(e.field, "hand.fingers");
}

#[test]
fn cyclic_or_disconnected_urdf_is_refused() {
    let links = "<link name='a'/><link name='b'/><link name='c'/>";
    let joint = |n: &str, p: &str, c: &str| {
        format!("<joint name='{n}' type='fixed'><parent link='{p}'/><child link='{c}'/></joint>")
    };
    // Two roots.
    let e = urdf_err(&format!(
        "<robot name='r'>{links}{}</robot>",
        joint("j", "a", "b")
    ));
    assert!(
        e.message.contains("disconnected") && e.message.contains("a, c"),
        "{e}"
    );
    // A link with two parents.
    let e = urdf_err(&format!(
        "<robot name='r'>{links}{}{}</robot>",
        joint("j1", "a", "c"),
        joint("j2", "b", "c")
    ));
    assert_eq!(e.field, "hand.urdf.joint[j2].child");
    assert!(e.message.contains("only one parent"), "{e}");
    // A joint to an unknown link.
    let e = urdf_err(&format!(
        "<robot name='r'>{links}{}</robot>",
        joint("j", "a", "zz")
    ));
    assert_eq!(e.field, "hand.urdf.joint[j].child");
    assert!(e.message.contains("unknown link 'zz'"), "{e}");
    // A cycle through every link: no root.
    let e = urdf_err(&format!(
        "<robot name='r'>{links}{}{}{}</robot>",
        joint("j1", "a", "b"),
        joint("j2", "b", "c"),
        joint("j3", "c", "a")
    ));
    assert!(e.message.contains("cycle"), "{e}");
    // A cycle beside the root.
    let e = urdf_err(&format!(
        "<robot name='r'>{links}<link name='d'/>{}{}{}</robot>",
        joint("j1", "a", "b"),
        joint("j2", "c", "d"),
        joint("j3", "d", "c")
    ));
    assert!(
        e.message.contains("c, d") && e.message.contains("cycle"),
        "{e}"
    );
    // Duplicate names.
    assert!(
        urdf_err("<robot name='r'><link name='a'/><link name='a'/></robot>")
            .message
            .contains("duplicate")
    );
}

#[test]
fn absurd_joint_limits_are_refused() {
    let mj = |attrs: &str| {
        mjcf_err(&format!(
            "<mujoco><compiler angle='radian'/><worldbody><body><joint name='j' {attrs}/></body>\
             </worldbody></mujoco>"
        ))
    };
    let e = mj("range='1 0.5'");
    assert_eq!(e.field, "hand.mjcf.joint[j].range");
    assert!(
        e.message.contains("lower limit 1 is above upper limit 0.5"),
        "{e}"
    );
    let e = mj("range='0 nan'");
    assert!(e.message.contains("finite"), "{e}");
    let e = mj("range='-10 10'");
    assert!(e.message.contains("> 2π"), "{e}");
    let e = mj("type='slide' range='0 3'");
    assert!(e.message.contains("> 1 m"), "{e}");
    // Degrees (MuJoCo's default unit) are converted before the check: 0..400° is too wide, 0..90° fine.
    let deg = |r: &str| {
        mjcf::parse_mjcf(
            &format!(
                "<mujoco><worldbody><body><joint name='j' range='{r}'/></body></worldbody></mujoco>"
            ),
            Path::new("."),
            "t.xml",
        )
    };
    assert!(deg("0 400").unwrap_err().message.contains("> 2π"));
    assert!((deg("0 90").unwrap().joints[0].range.unwrap().1 - FRAC_PI_2).abs() < 1e-12);
    let ur = |lim: &str| {
        urdf_err(&format!(
            "<robot name='r'><link name='a'/><link name='b'/><joint name='j' type='revolute'>\
             <parent link='a'/><child link='b'/>{lim}</joint></robot>"
        ))
    };
    let e = ur("<limit lower='0.5' upper='-0.5'/>");
    assert_eq!(e.field, "hand.urdf.joint[j].range");
    assert!(
        ur("<limit lower='-inf' upper='1'/>")
            .message
            .contains("finite")
    );
    assert!(ur("<limit lower='-4' upper='4'/>").message.contains("> 2π"));
    assert_eq!(ur("").field, "hand.urdf.joint[j].limit");
}
