//! Reaching trajectories (issue 18 part 4, dissertation §3.3): the reach ends on the grasp, at
//! rest, having reached the pre-grasp point within 5 mm; it keeps the requested clearance from
//! an obstacle its unobstructed path runs through; bad requests are refused naming the field.

use graspd_core::cloud::Plane;
use graspd_core::reaching::{Obstacle, ReachOptions, ReachRequest, Scene, plan_reach};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

/// From 40 cm above the table to a grasp from above at (0.5, 0.2, 0.1), 10 cm of approach
/// straight down; a hand of 4 cm radius.
fn request(obstacles: Vec<Obstacle>) -> ReachRequest {
    ReachRequest {
        start: Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.4), UnitQuaternion::identity()),
        goal: Isometry3::from_parts(
            Translation3::new(0.5, 0.2, 0.1),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI),
        ),
        approach: Vector3::new(0.0, 0.0, -1.0),
        pregrasp_distance: 0.1,
        scene: Scene {
            obstacles,
            table: Some(Plane::checked(Vector3::z(), 0.0, "table").unwrap()),
            hand_radius: 0.04,
        },
        demonstrations: Vec::new(),
        options: ReachOptions::default(),
    }
}

/// A box astride the unobstructed reach's path, half-way along it.
fn blocking_box() -> Obstacle {
    Obstacle {
        centre: Point3::new(0.25, 0.1, 0.3),
        half_extents: Vector3::new(0.04, 0.04, 0.15),
        orientation: UnitQuaternion::identity(),
    }
}

#[test]
fn a_free_reach_ends_on_the_grasp_at_rest() {
    let req = request(Vec::new());
    let started = std::time::Instant::now();
    let t = plan_reach(&req).unwrap();
    println!(
        "{} samples in {:?}; reach error {:.2} mm",
        t.samples.len(),
        started.elapsed(),
        t.reach_error * 1e3
    );
    let dt = req.options.time_step;
    let (first, last) = (t.samples[0], *t.samples.last().unwrap());
    assert_eq!(first.pose, req.start);
    assert!((last.pose.translation.vector - req.goal.translation.vector).norm() < 1e-9);
    assert!(last.pose.rotation.angle_to(&req.goal.rotation) < 1e-9);
    assert!(last.velocity.norm() < 1e-9, "{}", last.velocity);
    assert!(t.reach_error < 0.005, "{} m", t.reach_error);
    // 1.5 s of reach and 0.6 s of approach, one sample per step.
    assert_eq!(t.samples.len(), 1 + 150 + 60);
    for w in t.samples.windows(2) {
        assert!((w[1].time - w[0].time - dt).abs() < 1e-9);
        // No jump: the hand moves at most its speed × a step (+ a little).
        let moved = (w[1].pose.translation.vector - w[0].pose.translation.vector).norm();
        assert!(moved <= w[1].velocity.norm() * dt + 1e-3, "{moved}");
    }
    assert!(t.obstacle_clearance.is_none());
    assert!(t.table_clearance.unwrap() > 0.09);
    // The speed rises and falls once, as a human reach's does: its peak lies in the middle
    // half of the reach.
    let speeds: Vec<f64> = t.samples[..151].iter().map(|s| s.velocity.norm()).collect();
    let peak = (0..speeds.len())
        .max_by(|&a, &b| speeds[a].total_cmp(&speeds[b]))
        .unwrap();
    assert!((38..=113).contains(&peak), "peak speed at sample {peak}");
    // Deterministic.
    assert_eq!(plan_reach(&req).unwrap(), t);
}

#[test]
fn the_reach_keeps_its_clearance_from_an_obstacle_in_its_way() {
    let free = plan_reach(&request(Vec::new())).unwrap();
    let b = blocking_box();
    let closest = free
        .samples
        .iter()
        .map(|s| b.distance(&Point3::from(s.pose.translation.vector)).0 - 0.04)
        .fold(f64::INFINITY, f64::min);
    assert!(
        closest < 0.0,
        "the unobstructed reach misses the box ({closest} m)"
    );
    let req = request(vec![b]);
    let started = std::time::Instant::now();
    let t = plan_reach(&req).unwrap();
    let (c, i) = t.obstacle_clearance.unwrap();
    println!(
        "around the box in {:?}: clearance {:.1} mm (unobstructed {:.1} mm), reach error {:.2} mm",
        started.elapsed(),
        c * 1e3,
        closest * 1e3,
        t.reach_error * 1e3
    );
    assert_eq!(i, 0);
    assert!(c >= 0.01, "comes within {c} m of the box");
    assert!(t.reach_error < 0.005, "{} m", t.reach_error);
    let last = t.samples.last().unwrap();
    assert!((last.pose.translation.vector - req.goal.translation.vector).norm() < 1e-9);
}

