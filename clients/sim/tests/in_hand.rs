//! The in-hand rotation task (dissertation §7.5, issue 19) in MuJoCo: the block rests on the
//! still hand for a whole episode, a drop is latched and paid at Eq 7.12's −10, r_hand follows
//! Eq 7.5 on the hand's joints (with hand-made synergies, and with the ones a real graspd serves
//! on loopback), and the trainer's pipe answers with the documented layout.

use graspd_core::GraspType;
use graspd_core::hand::PostureSynergies;
use graspd_core::hand::posture_synergies::LabelledPosture;
use graspd_sim::hand::SimHand;
use graspd_sim::in_hand::env::{
    DROP_Z, EPISODE_STEPS, InHandEnv, InHandObject, InHandScene, InHandTask, TargetRotation,
};
use graspd_sim::in_hand::env_server::{STEP_EXTRAS, serve};
use graspd_sim::in_hand::hand_reward::HandReward;
use graspd_sim::service::Service;

fn shadow_scene(object: InHandObject) -> Option<InHandScene> {
    let d = graspd_testkit::testdata_dir();
    if !d.join("hands").is_dir() {
        eprintln!("skipped: {} not found", d.display());
        return None;
    }
    let hand = SimHand::load("shadow", &d.join("hands")).unwrap();
    let task = InHandTask {
        object,
        rotation: TargetRotation::Z,
    };
    Some(InHandScene::build(&hand, task).unwrap())
}

/// Synergies of the scene's joints fitted to postures in which only `rh_FFJ3` and `rh_MFJ3`
/// move: e₁ and e₂ span those two joints, so d_hand is the squared distance of the two angles'
/// deviations from the precision postures' mean, in the plane of the components.
fn two_joint_synergies(scene: &InHandScene) -> PostureSynergies {
    let names: Vec<String> = scene
        .hand_joints
        .iter()
        .map(|(n, _, _)| n.clone())
        .collect();
    let (ff, mf) = (index(scene, "rh_FFJ3"), index(scene, "rh_MFJ3"));
    let posture = |a: f64, b: f64, grasp_type| {
        let mut joints = vec![0.0; names.len()];
        joints[ff] = a;
        joints[mf] = b;
        LabelledPosture { joints, grasp_type }
    };
    let postures = [
        posture(1.0, 0.2, GraspType::Precision),
        posture(1.2, 0.4, GraspType::Precision),
        posture(0.0, 0.0, GraspType::LargeWrap),
        posture(0.2, 1.0, GraspType::LargeWrap),
    ];
    PostureSynergies::fit(names, &postures).unwrap()
}

fn index(scene: &InHandScene, name: &str) -> usize {
    scene
        .hand_joints
        .iter()
        .position(|(n, _, _)| n == name)
        .unwrap()
}

#[test]
fn the_block_rests_on_the_still_hand_for_a_whole_episode() {
    let Some(scene) = shadow_scene(InHandObject::Block) else {
        return;
    };
    assert_eq!(scene.state_dim(), 68, "24 joints × 2 + 6 + 7 + 7 (§7.5.1)");
    assert_eq!(scene.action_dim(), 20);
    let mut env = InHandEnv::new(&scene, 3);
    let s0 = env.reset();
    assert_eq!(s0.len(), 68);
    // The object lies on the palm (its surface at about 0.017 m: the 5 cm cube's centre 2.5 cm
    // above it).
    let p = env.object_position();
    assert!((p[2] - 0.042).abs() < 0.006, "settled at {p:?}");
    let still = vec![0.0_f32; 20];
    for t in 1..=EPISODE_STEPS {
        let step = env.step(&still);
        assert!(!step.dropped, "dropped at step {t}");
        assert_eq!(step.done, t == EPISODE_STEPS, "step {t}");
        // r_ext is Eq 7.12 of the reported angle.
        let want = if step.angle < 0.1 {
            50.0
        } else {
            -(step.angle - 0.1) / 4.9
        };
        assert!((step.r_ext - want).abs() < 1e-9, "{} vs {want}", step.r_ext);
        assert_eq!(step.success, step.angle < 0.1);
    }
    let q = env.object_position();
    assert!(
        (q[0] - p[0]).hypot(q[1] - p[1]) < 0.01,
        "the still hand moved the block from {p:?} to {q:?}"
    );
}

