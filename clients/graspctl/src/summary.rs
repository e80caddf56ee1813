//! Human-readable summaries of plans and hands.

use graspd_api::convert::{plane_source_name, type_source_name};
use graspd_api::request::HandSynergies;
use graspd_core::planning::{Pose, StageStats};
use graspd_core::{GraspPlan, GraspType, HandDescription};
use nalgebra::{Point3, Vector3};
use std::fmt::Write;

fn p(v: &Point3<f64>) -> String {
    format!("({:.4}, {:.4}, {:.4})", v.x, v.y, v.z)
}

fn n(v: &Vector3<f64>) -> String {
    format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z)
}

fn pose(pose: &Pose) -> String {
    let q = pose.orientation;
    format!(
        "position {} m, quaternion (x {:.4}, y {:.4}, z {:.4}, w {:.4})",
        p(&pose.position),
        q.i,
        q.j,
        q.k,
        q.w
    )
}

fn stage(s: &StageStats) -> String {
    format!(
        "|Φ| {:.3e}, {} candidates, {} iterations (best at {}), {} evaluations, {} accepted, {} restarts, feasible found: {}, {:.3} s",
        s.solution_space,
        s.candidates,
        s.iterations,
        s.best_iteration,
        s.evaluations,
        s.accepted,
        s.restarts,
        if s.feasible_found { "yes" } else { "no" },
        s.seconds
    )
}

pub fn plan(plan: &GraspPlan) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "hand            {}", plan.hand);
    let requested = if plan.requested_type != plan.grasp_type {
        format!(", requested {}", plan.requested_type)
    } else {
        String::new()
    };
    let _ = writeln!(
        w,
        "grasp type      {} (source: {}{requested})",
        plan.grasp_type,
        type_source_name(plan.type_source)
    );
    let scores: Vec<String> = GraspType::ALL
        .iter()
        .zip(plan.type_scores)
        .map(|(t, v)| format!("{t} {v:.2}"))
        .collect();
    let _ = writeln!(w, "type scores     {}", scores.join(", "));
    match &plan.infeasible_reason {
        _ if plan.feasible => {
            let _ = writeln!(w, "feasible        yes");
        }
        Some(reason) => {
            let _ = writeln!(w, "feasible        NO: {reason}");
        }
        None => {
            let _ = writeln!(w, "feasible        NO");
        }
    }
    let _ = writeln!(
        w,
        "attention       {} normal {}",
        p(&plan.attention_point),
        n(&plan.attention_normal)
    );
    let o = &plan.opposition;
    let _ = writeln!(
        w,
        "opposition      {}-{}: {} {} normal {}, {} {} normal {}",
        o.h1,
        o.h2,
        o.h1,
        p(&o.points[0]),
        n(&o.normals[0]),
        o.h2,
        p(&o.points[1]),
        n(&o.normals[1])
    );
    let _ = writeln!(w, "contacts        {}", plan.contacts.len());
    for c in &plan.contacts {
        let _ = writeln!(
            w,
            "  {:<8} {:<2} {} normal {} (point {})",
            c.finger,
            c.part.code(),
            p(&c.position),
            n(&c.normal),
            c.point_index
        );
    }
    let _ = writeln!(w, "hand pose       {}", pose(&plan.hand_pose));
    let _ = writeln!(w, "pre-grasp pose  {}", pose(&plan.pregrasp_pose));
    if !plan.joints.is_empty() {
        let joints: Vec<String> = plan
            .joints
            .iter()
            .map(|(name, a)| format!("{name} {a:.3}"))
            .collect();
        let _ = writeln!(w, "joints (rad)    {}", joints.join(", "));
    }
    let q = &plan.quality;
    let _ = writeln!(
        w,
        "quality         S (GII) {:.4}  R {:.4}  G {:.4}  Q {:.4}  ε {:.4}",
        q.gii, q.reachability, q.attention, q.objective, q.epsilon
    );
    let _ = writeln!(
        w,
        "                aperture/area {:.4}  palm height {:.4} m",
        q.aperture_or_area, q.palm_height
    );
    match &plan.support_plane {
        Some(pl) => {
            let _ = writeln!(
                w,
                "support plane   normal {} offset {:.4} ({})",
                n(&pl.normal),
                pl.offset,
                plane_source_name(plan.plane_source)
            );
        }
        None => {
            let _ = writeln!(w, "support plane   none");
        }
    }
    if let Some(p) = &plan.perception {
        let [u0, v0, u1, v1] = p.roi;
        let _ = writeln!(
            w,
            "perception      {}×{} frame, {} objects, target by {} ({} points), ROI u {u0}..{u1} v {v0}..{v1} ({} px){}, {:.1} ms",
            p.width,
            p.height,
            p.objects,
            p.target_source.name(),
            p.object_points,
            p.roi_pixels,
            p.attention_pixel
                .map(|[u, v]| format!(", attention pixel ({u:.0}, {v:.0})"))
                .unwrap_or_default(),
            p.timings.total * 1e3
        );
    }
    let c = &plan.collision;
    let collision = if !c.checked {
        "not checked".to_string()
    } else if c.clear {
        "clear".to_string()
    } else {
        format!(
            "COLLIDES: {} points at the grasp, {} at the pre-grasp, {} on the approach",
            c.final_points_in_collision,
            c.pregrasp_points_in_collision,
            c.approach_points_in_collision
        )
    };
    let _ = writeln!(w, "collision       {collision}");
    if let Some(lq) = &plan.learned_quality {
        let _ = writeln!(
            w,
            "learned quality P(success) {:.3}; search posterior {:.3} ± {:.3}; {} network calls of {} candidates",
            lq.probability, lq.posterior_mean, lq.posterior_std, lq.network_calls, lq.candidates
        );
    }
    let _ = writeln!(w, "stage 1         {}", stage(&plan.stage1));
    let _ = writeln!(w, "stage 2         {}", stage(&plan.stage2));
    let t = &plan.timings;
    let _ = writeln!(
        w,
        "timings (s)     preprocess {:.3}, normals {:.3}, grasp type {:.3}, stage 1 {:.3}, stage 2 {:.3}, finalize {:.3}, total {:.3}",
        t.preprocess, t.normals, t.grasp_type, t.stage1, t.stage2, t.finalize, t.total
    );
    let _ = writeln!(
        w,
        "points used     {}, mode {}, seed {}",
        plan.points_used,
        plan.mode.name(),
        plan.seed
    );
    for warning in &plan.warnings {
        let _ = writeln!(w, "warning         {warning}");
    }
    s
}

