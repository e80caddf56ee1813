//! RGB-D frames as received (rgb8/bgr8/PNG/JPEG colour, 16UC1/32FC1/16-bit PNG depth): decoding
//! under a small pixel limit, then the whole perception chain to Ω (saliency, segmentation,
//! ROI) when the frame decodes. Layout: byte 0 picks the encodings, bytes 1–2 the size (each
//! side 1..=64), bytes 3–4 where the colour bytes end; the rest is colour then depth data.
#![no_main]
use graspd_core::GraspType;
use graspd_core::perception::{
    CameraIntrinsics, ColorEncoding, DepthEncoding, ImageData, InformationParams, PerceptionModels,
    RgbdFrame, RgbdLimits, TargetHint, grasp_information,
};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 5 {
        return;
    }
    let colors = [
        ColorEncoding::Rgb8,
        ColorEncoding::Bgr8,
        ColorEncoding::Png,
        ColorEncoding::Jpeg,
    ];
    let depths = [
        DepthEncoding::Mono16,
        DepthEncoding::Float32,
        DepthEncoding::Png16,
    ];
    let (w, h) = (1 + (data[1] % 64) as usize, 1 + (data[2] % 64) as usize);
    let body = &data[5..];
    let split = (u16::from_le_bytes([data[3], data[4]]) as usize).min(body.len());
    let frame = RgbdFrame {
        color: ImageData {
            encoding: colors[(data[0] % 4) as usize],
            data: body[..split].to_vec(),
            step: 0,
        },
        depth: ImageData {
            encoding: depths[((data[0] / 4) % 3) as usize],
            data: body[split..].to_vec(),
            step: 0,
        },
        width: w,
        height: h,
        intrinsics: CameraIntrinsics {
            fx: 50.0,
            fy: 50.0,
            cx: w as f64 / 2.0,
            cy: h as f64 / 2.0,
        },
        depth_scale: None,
        camera_to_world: None,
    };
    let Ok(decoded) = frame.decode("rgbd", &RgbdLimits { max_pixels: 4096 }) else {
        return;
    };
    let hint = match data[0] / 12 % 3 {
        0 => TargetHint::Auto,
        1 => TargetHint::Pixel {
            u: data[1] as u32 % 70,
            v: data[2] as u32 % 70,
        },
        _ => TargetHint::Region {
            u_min: 0,
            v_min: 0,
            u_max: w as u32,
            v_max: h as u32 / 2 + 1,
        },
    };
    let _ = grasp_information(
        &decoded,
        hint,
        None,
        PerceptionModels::default(),
        &GraspType::ALL,
        &InformationParams::default(),
    );
});
