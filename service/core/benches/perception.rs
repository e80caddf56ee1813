//! Criterion benchmark of the perception front end on a 640×480 RGB-D frame rendered from the
//! YCB meshes (tomato soup can and mustard bottle on a table): decoding (raw rgb8 + 16UC1, and
//! PNG + 16-bit PNG), back-projection to a cloud, segmentation (RANSAC support plane, Euclidean
//! clustering, target choice), the VOCUS2 saliency map, and decode + cloud + segmentation
//! with and without saliency.
//! `cargo bench -p graspd-core --bench perception`.

use criterion::{Criterion, criterion_group, criterion_main};
use graspd_core::perception::{
    CameraIntrinsics, CloudFrame, ColorEncoding, DepthEncoding, ImageData, RgbdFrame, RgbdLimits,
    SaliencyParams, SegmentationParams, TargetHint, depth_to_cloud, saliency_map, segment,
};
use graspd_testkit::Object;
use graspd_testkit::rgbd::{RgbdRender, RgbdScene, SceneObject};
use image::{ImageEncoder, codecs::png::PngEncoder};
use std::hint::black_box;

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

fn png(data: &[u8], w: usize, h: usize, ty: image::ExtendedColorType) -> Vec<u8> {
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(data, w as u32, h as u32, ty)
        .unwrap();
    out
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
        data: png(&r.rgb, r.width, r.height, image::ExtendedColorType::Rgb8),
        step: 0,
    };
    let mm: Vec<u8> = r.depth_mm().iter().flat_map(|d| d.to_ne_bytes()).collect();
    png_frame.depth = ImageData {
        encoding: DepthEncoding::Png16,
        data: png(&mm, r.width, r.height, image::ExtendedColorType::L16),
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
    g.finish();
}

criterion_group!(benches, bench_perception);
criterion_main!(benches);