#[test]
fn a_drop_is_latched_and_costs_minus_ten_each_step_to_the_episode_end() {
    let Some(scene) = shadow_scene(InHandObject::Egg) else {
        return;
    };
    let mut env = InHandEnv::new(&scene, 0);
    env.reset();
    // The egg teleported below the palm: dropped.
    let z = env.object_position()[2];
    let k = scene.object_qpos + 2;
    env.data.qpos_mut()[k] = DROP_Z - 0.05;
    env.data.qvel_mut().fill(0.0);
    let still = vec![0.0_f32; scene.action_dim()];
    let first = env.step(&still);
    assert!(first.dropped && !first.success && !first.done);
    assert_eq!(first.r_ext, -10.0);
    // Back on the palm it stays dropped: the episode is lost.
    env.data.qpos_mut()[k] = z;
    env.data.qvel_mut().fill(0.0);
    let second = env.step(&still);
    assert!(second.dropped && !second.success);
    assert_eq!(second.r_ext, -10.0);
}

#[test]
fn r_hand_is_eq_7_5_of_the_distance_to_the_precision_centre() {
    let Some(scene) = shadow_scene(InHandObject::Block) else {
        return;
    };
    let reward = HandReward::new(two_joint_synergies(&scene), &scene).unwrap();
    let (ff, mf) = (index(&scene, "rh_FFJ3"), index(&scene, "rh_MFJ3"));
    let at = |a: f64, b: f64| {
        let mut q = vec![0.0; scene.hand_joints.len()];
        q[ff] = a;
        q[mf] = b;
        q
    };
    // The precision centre is the mean of its postures, (1.1, 0.3): the components span the
    // plane, so d_hand is the plain squared distance there.
    assert!(reward.distance(&at(1.1, 0.3)) < 1e-12);
    let d = reward.distance(&at(1.1 + 0.3, 0.3 - 0.4));
    assert!((d - 0.25).abs() < 1e-9, "{d}");
    assert_eq!(reward.reward(&at(1.1, 0.3)), 1.5);
    // d = 0.9: −(0.9 − 0.4) / (1.4 − 0.4) = −0.5.
    let q = at(1.1 + 0.9_f64.sqrt(), 0.3);
    assert!((reward.reward(&q) + 0.5).abs() < 1e-9);
    // The open hand lies 1.1² + 0.3² = 1.3 away: −0.9.
    assert!((reward.reward(&at(0.0, 0.0)) + 0.9).abs() < 1e-9);
    assert_eq!(reward.reward(&at(-1.0, 0.0)), -10.0);
}

#[test]
fn r_hand_needs_the_hands_joints_and_a_precision_centre() {
    let Some(scene) = shadow_scene(InHandObject::Block) else {
        return;
    };
    let mut renamed = two_joint_synergies(&scene);
    renamed.joints[0] = "not_a_joint".into();
    let e = HandReward::new(renamed, &scene).err().unwrap().to_string();
    assert!(e.contains("not_a_joint"), "{e}");
    let mut no_precision = two_joint_synergies(&scene);
    no_precision
        .centres
        .retain(|c| c.grasp_type != GraspType::Precision);
    let e = HandReward::new(no_precision, &scene)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("precision"), "{e}");
}

