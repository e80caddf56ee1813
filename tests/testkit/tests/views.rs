//! Checks that the testkit's clouds look like what a depth camera would see.

use graspd_core::cloud::{RansacParams, detect_support_plane};
use graspd_testkit::ycb::{mesh_aabb, signed_volume};
use graspd_testkit::{Object, ViewSpec, mesh, sample_surface, standard_view, view};
use nalgebra::Vector3;
use std::time::Instant;

#[test]
fn tomato_can_view_lies_on_the_can_and_faces_the_camera() {
    let v = standard_view(Object::TomatoSoupCan, 2000, 1);
    assert_eq!(v.cloud.len(), 2000);
    assert_eq!(v.true_normals.len(), 2000);
    assert!(v.is_table.iter().all(|t| !t));
    assert!(v.cloud.normals.is_none());
    let (lo, hi) = v.object_aabb;
    // README: 67.9 x 67.7 x 101.9 mm, y from +50 mm.
    assert!((hi.z - lo.z - 0.1019).abs() < 1e-3 && (lo.y - 0.0501).abs() < 1e-3);
    let margin = 0.003; // 6 sigma of the 0.5 mm noise
    for p in &v.cloud.points {
        for k in 0..3 {
            assert!(
                p[k] > lo[k] - margin && p[k] < hi[k] + margin,
                "{p} outside the can"
            );
        }
    }
    // The camera is 0.6 m from the centre, 40 degrees up.
    let to_cam = v.viewpoint - v.object_center;
    assert!((to_cam.norm() - 0.6).abs() < 1e-9);
    assert!((to_cam.z / to_cam.norm() - 40f64.to_radians().sin()).abs() < 1e-9);
    // Visible side: every normal faces the camera; points on the mantle lie on the camera's
    // half of the can.
    let horiz = |w: Vector3<f64>| Vector3::new(w.x, w.y, 0.0);
    let mut mantle = 0;
    let mut near_side = 0;
    for (p, n) in v.cloud.points.iter().zip(&v.true_normals) {
        assert!(n.dot(&(v.viewpoint - p)) > 0.0);
        if p.z < hi.z - 0.01 {
            mantle += 1;
            if horiz(p - v.object_center).dot(&horiz(to_cam)) > 0.0 {
                near_side += 1;
            }
        }
    }
    assert!(mantle > 500, "mantle points {mantle}");
    assert!(
        near_side as f64 > 0.97 * mantle as f64,
        "{near_side} of {mantle} on the near side"
    );
    // Seen from 40 degrees up, the lid is visible too (it is recessed ~6 mm below the rim).
    let lid = v.true_normals.iter().filter(|n| n.z > 0.9).count();
    assert!(lid > 300, "lid points {lid}");
    let mean_dist: f64 = v
        .cloud
        .points
        .iter()
        .map(|p| (p - v.viewpoint).norm())
        .sum::<f64>()
        / 2000.0;
    assert!(mean_dist < 0.6, "mean distance {mean_dist}");
}

#[test]
fn counts_and_determinism() {
    let a = standard_view(Object::TomatoSoupCan, 2000, 7);
    let b = standard_view(Object::TomatoSoupCan, 2000, 7);
    let c = standard_view(Object::TomatoSoupCan, 2000, 8);
    assert_eq!(a.cloud, b.cloud);
    assert_ne!(a.cloud, c.cloud);
    assert_eq!(a.viewpoint, c.viewpoint);
    for n in [100, 500, 1234] {
        assert_eq!(standard_view(Object::GelatinBox, n, 3).cloud.len(), n);
    }
    // More than a VGA sensor sees: the sensor is zoomed until there are enough.
    let dense = standard_view(Object::Orange, 9000, 1);
    assert_eq!(dense.cloud.len(), 9000);
}

#[test]
fn every_object_gives_a_view() {
    for o in Object::ALL {
        let t = Instant::now();
        let v = standard_view(o, 2000, 1);
        assert_eq!(v.cloud.len(), 2000, "{o}");
        let (lo, hi) = v.object_aabb;
        assert!(lo.z.abs() < 0.004, "{o} stands on the table: {lo}");
        let above = v.cloud.points.iter().filter(|p| p.z > -0.002).count();
        assert_eq!(above, 2000, "{o}: points below the table");
        assert!(v.cloud.points.iter().all(|p| p.z < hi.z + 0.003));
        // Every mesh is wound with outward normals (positive volume), and the volume is
        // plausible: between 10 % (the curved banana fills ~17 %) and 100 % of the bounding box.
        let vol = signed_volume(&mesh(o).unwrap());
        let boxed = (hi - lo).product();
        assert!(
            vol > 0.1 * boxed && vol < boxed,
            "{o}: volume {vol}, box {boxed}"
        );
        eprintln!("{o}: {:?} (mesh loaded on first use)", t.elapsed());
    }
}