fn types(hand: &HandDescription) -> String {
    hand.realisable_types()
        .iter()
        .map(|t| t.name())
        .collect::<Vec<_>>()
        .join(", ")
}

pub fn hands(hands: &[HandDescription]) -> String {
    let mut s = String::new();
    for h in hands {
        let _ = writeln!(
            s,
            "{:<18} {} fingers  types: {}",
            h.name,
            h.fingers.len(),
            types(h)
        );
        if !h.description.is_empty() {
            let _ = writeln!(s, "{:<18} {}", "", h.description);
        }
    }
    s
}

pub fn hand(h: &HandDescription) -> String {
    let mut s = String::new();
    let w = &mut s;
    let g = &h.geometry;
    let _ = writeln!(w, "name            {}", h.name);
    let _ = writeln!(w, "description     {}", h.description);
    let _ = writeln!(w, "types           {}", types(h));
    let _ = writeln!(
        w,
        "palm            {:.3} × {:.3} × {:.3} m (width × length × thickness)",
        g.palm_width, g.palm_length, g.palm_thickness
    );
    let _ = writeln!(
        w,
        "aperture        {:.3} to {:.3} m, max height {:.3} m, finger width {:.3} m",
        g.min_aperture, g.max_aperture, g.max_height, g.finger_width
    );
    let _ = writeln!(w, "fingers");
    for f in &h.fingers {
        let parts: Vec<&str> = f.parts.iter().map(|p| p.code()).collect();
        let _ = writeln!(
            w,
            "  {:<8} {:<6} parts {:<6} length {:.3} m  base ({:.3}, {:.3}, {:.3})",
            f.name,
            if f.thumb { "thumb" } else { "" },
            parts.join(","),
            f.length,
            f.base[0],
            f.base[1],
            f.base[2]
        );
    }
    let _ = writeln!(w, "grasp types");
    for r in &h.grasp_types {
        let _ = writeln!(
            w,
            "  {:<11} h1 [{}]  h2 [{}]",
            r.grasp_type.name(),
            r.h1.join(", "),
            r.h2.join(", ")
        );
    }
    for e in &h.equivalent_types {
        let _ = writeln!(
            w,
            "  {:<11} same as {}",
            e.grasp_type.name(),
            e.same_as.name()
        );
    }
    s
}

/// A hand's posture synergies: the fit, the first components' shares and largest joints, and
/// each grasp type's centre on (a₁, a₂).
pub fn synergies(h: &HandSynergies) -> String {
    let mut s = String::new();
    let w = &mut s;
    let sy = &h.synergies;
    let _ = writeln!(w, "hand            {}", h.hand);
    let _ = writeln!(
        w,
        "postures        {} feasible of {} plans (seed {}), {} joints, {} components",
        sy.postures,
        h.plans,
        h.seed,
        sy.joints.len(),
        sy.components.len()
    );
    let _ = writeln!(w, "components      share  largest joints");
    for (i, c) in sy.components.iter().take(4).enumerate() {
        let mut order: Vec<usize> = (0..c.direction.len()).collect();
        order.sort_by(|&a, &b| c.direction[b].abs().total_cmp(&c.direction[a].abs()));
        let joints: Vec<String> = order
            .iter()
            .take(3)
            .map(|&j| format!("{} {:+.2}", sy.joints[j], c.direction[j]))
            .collect();
        let _ = writeln!(
            w,
            "  e{}           {:5.1} %  {}",
            i + 1,
            100.0 * c.explained,
            joints.join(", ")
        );
    }
    let _ = writeln!(w, "centres         postures  (a1, a2)");
    for c in &sy.centres {
        let a = |k: usize| c.amplitudes.get(k).copied().unwrap_or(0.0);
        let _ = writeln!(
            w,
            "  {:<13} {:>8}  ({:+.3}, {:+.3})",
            c.grasp_type.name(),
            c.postures,
            a(0),
            a(1)
        );
    }
    s
}