#[test]
fn the_trainers_pipe_answers_with_the_documented_layout() {
    let Some(scene) = shadow_scene(InHandObject::Block) else {
        return;
    };
    let reward = HandReward::new(two_joint_synergies(&scene), &scene).unwrap();
    let (d, nu, envs) = (scene.state_dim(), scene.action_dim(), 2);
    let mut input = b"R".to_vec();
    for _ in 0..EPISODE_STEPS {
        input.push(b'S');
        input.extend(std::iter::repeat_n(0.0_f32.to_le_bytes(), envs * nu).flatten());
    }
    input.push(b'Q');
    let mut output = Vec::new();
    serve(&scene, &reward, envs, 7, &input[..], &mut output).unwrap();
    let newline = output.iter().position(|&b| b == b'\n').unwrap();
    let header: serde_json::Value = serde_json::from_slice(&output[..newline]).unwrap();
    assert_eq!(header["state_dim"], 68);
    assert_eq!(header["action_dim"], 20);
    assert_eq!(header["envs"], 2);
    assert_eq!(header["joints"][0], "rh_WRJ2");
    let numbers: Vec<f32> = output[newline + 1..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let row = 2 * d + STEP_EXTRAS;
    assert_eq!(numbers.len(), envs * d + EPISODE_STEPS * envs * row);
    let steps = &numbers[envs * d..];
    for (t, rows) in steps.chunks_exact(envs * row).enumerate() {
        for r in rows.chunks_exact(row) {
            let (s1, next, extras) = (&r[..d], &r[d..2 * d], &r[2 * d..]);
            let flags = extras[3] as u32;
            let done = flags & 1 == 1;
            assert_eq!(done, t + 1 == EPISODE_STEPS, "step {t}");
            // Before the end the next state is s_{t+1}; at the end a fresh episode's s₀.
            assert_eq!(s1 == next, !done, "step {t}");
            // r_ext of the reported angle (Eq 7.12).
            let angle = f64::from(extras[2]);
            let want = if angle < 0.1 {
                50.0
            } else {
                -(angle - 0.1) / 4.9
            };
            assert!((f64::from(extras[0]) - want).abs() < 1e-4);
        }
    }
    // An unknown command is refused by name.
    let e = serve(&scene, &reward, 1, 0, &b"X"[..], &mut Vec::new())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("unknown command"), "{e}");
}

/// The synergies graspd fits to its own Shadow plans, fetched as graspd-sim in-hand-env fetches
/// them (the hand registered by the client, then GetHandSynergies): every joint maps onto the
/// scene, and the open hand the episodes start from lies far from the precision centre.
#[test]
fn r_hand_from_the_synergies_a_running_graspd_serves() {
    let Some(scene) = shadow_scene(InHandObject::Block) else {
        return;
    };
    let server = graspd_e2e::Server::start();
    let rt = tokio::runtime::Runtime::new().unwrap();
    let service =
        Service::connect(&format!("http://{}", server.grpc_addr), rt.handle().clone()).unwrap();
    let hand = SimHand::load("shadow", &graspd_testkit::testdata_dir().join("hands")).unwrap();
    service.ensure_hand(&hand).unwrap();
    let synergies = service.hand_synergies(&hand.graspd_hand).unwrap();
    assert_eq!(synergies.joints.len(), 24);
    let precision = synergies
        .centres
        .iter()
        .find(|c| c.grasp_type == GraspType::Precision)
        .expect("the Shadow's plans include precision grasps")
        .amplitudes[..2]
        .to_vec();
    let reward = HandReward::new(synergies.clone(), &scene).unwrap();
    let mut env = InHandEnv::new(&scene, 1);
    env.reset();
    let open = env.joint_angles();
    assert!(reward.distance(&open) > 1.4, "{}", reward.distance(&open));
    assert_eq!(reward.reward(&open), -10.0);
    // The precision centre's posture (Eq 7.3), in the scene's joint order, earns 1.5.
    let centre = synergies.posture(&precision);
    let mut q = vec![0.0; scene.hand_joints.len()];
    for (name, v) in synergies.joints.iter().zip(&centre) {
        q[index(&scene, name)] = *v;
    }
    assert!(reward.distance(&q) < 1e-9);
    assert_eq!(reward.reward(&q), 1.5);
}
