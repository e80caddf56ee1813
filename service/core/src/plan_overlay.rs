//! A picture of a plan for people (issue 3), drawn over what perception saw (so it sits above
//! both perception and planning): the colour image with the heat map of s* (or the ROI
//! tinted when no model ran), the ROI box, the attention point, the projected contacts, the
//! pregrasping opposition and the approach from the pre-grasp to the grasp pose.
//!
//! Colours: ROI box yellow (the ROI itself tinted yellow when no model ran), attention point
//! white ring with a red centre, opposition cyan, contacts green, approach magenta, heat map red
//! with the probability as opacity.

use crate::perception::{DecodedFrame, GraspInformation};
use crate::planning::GraspPlan;
use image::{ImageFormat, Rgb, RgbImage};
use imageproc::drawing::{
    draw_filled_circle_mut, draw_hollow_circle_mut, draw_hollow_rect_mut, draw_line_segment_mut,
};
use imageproc::rect::Rect;
use nalgebra::Point3;
use std::io::Cursor;

const YELLOW: Rgb<u8> = Rgb([255, 220, 0]);
const WHITE: Rgb<u8> = Rgb([255, 255, 255]);
const RED: Rgb<u8> = Rgb([230, 20, 20]);
const CYAN: Rgb<u8> = Rgb([0, 230, 255]);
const GREEN: Rgb<u8> = Rgb([40, 220, 60]);
const MAGENTA: Rgb<u8> = Rgb([240, 40, 240]);

/// The pixel where a point of the plan's frame appears, `None` behind the camera.
pub fn project(frame: &DecodedFrame, p: &Point3<f64>) -> Option<(f32, f32)> {
    let c = match &frame.camera_to_world {
        Some(t) => t.inverse_transform_point(p),
        None => *p,
    };
    if c.z <= 1e-6 {
        return None;
    }
    let k = &frame.intrinsics;
    Some((
        (k.fx * c.x / c.z + k.cx) as f32,
        (k.fy * c.y / c.z + k.cy) as f32,
    ))
}

/// The overlay as PNG bytes (see the module docs).
pub fn draw_overlay(frame: &DecodedFrame, info: &GraspInformation, plan: &GraspPlan) -> Vec<u8> {
    let (w, h) = (frame.width, frame.height);
    let mut img = RgbImage::from_raw(w as u32, h as u32, frame.rgb.clone())
        .expect("a decoded frame holds 3 bytes per pixel");
    // Heat map of s* over the whole image (the model's view), or the ROI tinted.
    let s_star = info.detection.as_ref().map(|d| (d, plan.grasp_type));
    for v in 0..h {
        for u in 0..w {
            let (alpha, tint) = match s_star {
                Some((d, s)) => {
                    let (mu, mv) = d.maps.map_pixel(u, v, w, h);
                    (0.6 * d.maps.prob(s, mu, mv), RED)
                }
                None if info.roi[v * w + u] => (0.3, YELLOW),
                None => (0.0, RED),
            };
            if alpha > 0.0 {
                let px = img.get_pixel_mut(u as u32, v as u32);
                for (c, target) in px.0.iter_mut().zip(tint.0) {
                    *c = (*c as f32 * (1.0 - alpha) + target as f32 * alpha) as u8;
                }
            }
        }
    }
    let [u0, v0, u1, v1] = info.roi_box;
    if u1 > u0 && v1 > v0 {
        for grow in 0..2 {
            draw_hollow_rect_mut(
                &mut img,
                Rect::at(u0 as i32 - grow, v0 as i32 - grow)
                    .of_size(u1 - u0 + 2 * grow as u32, v1 - v0 + 2 * grow as u32),
                YELLOW,
            );
        }
    }
    let [a, b] = plan.opposition.points;
    if let (Some(pa), Some(pb)) = (project(frame, &a), project(frame, &b)) {
        thick_line(&mut img, pa, pb, CYAN);
        for p in [pa, pb] {
            draw_hollow_circle_mut(&mut img, (p.0 as i32, p.1 as i32), 6, CYAN);
        }
    }
    for c in &plan.contacts {
        if let Some(p) = project(frame, &c.position) {
            draw_filled_circle_mut(&mut img, (p.0 as i32, p.1 as i32), 4, GREEN);
        }
    }
    let (pre, grasp) = (plan.pregrasp_pose.position, plan.hand_pose.position);
    if let (Some(p0), Some(p1)) = (project(frame, &pre), project(frame, &grasp)) {
        thick_line(&mut img, p0, p1, MAGENTA);
        draw_filled_circle_mut(&mut img, (p1.0 as i32, p1.1 as i32), 3, MAGENTA);
    }
    let att = info
        .attention_pixel
        .map(|(u, v)| (u as f32, v as f32))
        .or_else(|| project(frame, &plan.attention_point));
    if let Some((u, v)) = att {
        draw_hollow_circle_mut(&mut img, (u as i32, v as i32), 9, WHITE);
        draw_hollow_circle_mut(&mut img, (u as i32, v as i32), 10, WHITE);
        draw_filled_circle_mut(&mut img, (u as i32, v as i32), 3, RED);
    }
    let mut png = Vec::new();
    img.write_to(&mut Cursor::new(&mut png), ImageFormat::Png)
        .expect("PNG encoding into memory");
    png
}

/// A 3-pixel-wide segment.
fn thick_line(img: &mut RgbImage, a: (f32, f32), b: (f32, f32), color: Rgb<u8>) {
    for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)] {
        draw_line_segment_mut(img, (a.0 + dx, a.1 + dy), (b.0 + dx, b.1 + dy), color);
    }
}
