//! Perception on RGB-D frames rendered from the YCB meshes (graspd_testkit::rgbd): decoding of
//! every encoding, field-named errors for bad frames, segmentation of the target object from
//! the table (mask IoU against the renderer's ground truth, points on the mesh surface) and the
//! choice of the target by hints.

use graspd_core::perception::{
    CameraIntrinsics, CloudFrame, ColorEncoding, DecodedFrame, DepthEncoding, ImageData,
    InformationParams, PerceptionModels, RgbdFrame, RgbdLimits, SaliencyParams, SegmentationParams,
    TargetChoice, TargetHint, depth_to_cloud, grasp_information, saliency_map, segment,
};
use graspd_testkit::Object;
use graspd_testkit::rgbd::{RgbdRender, RgbdScene, SceneObject};
use image::{ImageEncoder, codecs::jpeg::JpegEncoder, codecs::png::PngEncoder};

const RED: [u8; 3] = [200, 40, 30];
const BLUE: [u8; 3] = [30, 60, 200];

fn raw_frame(r: &RgbdRender, with_pose: bool) -> RgbdFrame {
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
        camera_to_world: with_pose.then_some(r.camera_to_world),
    }
}

fn png(data: &[u8], w: usize, h: usize, ty: image::ExtendedColorType) -> Vec<u8> {
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(data, w as u32, h as u32, ty)
        .unwrap();
    out
}

fn decode(f: &RgbdFrame) -> DecodedFrame {
    f.decode("rgbd", &RgbdLimits::default()).unwrap()
}

fn iou(a: &[bool], b: &[bool]) -> f64 {
    let inter = a.iter().zip(b).filter(|(x, y)| **x && **y).count();
    let union = a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    inter as f64 / union.max(1) as f64
}

fn two_objects() -> RgbdRender {
    RgbdScene::on_table(vec![
        SceneObject::new(Object::TomatoSoupCan, 0.0, -0.09, RED),
        SceneObject::new(Object::MustardBottle, 0.03, 0.1, BLUE),
    ])
    .render()
    .unwrap()
}

#[test]
fn each_table_5_2_object_is_segmented_from_the_table() {
    for object in Object::TABLE_5_2 {
        let mut scene = RgbdScene::on_table(vec![SceneObject::new(object, 0.0, 0.0, RED)]);
        scene.depth_noise_sigma = 0.0005;
        let r = scene.render().unwrap();
        let frame = decode(&raw_frame(&r, true));
        let cloud = depth_to_cloud(&frame, CloudFrame::World);
        assert_eq!(cloud.frame, CloudFrame::World);
        let s = segment(
            &cloud,
            TargetHint::Auto,
            None,
            None,
            &SegmentationParams::default(),
        )
        .unwrap();
        let plane = s.plane.expect("the table is found");
        assert!(
            plane.normal.z > 0.999 && plane.offset.abs() < 0.002,
            "{object}: {plane:?}"
        );
        assert_eq!(s.choice, TargetChoice::ImageCentre);
        let score = iou(&s.mask, &r.object_mask(0));
        assert!(score >= 0.8, "{object}: mask IoU {score:.3}");
        let worst = s
            .object
            .points
            .iter()
            .map(|p| r.distance_to_object(0, p))
            .fold(0.0, f64::max);
        eprintln!(
            "{object}: IoU {score:.3}, {} points, farthest {:.2} mm off the mesh",
            s.object.len(),
            worst * 1e3
        );
        assert!(worst <= 0.003, "{object}: a point {worst} m off the mesh");
        assert!(s.object.len() > 1000, "{object}: {} points", s.object.len());
    }
}

#[test]
fn a_hint_pixel_or_region_picks_the_right_one_of_two_objects() {
    let r = two_objects();
    let frame = decode(&raw_frame(&r, false));
    let cloud = depth_to_cloud(&frame, CloudFrame::Camera);
    let params = SegmentationParams::default();
    for k in 0..2 {
        let (u, v) = r.object_pixel(k);
        let s = segment(&cloud, TargetHint::Pixel { u, v }, None, None, &params).unwrap();
        assert_eq!(s.choice, TargetChoice::Pixel);
        assert_eq!(s.clusters.len(), 2, "two objects on the table");
        let score = iou(&s.mask, &r.object_mask(k));
        assert!(score >= 0.8, "object {k}: IoU {score:.3}");
        assert!(iou(&s.mask, &r.object_mask(1 - k)) < 0.01);
        // A box around the object's centre pixel picks it too.
        let region = TargetHint::Region {
            u_min: u.saturating_sub(10),
            v_min: v.saturating_sub(10),
            u_max: u + 10,
            v_max: v + 10,
        };
        let s = segment(&cloud, region, None, None, &params).unwrap();
        assert_eq!(s.choice, TargetChoice::Region);
        assert!(iou(&s.mask, &r.object_mask(k)) >= 0.8);
    }
    // Camera frame: the table's normal points toward the camera (negative z component).
    let s = segment(&cloud, TargetHint::Auto, None, None, &params).unwrap();
    assert!(s.plane.unwrap().normal.z < -0.5);
}

