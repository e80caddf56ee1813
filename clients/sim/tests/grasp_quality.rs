//! The shipped grasp-quality network (models/grasp_quality/grasp_quality.onnx) against physics
//! on scenes it was not trained on: `label-grasps`' protocol on 24 scenes of a seed range
//! train.sh does not use (half YCB objects, half generated primitives), 8 sampled 2F-85 grasps
//! each executed in MuJoCo, rated by graspd's own loading, cropping and inference code. The
//! network must tell held from dropped (a broken export, a contract change or a drift between
//! the crop of training and of serving fails here), and the grasp it rates highest in a scene
//! must hold more often than the scene's average grasp — what the planner relies on.
//!
//! Needs MuJoCo and ONNX Runtime (`make test` provides both) and ../shared/testdata.

use graspd_core::planning::grasp_quality::GraspQualityModel;
use graspd_core::planning::grasp_quality::crop::GraspView;
use graspd_sim::camera::{Intrinsics, default_view};
use graspd_sim::labels::{LabelConfig, label_scenes};
use graspd_sim::object::{BEYOND_TABLE_5_2, TABLE_5_2, is_shared_ycb};
use graspd_sim::trial::TrialOptions;

/// Scenes of train.sh's labels are seeds 0..3000.
const HELD_OUT_SEED: u64 = 900_000;

#[test]
fn shipped_grasp_quality_tells_held_from_dropped_on_unseen_scenes() {
    let testdata = graspd_testkit::testdata_dir();
    let config = LabelConfig {
        hand: "robotiq_2f85".into(),
        objects: [TABLE_5_2.as_slice(), &BEYOND_TABLE_5_2]
            .concat()
            .into_iter()
            .filter(|o| is_shared_ycb(o))
            .map(String::from)
            .collect(),
        scenes: 24,
        per_scene: 8,
        seed: HELD_OUT_SEED,
        jobs: 2,
        out: std::env::temp_dir(),
        hands_dir: testdata.join("hands"),
        objects_dir: testdata.join("objects"),
        options: TrialOptions {
            intrinsics: Intrinsics::kinect(640, 480),
            camera: default_view(),
            cloud_input: false,
            replans: 0,
            snapshot: None,
            guarded_close: true,
            candidate: 0,
            grasp_type: None,
            place_range: 0.1,
            views: 1,
            gravity_test: false,
            grip_reflex: true,
            mode: None,
        },
    };
    let (records, summary) = label_scenes(&config).unwrap();
    assert!(records.len() >= 150, "{summary:?}");
    let model = GraspQualityModel::load(
        std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../models/grasp_quality/grasp_quality.onnx"
        )),
        1,
    )
    .unwrap();
    let views: Vec<GraspView> = records
        .iter()
        .map(|r| GraspView {
            crop: r.crop.clone(),
            configuration: r.configuration,
        })
        .collect();
    let p = model.quality(&views).unwrap();
    let right = records
        .iter()
        .zip(&p)
        .filter(|(r, q)| (**q >= 0.5) == (r.label == 1))
        .count();
    let accuracy = right as f64 / records.len() as f64;
    let (mut top, mut mean, mut scenes) = (0.0, 0.0, 0);
    for seed in HELD_OUT_SEED..HELD_OUT_SEED + 24 {
        let k: Vec<usize> = (0..records.len())
            .filter(|&i| records[i].scene_seed == seed)
            .collect();
        if k.len() < 2 || k.iter().all(|&i| records[i].label == 0) {
            continue;
        }
        let best = *k.iter().max_by(|&&a, &&b| p[a].total_cmp(&p[b])).unwrap();
        top += f64::from(records[best].label);
        mean += k.iter().map(|&i| f64::from(records[i].label)).sum::<f64>() / k.len() as f64;
        scenes += 1;
    }
    let (top, mean) = (top / scenes as f64, mean / scenes as f64);
    println!(
        "{} grasps, {:.0} % held; accuracy {accuracy:.3}; over {scenes} scenes with a hold the \
         top-rated grasp held {top:.3}, the average grasp {mean:.3}",
        records.len(),
        100.0 * summary.positives as f64 / records.len() as f64
    );
    assert!(accuracy >= 0.8, "accuracy {accuracy}");
    assert!(
        top >= mean + 0.2,
        "top-rated {top} against the average {mean}"
    );
}
