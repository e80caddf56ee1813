//! Latency of a reaching trajectory (`graspd_core::reaching::plan_reach`, dissertation §3.3),
//! single thread: p50 and p99 over repeated plans of a 57 cm reach to a top grasp (1.5 s of
//! reach and 0.6 s of approach at 10 ms, MPC horizon 30 steps), with no obstacle, with the
//! post of the tests in the way, and with six boxes on the table (the dissertation's scenes
//! hold 3–6 objects). `cargo bench -p graspd-core --bench reach`.

use graspd_core::cloud::Plane;
use graspd_core::reaching::{Obstacle, ReachOptions, ReachRequest, Scene, plan_reach};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use std::hint::black_box;
use std::time::Instant;

fn request(obstacles: Vec<Obstacle>) -> ReachRequest {
    ReachRequest {
        start: Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.4), UnitQuaternion::identity()),
        goal: Isometry3::from_parts(
            Translation3::new(0.5, 0.2, 0.1),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI),
        ),
        approach: -Vector3::z(),
        pregrasp_distance: 0.1,
        scene: Scene {
            obstacles,
            table: Some(Plane::checked(Vector3::z(), 0.0, "table").expect("a plane")),
            hand_radius: 0.04,
        },
        demonstrations: Vec::new(),
        options: ReachOptions::default(),
    }
}

fn cube(x: f64, y: f64, h: f64) -> Obstacle {
    Obstacle {
        centre: Point3::new(x, y, h),
        half_extents: Vector3::new(0.04, 0.04, h),
        orientation: UnitQuaternion::identity(),
    }
}

fn main() {
    let cases = [
        ("no obstacle", request(Vec::new())),
        ("a post in the way", request(vec![cube(0.25, 0.1, 0.15)])),
        (
            "six boxes on the table",
            request(vec![
                cube(0.25, 0.1, 0.15),
                cube(0.5, -0.1, 0.08),
                cube(0.7, 0.25, 0.1),
                cube(0.35, 0.35, 0.06),
                cube(0.1, 0.3, 0.12),
                cube(0.6, 0.45, 0.05),
            ]),
        ),
    ];
    println!("| scene | p50 | p99 | samples |");
    println!("|---|---:|---:|---:|");
    for (name, req) in &cases {
        let mut times = Vec::new();
        let mut samples = 0;
        for _ in 0..60 {
            let t = Instant::now();
            let r = black_box(plan_reach(black_box(req))).expect("a reach");
            times.push(t.elapsed().as_secs_f64() * 1e3);
            samples = r.samples.len();
        }
        times.sort_by(f64::total_cmp);
        let at = |q: f64| times[((times.len() - 1) as f64 * q).round() as usize];
        println!(
            "| {name} | {:.1} ms | {:.1} ms | {samples} |",
            at(0.5),
            at(0.99)
        );
    }
}
