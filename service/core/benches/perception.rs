//! Criterion benchmark of the perception front end on a 640×480 RGB-D frame rendered from the
//! YCB meshes (tomato soup can and mustard bottle on a table): decoding (raw rgb8 + 16UC1, and
//! PNG + 16-bit PNG), back-projection to a cloud, segmentation (RANSAC support plane, Euclidean
//! clustering, target choice), the VOCUS2 saliency map, and decode + cloud + segmentation
//! with and without saliency; the mean-shift ROI; the whole chain to Ω without a model and with
//! a 4→16→16→6 3 × 3 FCN through ONNX Runtime (1 thread; needs `ORT_DYLIB_PATH`, else those
//! rows are skipped); and Ω plus the plan.
//! `cargo bench -p graspd-core --bench perception`.

#[path = "../tests/common/onnx_builder.rs"]
mod onnx_builder;

use criterion::{Criterion, criterion_group, criterion_main};
use graspd_core::onnx_runtime::init_onnx_runtime;
use graspd_core::perception::{
    CameraIntrinsics, CloudFrame, ColorEncoding, DepthEncoding, GraspTypeModel, ImageData,
    InformationParams, PerceptionModels, RegionParams, RgbdFrame, RgbdLimits, SaliencyParams,
    SegmentationParams, TargetHint, depth_to_cloud, grasp_information, saliency_map,
    salient_regions, segment,
};
use graspd_core::{HandCatalog, PlanHints, PlanInput, PlannerOptions, plan};
use graspd_testkit::Object;
use graspd_testkit::rgbd::{RgbdRender, RgbdScene, SceneObject};
use std::hint::black_box;

/// The grasp-type model alone.
fn models(m: Option<&GraspTypeModel>) -> PerceptionModels<'_> {
    PerceptionModels {
        grasp_type: m,
        recogniser: None,
    }
}

fn frame(r: &RgbdRender) -> RgbdFrame {
    RgbdFrame {
        color: ImageData {
            encoding: ColorEncoding::Rgb8,
            data: r.rgb.clone(),
            step: 0,
        },
        depth: ImageData {
            encoding: DepthEncoding::Mono16,
            data: r.depth_mm_le(),
            step: 0,
        },
        width: r.width,
        height: r.height,
        intrinsics: CameraIntrinsics {
            fx: r.intrinsics.fx,
            fy: r.intrinsics.fy,
            cx: r.intrinsics.cx,
            cy: r.intrinsics.cy,
        },
        depth_scale: None,
        camera_to_world: Some(r.camera_to_world),
    }
}