#[test]
fn table_view_has_a_detectable_support_plane() {
    let spec = ViewSpec::standard(1500, 2).with_table(0.15);
    let v = view(Object::MustardBottle, &spec).unwrap();
    let on_object = v.is_table.iter().filter(|t| !**t).count();
    let on_table = v.cloud.len() - on_object;
    assert_eq!(on_object, 1500);
    assert!(on_table > on_object, "table {on_table}");
    assert_eq!(v.object_cloud().len(), 1500);
    for (p, t) in v.cloud.points.iter().zip(&v.is_table) {
        if *t {
            // Within the 0.3 m patch, give or take the range noise along slanted rays.
            let c = v.object_center;
            assert!(p.z.abs() < 0.003, "{p}");
            assert!(
                (p.x - c.x).abs() < 0.153 && (p.y - c.y).abs() < 0.153,
                "{p}"
            );
        }
    }
    let fit = detect_support_plane(&v.cloud.points, RansacParams::default(), 1, 32)
        .expect("the table is found");
    assert!(fit.plane.normal.z > 0.999, "{:?}", fit.plane);
    assert!(fit.plane.offset.abs() < 1e-3, "{:?}", fit.plane);
    let kept: Vec<bool> = fit.removed.iter().map(|r| !r).collect();
    let kept_table = kept
        .iter()
        .zip(&v.is_table)
        .filter(|(k, t)| **k && **t)
        .count();
    assert!(kept_table < on_table / 50, "{kept_table} table points kept");
}

#[test]
fn surface_samples_have_outward_normals() {
    let m = mesh(Object::TomatoSoupCan).unwrap();
    assert!(signed_volume(&m) > 0.0);
    let (lo, hi) = mesh_aabb(&m);
    let c = nalgebra::center(&lo, &hi);
    let s = sample_surface(&m, 3000, 5);
    assert_eq!(s.len(), 3000);
    let normals = s.normals.as_ref().unwrap();
    // Away from the rims, the can is a cylinder: mantle normals point away from the axis.
    let radial = |p: &nalgebra::Point3<f64>| Vector3::new(p.x - c.x, p.y - c.y, 0.0);
    let (mut mantle, mut outward) = (0, 0);
    for (p, n) in s.points.iter().zip(normals) {
        if p.z > 0.01 && p.z < 0.09 && radial(p).norm() > 0.03 {
            mantle += 1;
            if radial(p).dot(n) > 0.0 {
                outward += 1;
            }
        }
    }
    assert!(
        mantle > 1500 && outward == mantle,
        "{outward} of {mantle} outward"
    );
    // Overall most normals point away from the centre; the exceptions are the inner walls of
    // the rolled rims at the top and bottom, which do face the axis.
    let away = s
        .points
        .iter()
        .zip(normals)
        .filter(|(p, n)| (*p - c).dot(n) > 0.0)
        .count();
    assert!(away > 2700, "{away} of 3000 away from the centre");
    assert_eq!(s, sample_surface(&m, 3000, 5));
    // Chips can: collision mesh, scaled, standing on the table.
    let chips = mesh(Object::ChipsCan).unwrap();
    let cs = sample_surface(&chips, 500, 1);
    assert!(cs.points.iter().all(|p| p.z > -1e-9 && p.z < 0.2417));
}

#[test]
fn timing_of_standard_view() {
    // Warm the mesh cache, then time a view (printed; `cargo test -- --nocapture`).
    let t = Instant::now();
    let _ = mesh(Object::TomatoSoupCan).unwrap();
    let load = t.elapsed();
    let t = Instant::now();
    let v = standard_view(Object::TomatoSoupCan, 2000, 11);
    let render = t.elapsed();
    eprintln!(
        "tomato soup can: mesh load + BVH {load:?}, standard_view {render:?} ({} rays, {}x{})",
        v.camera.intrinsics.width * v.camera.intrinsics.height,
        v.camera.intrinsics.width,
        v.camera.intrinsics.height
    );
}
