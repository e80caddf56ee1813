//! `options.mode = learned_quality` (dissertation ch. 3) with the shipped grasp-quality network
//! (models/grasp_quality/grasp_quality.onnx) and the Robotiq 2F-85's kinematics, in-process:
//! plans come down (within the slope of the line between the jaws' contacts) with the network's P(success), the Gaussian process's posterior
//! and the search's cost; the search ends within its budget; a seed gives one plan; requests
//! the mode cannot serve name `options.mode`.
//!
//! Needs ONNX Runtime (`$ORT_DYLIB_PATH`, set by `make test`).

use graspd_core::error::PlanError;
use graspd_core::hand::kinematics::KinematicHand;
use graspd_core::planning::grasp_quality::GraspQualityModel;
use graspd_core::planning::{
    GraspPlan, KinematicModel, PlanHints, PlanInput, PlannerMode, PlannerOptions, plan,
};
use graspd_testkit::view::standard_view;
use graspd_testkit::ycb::Object;
use std::sync::Arc;

fn network() -> Arc<GraspQualityModel> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/grasp_quality/grasp_quality.onnx"
    );
    Arc::new(GraspQualityModel::load(std::path::Path::new(path), 1).unwrap())
}

fn model(file: &str) -> Arc<KinematicModel> {
    let path = graspd_testkit::testdata_dir().join("hands").join(file);
    Arc::new(KinematicModel::new(KinematicHand::from_mjcf_file(&path).unwrap()).unwrap())
}

fn plan_on(
    m: &Arc<KinematicModel>,
    object: Object,
    seed: u64,
    network: Option<Arc<GraspQualityModel>>,
) -> Result<GraspPlan, PlanError> {
    let v = standard_view(object, 2000, seed);
    plan(PlanInput {
        cloud: v.object_cloud(),
        hand: m.describe().unwrap(),
        hints: PlanHints {
            support_plane: Some(v.support_plane),
            viewpoint: Some(v.viewpoint),
            ..Default::default()
        },
        options: PlannerOptions {
            seed,
            mode: PlannerMode::LearnedQuality,
            ..Default::default()
        },
        kinematics: Some(m.clone()),
        grasp_quality: network,
    })
}

#[test]
fn the_gripper_plans_down_with_the_learned_quality() {
    let gripper = model("robotiq_2f85/2f85.xml");
    let net = network();
    let mut feasible = 0;
    let objects = [
        Object::TomatoSoupCan,
        Object::MustardBottle,
        Object::Banana,
        Object::PottedMeatCan,
    ];
    for object in objects {
        let p = plan_on(&gripper, object, 1, Some(net.clone())).unwrap();
        let lq = p.learned_quality.clone().expect("learned_quality");
        println!(
            "{object:?}: feasible={} P={:.3} μ={:.3} σ={:.3} calls={} of {} {:?}",
            p.feasible,
            lq.probability,
            lq.posterior_mean,
            lq.posterior_std,
            lq.network_calls,
            lq.candidates,
            p.infeasible_reason
        );
        assert_eq!(p.mode, PlannerMode::LearnedQuality);
        assert_eq!(p.grasp_type.name(), "pinch");
        assert!((0.0..=1.0).contains(&lq.probability));
        assert!(lq.network_calls <= 60 && lq.network_calls <= lq.candidates);
        assert!(
            lq.posterior_std < 0.2,
            "σ = {} at a grasp it observed",
            lq.posterior_std
        );
        // Down, made perpendicular to the line between the two contacts (which leans by the
        // contacts' heights within the jaws' 6 mm tube).
        let a = p.approach.unwrap();
        assert!(a.z < -0.98, "{object:?}: approach {a:?}");
        assert!(
            !p.joints.is_empty() && !p.squeeze_joints.is_empty(),
            "{object:?}"
        );
        feasible += usize::from(p.feasible);
    }
    // Whether they hold is graspd-sim's to say (docs/sim-benchmark.md, "Learned quality"); here
    // at least half are feasible by graspd's own judge.
    assert!(feasible >= 2, "{feasible} of {} feasible", objects.len());
    // One seed, one plan.
    let a = plan_on(&gripper, Object::Banana, 4, Some(net.clone())).unwrap();
    let b = plan_on(&gripper, Object::Banana, 4, Some(net)).unwrap();
    assert_eq!(a.hand_pose, b.hand_pose);
    assert_eq!(a.learned_quality, b.learned_quality);
}

#[test]
fn requests_the_mode_cannot_serve_name_it() {
    let field_of = |r: Result<GraspPlan, PlanError>| match r {
        Err(PlanError::InvalidInput(e)) => (e.field, e.message),
        other => panic!("{:?}", other.map(|p| p.feasible)),
    };
    // No network loaded.
    let (field, message) = field_of(plan_on(
        &model("robotiq_2f85/2f85.xml"),
        Object::TomatoSoupCan,
        1,
        None,
    ));
    assert_eq!(field, "options.mode");
    assert!(message.contains("network"), "{message}");
    // A hand whose pinch is not between two single jaws.
    let (field, message) = field_of(plan_on(
        &model("shadow_hand/right_hand.xml"),
        Object::TomatoSoupCan,
        1,
        Some(network()),
    ));
    assert_eq!(field, "options.mode");
    assert!(message.contains("two-jaw"), "{message}");
}