fn bench_perception(c: &mut Criterion) {
    let r = RgbdScene::on_table(vec![
        SceneObject::new(Object::TomatoSoupCan, 0.0, -0.09, [200, 40, 30]),
        SceneObject::new(Object::MustardBottle, 0.03, 0.1, [30, 60, 200]),
    ])
    .render()
    .expect("test data");
    let raw = frame(&r);
    let mut png_frame = raw.clone();
    png_frame.color = ImageData {
        encoding: ColorEncoding::Png,
        data: r.color_png(),
        step: 0,
    };
    png_frame.depth = ImageData {
        encoding: DepthEncoding::Png16,
        data: r.depth_png(),
        step: 0,
    };
    let lim = RgbdLimits::default();
    let params = SegmentationParams::default();
    let decoded = raw.decode("rgbd", &lim).unwrap();
    let cloud = depth_to_cloud(&decoded, CloudFrame::World);

    let mut g = c.benchmark_group("perception_640x480");
    g.sample_size(30);
    g.bench_function("decode_raw_rgb8_16uc1", |b| {
        b.iter(|| black_box(raw.decode("rgbd", &lim).unwrap()))
    });
    g.bench_function("decode_png_png16", |b| {
        b.iter(|| black_box(png_frame.decode("rgbd", &lim).unwrap()))
    });
    g.bench_function("depth_to_cloud", |b| {
        b.iter(|| black_box(depth_to_cloud(&decoded, CloudFrame::World)))
    });
    g.bench_function("segmentation", |b| {
        b.iter(|| black_box(segment(&cloud, TargetHint::Auto, None, None, &params).unwrap()))
    });
    let sal = SaliencyParams::default();
    g.bench_function("saliency_vocus2", |b| {
        b.iter(|| {
            black_box(saliency_map(
                &decoded.rgb,
                decoded.width,
                decoded.height,
                &sal,
            ))
        })
    });
    g.bench_function("decode_cloud_saliency_segmentation_raw", |b| {
        b.iter(|| {
            let d = raw.decode("rgbd", &lim).unwrap();
            let c = depth_to_cloud(&d, CloudFrame::World);
            let m = saliency_map(&d.rgb, d.width, d.height, &sal);
            black_box(segment(&c, TargetHint::Auto, Some(&m.data), None, &params).unwrap())
        })
    });
    g.bench_function("decode_cloud_segmentation_raw", |b| {
        b.iter(|| {
            let d = raw.decode("rgbd", &lim).unwrap();
            let c = depth_to_cloud(&d, CloudFrame::World);
            black_box(segment(&c, TargetHint::Auto, None, None, &params).unwrap())
        })
    });
    g.bench_function("decode_cloud_segmentation_png", |b| {
        b.iter(|| {
            let d = png_frame.decode("rgbd", &lim).unwrap();
            let c = depth_to_cloud(&d, CloudFrame::World);
            black_box(segment(&c, TargetHint::Auto, None, None, &params).unwrap())
        })
    });
    let map = saliency_map(&decoded.rgb, decoded.width, decoded.height, &sal);
    g.bench_function("mean_shift_regions", |b| {
        b.iter(|| black_box(salient_regions(&map, &RegionParams::default())))
    });
    let info_params = InformationParams::default();
    let model = init_onnx_runtime(None).ok().map(|()| {
        let path =
            std::env::temp_dir().join(format!("graspd-bench-fcn-{}.onnx", std::process::id()));
        std::fs::write(&path, onnx_builder::small_fcn(4).build()).unwrap();
        GraspTypeModel::load(&path, 1).unwrap()
    });
    if model.is_none() {
        eprintln!("ORT_DYLIB_PATH unset or unloadable: the model rows are skipped");
    }
    // The shipped network (models/grasp_type), as graspd loads it by default.
    let shipped = model.as_ref().map(|_| {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../models/grasp_type/grasp_type.onnx"
        );
        GraspTypeModel::load(std::path::Path::new(path), 1).unwrap()
    });
    let hand = HandCatalog::builtin().get("shadow").cloned().unwrap();
    let realisable = hand.realisable_types();
    for (name, m) in [
        ("no_model", None),
        ("fcn_4_16_16_6", model.as_ref()),
        ("shipped_unet", shipped.as_ref()),
    ] {
        if name != "no_model" && m.is_none() {
            continue;
        }
        if let Some(m) = m {
            g.bench_function(format!("model_inference_1_thread_{name}"), |b| {
                b.iter(|| black_box(m.infer(&decoded).unwrap()))
            });
        }
        g.bench_function(format!("grasp_information_{name}"), |b| {
            b.iter(|| {
                let d = raw.decode("rgbd", &lim).unwrap();
                black_box(
                    grasp_information(
                        &d,
                        TargetHint::Auto,
                        None,
                        models(m),
                        &realisable,
                        &info_params,
                    )
                    .unwrap(),
                )
            })
        });
        g.bench_function(format!("rgbd_plan_shadow_{name}"), |b| {
            b.iter(|| {
                let d = raw.decode("rgbd", &lim).unwrap();
                let info = grasp_information(
                    &d,
                    TargetHint::Auto,
                    None,
                    models(m),
                    &realisable,
                    &info_params,
                )
                .unwrap();
                black_box(
                    plan(PlanInput {
                        cloud: info.object,
                        hand: hand.clone(),
                        hints: PlanHints {
                            support_plane: info.plane,
                            viewpoint: Some(info.viewpoint),
                            attention_point: info.attention_point,
                            detected_types: info.detection.map(|d| d.probabilities),
                            ..Default::default()
                        },
                        options: PlannerOptions::default(),
                        kinematics: None,
                        grasp_quality: None,
                    })
                    .unwrap(),
                )
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_perception);
criterion_main!(benches);