#[test]
fn bad_reaches_are_refused_naming_the_field() {
    let field = |req: ReachRequest| plan_reach(&req).unwrap_err().field;
    // The start inside an obstacle.
    let mut r = request(vec![Obstacle {
        centre: Point3::new(0.0, 0.0, 0.4),
        half_extents: Vector3::new(0.05, 0.05, 0.05),
        orientation: UnitQuaternion::identity(),
    }]);
    assert_eq!(field(r.clone()), "start");
    // The goal inside one.
    r.scene.obstacles[0].centre = Point3::new(0.5, 0.2, 0.1);
    assert_eq!(field(r.clone()), "goal");
    // The goal under the table.
    let mut r = request(Vec::new());
    r.goal.translation.vector.z = -0.05;
    assert_eq!(field(r), "goal");
    // A goal walled in: the approach's pre-grasp point sits inside a box.
    let mut r = request(vec![Obstacle {
        centre: Point3::new(0.5, 0.2, 0.22),
        half_extents: Vector3::new(0.1, 0.1, 0.02),
        orientation: UnitQuaternion::identity(),
    }]);
    assert_eq!(field(r.clone()), "approach");
    // A wall the hand cannot get round in the time given.
    r.scene.obstacles[0] = Obstacle {
        centre: Point3::new(0.25, 0.1, 0.5),
        half_extents: Vector3::new(0.02, 3.0, 3.0),
        orientation: UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.38),
    };
    assert_eq!(field(r), "obstacles[0]");
    let mut r = request(Vec::new());
    r.approach = Vector3::zeros();
    assert_eq!(field(r), "approach");
    let mut r = request(Vec::new());
    r.start.translation.vector.x = f64::NAN;
    assert_eq!(field(r), "start");
    let mut r = request(Vec::new());
    r.options.time_step = 0.5;
    assert_eq!(field(r), "options.time_step");
    let mut r = request(vec![blocking_box()]);
    r.scene.obstacles[0].half_extents.y = -1.0;
    assert_eq!(field(r), "obstacles[0].half_extents");
}

/// A user's demonstration shapes the reach: a straight one keeps the hand on the line from the
/// start to the pre-grasp point, where the built-in one rises off it by a tenth of the reach
/// (5.7 cm here); both end on the grasp.
#[test]
fn a_posted_demonstration_shapes_the_reach() {
    use graspd_core::reaching::forcing_term::Demonstration;
    let req = request(Vec::new());
    let (a, b) = (
        req.start.translation.vector,
        Vector3::new(0.5, 0.2, 0.2), // the pre-grasp point
    );
    let off_line = |t: &graspd_core::reaching::Trajectory| {
        t.samples[..151]
            .iter()
            .map(|s| {
                let p = s.pose.translation.vector - a;
                let d = (b - a).normalize();
                (p - d * p.dot(&d)).norm()
            })
            .fold(0.0, f64::max)
    };
    let built_in = plan_reach(&req).unwrap();
    let mut req = req;
    // Sampled the way a recording is: 120 Hz, 0.8 s, a straight minimum-jerk line somewhere
    // else in the world (only its shape counts).
    req.demonstrations = vec![Demonstration {
        dt: 1.0 / 120.0,
        positions: (0..=96)
            .map(|k| {
                let s = k as f64 / 96.0;
                let along = 10.0 * s.powi(3) - 15.0 * s.powi(4) + 6.0 * s.powi(5);
                Vector3::new(1.0, 2.0, 0.5) + along * Vector3::new(0.0, 0.3, 0.0)
            })
            .collect(),
    }];
    let straight = plan_reach(&req).unwrap();
    let (bi, st) = (off_line(&built_in), off_line(&straight));
    println!("farthest off the line: built-in {bi:.4} m, straight {st:.4} m");
    assert!((0.045..0.07).contains(&bi), "{bi}");
    assert!(st < 0.005, "{st}");
    assert!(straight.reach_error < 0.005);
    let last = straight.samples.last().unwrap();
    assert!((last.pose.translation.vector - req.goal.translation.vector).norm() < 1e-9);
}