#[test]
fn colour_and_depth_round_trip_through_png_16_bit_png_and_jpeg() {
    let r = two_objects();
    let (w, h) = (r.width, r.height);
    let raw = raw_frame(&r, false);
    let reference = decode(&raw);
    // PNG colour, 16-bit PNG depth (millimetres): identical to the raw frame.
    let mut f = raw.clone();
    f.color = ImageData {
        encoding: ColorEncoding::Png,
        data: png(&r.rgb, w, h, image::ExtendedColorType::Rgb8),
        step: 0,
    };
    let mm: Vec<u8> = r.depth_mm().iter().flat_map(|d| d.to_ne_bytes()).collect();
    f.depth = ImageData {
        encoding: DepthEncoding::Png16,
        data: png(&mm, w, h, image::ExtendedColorType::L16),
        step: 0,
    };
    let d = decode(&f);
    assert_eq!(d.rgb, reference.rgb);
    assert_eq!(d.depth, reference.depth);
    // JPEG colour: close to the original (lossy), depth as 32FC1 metres exact.
    let mut jpeg = Vec::new();
    JpegEncoder::new_with_quality(&mut jpeg, 95)
        .write_image(&r.rgb, w as u32, h as u32, image::ExtendedColorType::Rgb8)
        .unwrap();
    f.color = ImageData {
        encoding: ColorEncoding::Jpeg,
        data: jpeg,
        step: 0,
    };
    f.depth = ImageData {
        encoding: DepthEncoding::Float32,
        data: r.depth_f32_le(),
        step: 0,
    };
    let d = decode(&f);
    let mean_err = d
        .rgb
        .iter()
        .zip(&r.rgb)
        .map(|(a, b)| (*a as f64 - *b as f64).abs())
        .sum::<f64>()
        / d.rgb.len() as f64;
    assert!(mean_err < 3.0, "JPEG mean error {mean_err}");
    assert_eq!(d.depth, r.depth);
    // BGR8 with padded rows.
    let step = 3 * w + 5;
    let mut bgr = vec![0u8; step * h];
    for v in 0..h {
        for u in 0..w {
            let s = 3 * (v * w + u);
            bgr[v * step + 3 * u..v * step + 3 * u + 3].copy_from_slice(&[
                r.rgb[s + 2],
                r.rgb[s + 1],
                r.rgb[s],
            ]);
        }
    }
    f.color = ImageData {
        encoding: ColorEncoding::Bgr8,
        data: bgr,
        step,
    };
    assert_eq!(decode(&f).rgb, reference.rgb);
}

/// The error of `frame` (decoded with `limits`): its field and message.
fn error(frame: &RgbdFrame, limits: &RgbdLimits) -> (String, String) {
    let e = frame.decode("rgbd", limits).unwrap_err();
    (e.field, e.message)
}

