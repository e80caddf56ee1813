//! What `GRASPD_SIM_DEBUG_DIR=DIR` saves of a trial, for looking at it: a picture of each
//! phase, the plan's posed depth in the true object and the grip after the close and after the
//! lift.

use crate::camera::{self, Intrinsics};
use crate::trial::world::Trial;
use mujoco_rs::prelude::*;
use nalgebra::Vector3;

/// With GRASPD_SIM_DEBUG_DIR set, saves a picture of each phase there (for looking at a trial):
/// two views of the object, from the front left and from the right, far enough to see a tall
/// object's top and the hand above it.
pub(crate) fn snapshot(trial: &mut Trial, phase: &str) {
    if let Some(dir) = std::env::var_os("GRASPD_SIM_DEBUG_DIR") {
        let o = trial.object_position() + Vector3::new(0.0, 0.0, 0.09);
        let mut imgs = Vec::new();
        for eye in [
            Vector3::new(-0.35, -0.32, 0.26),
            Vector3::new(0.4, -0.2, 0.3),
        ] {
            let view = camera::look_at(o + eye, o);
            imgs.push(trial.render(Intrinsics::kinect(360, 270), view));
        }
        let (w, h) = (imgs[0].intrinsics.width, imgs[0].intrinsics.height);
        let mut rgb = Vec::with_capacity(imgs[0].rgb.len() * 2);
        for row in 0..h as usize {
            for img in &imgs {
                let stride = 3 * w as usize;
                rgb.extend_from_slice(&img.rgb[row * stride..(row + 1) * stride]);
            }
        }
        let _ = image::save_buffer(
            std::path::Path::new(&dir).join(format!("{phase}.png")),
            &rgb,
            2 * w,
            h,
            image::ExtendedColorType::Rgb8,
        );
    }
}

/// With GRASPD_SIM_DEBUG_DIR set, appends the hand's normal force on the object, each
/// actuator's command at the touch and at the squeeze, position and force to `forces.txt` (for
/// looking at a grip).
pub(crate) fn forces(trial: &Trial, phase: &str, touch: &[f64], target: &[f64]) {
    let Some(dir) = std::env::var_os("GRASPD_SIM_DEBUG_DIR") else {
        return;
    };
    let m = &trial.scene.model;
    let mut normal = 0.0;
    let mut per_body: std::collections::BTreeMap<String, f64> = Default::default();
    for (i, other) in trial.hand_contacts_with_object() {
        let f = trial.data.contact_force(i)[0].max(0.0);
        normal += f;
        let name = m
            .id_to_name(MjtObjBase::mjOBJ_BODY, other)
            .unwrap_or_default()
            .to_string();
        *per_body.entry(name).or_default() += f;
    }
    let mut text = format!("{phase}: normal force on the object {normal:.2} N\n");
    for (b, f) in &per_body {
        text += &format!("  {b}: {f:.2} N\n");
    }
    let nu = m.ffi().nu as usize;
    let len = trial.data.actuator_length();
    let force = trial.data.actuator_force();
    for a in 0..nu {
        let name = m
            .id_to_name(MjtObjBase::mjOBJ_ACTUATOR, a)
            .unwrap_or_default();
        text += &format!(
            "  {name}: touch {:.3} target {:.3} length {:.3} force {:.3}\n",
            touch[a], target[a], len[a], force[a]
        );
    }
    let path = std::path::Path::new(&dir).join("forces.txt");
    let old = std::fs::read_to_string(&path).unwrap_or_default();
    let _ = std::fs::write(path, old + &text);
}

/// With GRASPD_SIM_DEBUG_DIR set, appends how deep each hand body is in the object at the
/// current (kinematically posed) state to `forces.txt`, and the gap to it of every hand body
/// within 3 cm (negative: inside): how far the plan's touch and squeeze are from the true
/// surface.
pub(crate) fn penetration(trial: &Trial, phase: &str) {
    let Some(dir) = std::env::var_os("GRASPD_SIM_DEBUG_DIR") else {
        return;
    };
    let m = &trial.scene.model;
    let mut deepest: std::collections::BTreeMap<String, f64> = Default::default();
    for (i, other) in trial.hand_contacts_with_object() {
        let d = -trial.data.contact()[i].dist;
        let name = m
            .id_to_name(MjtObjBase::mjOBJ_BODY, other)
            .unwrap_or_default()
            .to_string();
        let e = deepest.entry(name).or_insert(f64::NEG_INFINITY);
        *e = e.max(d);
    }
    let mut text = format!("{phase} (posed): depth in the true object per hand body\n");
    for (b, d) in &deepest {
        text += &format!("  {b}: {:.1} mm\n", d * 1e3);
    }
    // The gap of every hand body within 3 cm of the object (negative: inside).
    let bodyof = m.geom_bodyid().to_vec();
    let obj = trial.scene.object_bodies[0];
    let mut data = m.make_data();
    data.qpos_mut().copy_from_slice(trial.data.qpos());
    data.forward();
    let mut nearest: std::collections::BTreeMap<String, f64> = Default::default();
    for g in 0..bodyof.len() {
        if !trial.scene.hand_bodies[bodyof[g] as usize] {
            continue;
        }
        for o in (0..bodyof.len()).filter(|&o| bodyof[o] as usize == obj) {
            let d = data.geom_distance(g, o, 0.03, None);
            if d < 0.03 {
                let name = m
                    .id_to_name(MjtObjBase::mjOBJ_BODY, bodyof[g] as usize)
                    .unwrap_or_default()
                    .to_string();
                let e = nearest.entry(name).or_insert(f64::INFINITY);
                *e = e.min(d);
            }
        }
    }
    text += "  gaps (mm):";
    for (b, d) in &nearest {
        text += &format!(" {b} {:.1}", d * 1e3);
    }
    text += "\n";
    let path = std::path::Path::new(&dir).join("forces.txt");
    let old = std::fs::read_to_string(&path).unwrap_or_default();
    let _ = std::fs::write(path, old + &text);
}