#[test]
fn bad_frames_name_the_field() {
    let r = two_objects();
    let good = raw_frame(&r, false);
    let lim = RgbdLimits::default();

    let mut f = good.clone();
    f.color.data.pop();
    let (field, msg) = error(&f, &lim);
    assert_eq!(field, "rgbd.color.data");
    assert_eq!(msg, "921599 bytes, expected 921600 for 640×480 rgb8");

    // Depth of another size than the colour (a 320×240 16UC1 image in a 640×480 frame).
    let mut f = good.clone();
    f.depth.data.truncate(320 * 240 * 2);
    let (field, msg) = error(&f, &lim);
    assert_eq!(field, "rgbd.depth.data");
    assert!(msg.contains("expected 614400 for 640×480 16UC1"), "{msg}");
    let mut f = good.clone();
    f.depth = ImageData {
        encoding: DepthEncoding::Png16,
        data: png(
            &vec![0u8; 320 * 240 * 2],
            320,
            240,
            image::ExtendedColorType::L16,
        ),
        step: 0,
    };
    let (field, msg) = error(&f, &lim);
    assert_eq!(field, "rgbd.depth.data");
    assert!(msg.contains("320×240") && msg.contains("640×480"), "{msg}");

    // Unknown encodings are refused where the wire name is parsed.
    let e = ColorEncoding::parse("rgba16", "rgbd.color.encoding").unwrap_err();
    assert_eq!(e.field, "rgbd.color.encoding");
    let e = DepthEncoding::parse("mono8", "rgbd.depth.encoding").unwrap_err();
    assert_eq!(e.field, "rgbd.depth.encoding");

    // Truncated PNG.
    let mut f = good.clone();
    let full = png(&r.rgb, 640, 480, image::ExtendedColorType::Rgb8);
    f.color = ImageData {
        encoding: ColorEncoding::Png,
        data: full[..full.len() / 2].to_vec(),
        step: 0,
    };
    let (field, msg) = error(&f, &lim);
    assert_eq!(field, "rgbd.color.data");
    assert!(msg.contains("not a readable PNG"), "{msg}");
    // An 8-bit PNG where 16-bit depth is due.
    let mut f = good.clone();
    f.depth = ImageData {
        encoding: DepthEncoding::Png16,
        data: png(
            &vec![9u8; 640 * 480],
            640,
            480,
            image::ExtendedColorType::L8,
        ),
        step: 0,
    };
    let (field, msg) = error(&f, &lim);
    assert_eq!(field, "rgbd.depth.data");
    assert!(msg.contains("16-bit"), "{msg}");

    // Intrinsics: zero, negative, non-finite.
    for (name, value) in [
        ("fx", 0.0),
        ("fy", -525.0),
        ("fx", f64::NAN),
        ("cx", f64::INFINITY),
    ] {
        let mut f = good.clone();
        match name {
            "fx" => f.intrinsics.fx = value,
            "fy" => f.intrinsics.fy = value,
            _ => f.intrinsics.cx = value,
        }
        let (field, _) = error(&f, &lim);
        assert_eq!(field, format!("rgbd.intrinsics.{name}"));
    }
    let mut f = good.clone();
    f.depth_scale = Some(0.0);
    assert_eq!(error(&f, &lim).0, "rgbd.depth_scale");

    // Larger than the configured limit.
    let small = RgbdLimits {
        max_pixels: 640 * 479,
    };
    let (field, msg) = error(&good, &small);
    assert_eq!(field, "rgbd");
    assert!(msg.contains("307200 pixels exceed"), "{msg}");

    // All-invalid depth: zeros, and NaN/inf in 32FC1.
    let mut f = good.clone();
    f.depth.data = vec![0; 640 * 480 * 2];
    let (field, msg) = error(&f, &lim);
    assert_eq!(field, "rgbd.depth.data");
    assert!(msg.contains("no valid depth"), "{msg}");
    f.depth = ImageData {
        encoding: DepthEncoding::Float32,
        data: (0..640 * 480)
            .flat_map(|i| if i % 2 == 0 { f32::NAN } else { f32::INFINITY }.to_le_bytes())
            .collect(),
        step: 0,
    };
    assert_eq!(error(&f, &lim).0, "rgbd.depth.data");
}

#[test]
fn invalid_depth_pixels_are_skipped_not_propagated() {
    let r = two_objects();
    let mut f = raw_frame(&r, true);
    f.depth = ImageData {
        encoding: DepthEncoding::Float32,
        data: r
            .depth
            .iter()
            .enumerate()
            .flat_map(|(i, &d)| if i % 3 == 0 { f32::NAN } else { d }.to_le_bytes())
            .collect(),
        step: 0,
    };
    let d = decode(&f);
    let cloud = depth_to_cloud(&d, CloudFrame::World);
    let expected = r
        .depth
        .iter()
        .enumerate()
        .filter(|(i, d)| i % 3 != 0 && **d > 0.0)
        .count();
    assert_eq!(cloud.cloud.len(), expected);
    assert!(
        cloud
            .cloud
            .points
            .iter()
            .all(|p| p.coords.iter().all(|v| v.is_finite()))
    );
    // Still segments: a third of the pixels missing leaves the clusters connected.
    let s = segment(
        &cloud,
        TargetHint::Pixel {
            u: r.object_pixel(1).0,
            v: r.object_pixel(1).1,
        },
        None,
        None,
        &SegmentationParams::default(),
    )
    .unwrap();
    assert!(iou(&s.mask, &r.object_mask(1)) > 0.55);
}

#[test]
fn without_a_hint_the_most_salient_object_is_the_target() {
    // One object red, the other nearly the table's grey, then the colours swapped: in one of
    // the two scenes the image-centre rule would take the grey one.
    let grey = [160, 158, 150];
    for (k, colours) in [(0usize, [RED, grey]), (1, [grey, RED])] {
        let r = RgbdScene::on_table(vec![
            SceneObject::new(Object::TomatoSoupCan, 0.0, -0.09, colours[0]),
            SceneObject::new(Object::MustardBottle, 0.03, 0.1, colours[1]),
        ])
        .render()
        .unwrap();
        let frame = decode(&raw_frame(&r, false));
        let map = saliency_map(
            &frame.rgb,
            frame.width,
            frame.height,
            &SaliencyParams::default(),
        );
        let cloud = depth_to_cloud(&frame, CloudFrame::Camera);
        let params = SegmentationParams::default();
        let s = segment(&cloud, TargetHint::Auto, Some(&map.data), None, &params).unwrap();
        assert_eq!(s.choice, TargetChoice::Saliency);
        let score = iou(&s.mask, &r.object_mask(k));
        assert!(score >= 0.8, "red object {k}: IoU {score:.3}");
    }
}

/// The whole chain of method.md §4 without a model, then the planner on its output: the target
/// is the object, the ROI lies on it and covers most of it, the hint pixel's attention point is
/// on the mesh, and the plan's contacts are object points.
#[test]
fn grasp_information_then_a_plan_for_each_table_5_2_object() {
    let hand = graspd_core::HandCatalog::builtin()
        .get("parallel_gripper")
        .cloned()
        .unwrap();
    for object in Object::TABLE_5_2 {
        let r = RgbdScene::on_table(vec![SceneObject::new(object, 0.0, 0.0, RED)])
            .render()
            .unwrap();
        let frame = decode(&raw_frame(&r, true));
        let truth = r.object_mask(0);
        let (u, v) = r.object_pixel(0);
        for hint in [TargetHint::Auto, TargetHint::Pixel { u, v }] {
            let info = grasp_information(
                &frame,
                hint.clone(),
                None,
                PerceptionModels::default(),
                &hand.realisable_types(),
                &InformationParams::default(),
            )
            .unwrap();
            let on_object = info
                .roi
                .iter()
                .zip(&truth)
                .filter(|(a, b)| **a && **b)
                .count();
            let truth_n = truth.iter().filter(|t| **t).count();
            let precision = on_object as f64 / info.roi_pixels.max(1) as f64;
            let coverage = on_object as f64 / truth_n as f64;
            eprintln!(
                "{object} {hint:?}: ROI {:?} {} px, precision {precision:.3}, coverage {coverage:.3}, {:.1} ms",
                info.roi_box,
                info.roi_pixels,
                info.timings.total * 1e3
            );
            assert!(precision >= 0.98, "{object}: ROI precision {precision:.3}");
            assert!(
                coverage >= 0.75,
                "{object}: ROI covers {coverage:.3} of the object"
            );
            assert!(info.detection.is_none() && info.model_error.is_none());
            match hint {
                TargetHint::Auto => {
                    assert_eq!(info.target_choice, TargetChoice::Saliency);
                    assert!(info.attention_point.is_none());
                }
                _ => {
                    assert_eq!(info.target_choice, TargetChoice::Pixel);
                    let p = info.attention_point.unwrap();
                    let d = r.distance_to_object(0, &p);
                    assert!(d <= 0.003, "{object}: attention point {d} m off the mesh");
                    let (au, av) = info.attention_pixel.unwrap();
                    assert!((au - u as f64).abs() <= 3.0 && (av - v as f64).abs() <= 3.0);
                }
            }
            let plan = graspd_core::plan(graspd_core::PlanInput {
                cloud: info.object.clone(),
                hand: hand.clone(),
                hints: graspd_core::PlanHints {
                    support_plane: info.plane,
                    viewpoint: Some(info.viewpoint),
                    attention_point: info.attention_point,
                    ..Default::default()
                },
                options: graspd_core::PlannerOptions::default(),
                kinematics: None,
                grasp_quality: None,
            })
            .unwrap();
            // Seen contacts on the mesh; those on the mirror-completed side near it (the YCB
            // objects are only nearly symmetric).
            for c in &plan.contacts {
                let d = r.distance_to_object(0, &c.position);
                let limit = if c.inferred {
                    graspd_testkit::ycb::MAX_INFERRED_OFF
                } else {
                    0.003
                };
                assert!(
                    d <= limit,
                    "{object}: contact {d} m off the mesh (inferred: {})",
                    c.inferred
                );
            }
            assert!(plan.collision.min_plane_clearance.is_some());
            eprintln!(
                "  plan: {} feasible {} S {:.3}",
                plan.grasp_type, plan.feasible, plan.quality.gii
            );
        }
    }
}
