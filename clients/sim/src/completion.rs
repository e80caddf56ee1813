//! How well graspd's completion of a single view (graspd-core `cloud::completion`) guesses the
//! side the camera does not see, measured against what cameras all around the table see.
//!
//! Per object and seed (the bench's placements): the benchmark camera's view of the object
//! (every pixel whose ray hits it: an ideal segmentation) is completed exactly as the planner
//! completes it (camera position, the table's up and its plane). The truth is the object as
//! [`TRUTH_VIEWS`] cameras at the benchmark's elevation around the table see it. Two figures:
//! - **error**: each added point's distance to the nearest true point (mean and 90th
//!   percentile, mm) — a phantom surface the hand avoids or plans contacts on;
//! - **coverage**: of the true points the benchmark camera did not see (farther than
//!   [`SEEN_MM`] from every visible point), the share within [`COVERED_MM`] of an added
//!   point — the unseen side the hand would otherwise sweep through.
//!
//! The object's underside near the table, which no camera sees, counts in neither. No graspd is
//! needed (`graspd-sim completion`).

use crate::SimError;
use crate::camera::views_around;
use crate::hand::SimHand;
use crate::object::SimObject;
use crate::scene::{Scene, on_table};
use crate::trial::{Trial, TrialOptions, placement};
use graspd_core::cloud::{CloudIndex, Plane, symmetric_completion};
use nalgebra::{Point3, Vector3};
use std::path::Path;

/// Cameras around the table whose views together are the truth.
pub const TRUTH_VIEWS: usize = 8;
/// A true point this close to a visible one was seen, mm.
pub const SEEN_MM: f64 = 3.0;
/// A hidden true point this close to an added one is covered, mm.
pub const COVERED_MM: f64 = 5.0;

/// One view's completion measured.
#[derive(Debug, Clone, PartialEq)]
pub struct CompletionScore {
    pub object: String,
    pub seed: u64,
    pub visible: usize,
    pub added: usize,
    /// Added points' distances to the truth, mm: mean and 90th percentile (0 when none added).
    pub mean_mm: f64,
    pub p90_mm: f64,
    /// Hidden true points covered by the completion, and how many there were.
    pub covered: usize,
    pub hidden: usize,
}

/// Completes the benchmark camera's view of `object` placed by `seed` and measures it (module
/// documentation). `scene` holds the object (any hand, parked).
/// `opts` gives the camera, its image size and the placement range.
pub fn score_completion(
    scene: &Scene,
    object: &str,
    seed: u64,
    opts: &TrialOptions,
) -> CompletionScore {
    let (intrinsics, camera) = (opts.intrinsics, &opts.camera);
    let mut trial = Trial::new(scene, placement(seed, opts.place_range));
    let obj = scene.object_bodies[0];
    let is_object = |g: usize| scene.model.geom_bodyid()[g] as usize == obj;
    let views = views_around(camera, TRUTH_VIEWS);
    // The benchmark camera's view is the first of the truth's.
    let seen = trial.render(intrinsics, views[0]).points_of(is_object);
    let mut truth = seen.clone();
    for v in &views[1..] {
        truth.extend(trial.render(intrinsics, *v).points_of(is_object));
    }
    let eye = Point3::from(camera.translation.vector);
    let table = Plane {
        normal: Vector3::z(),
        offset: 0.0,
    };
    let added: Vec<Point3<f64>> = symmetric_completion(&seen, &eye, &Vector3::z(), Some(&table))
        .map(|c| c.points[c.visible..].to_vec())
        .unwrap_or_default();
    if let Some(dir) = std::env::var_os("GRASPD_SIM_DEBUG_DIR") {
        // The three clouds as `x y z` lines, for a viewer.
        for (what, pts) in [("seen", &seen), ("truth", &truth), ("added", &added)] {
            let text: String = pts
                .iter()
                .map(|p| format!("{:.5} {:.5} {:.5}\n", p.x, p.y, p.z))
                .collect();
            let _ = std::fs::write(
                Path::new(&dir).join(format!("{object}_{seed}_{what}.xyz")),
                text,
            );
        }
    }
    let mut errors: Vec<f64> = if truth.is_empty() {
        Vec::new()
    } else {
        let index = CloudIndex::new(&truth);
        added.iter().map(|p| index.nearest_one(p).1 * 1e3).collect()
    };
    errors.sort_by(f64::total_cmp);
    let mean_mm = errors.iter().sum::<f64>() / errors.len().max(1) as f64;
    let p90_mm = errors
        .get((errors.len() * 9 / 10).min(errors.len().saturating_sub(1)))
        .copied()
        .unwrap_or(0.0);
    let (mut covered, mut hidden) = (0, 0);
    if !seen.is_empty() {
        let seen_index = CloudIndex::new(&seen);
        let added_index = (!added.is_empty()).then(|| CloudIndex::new(&added));
        for p in &truth {
            if seen_index.nearest_one(p).1 * 1e3 <= SEEN_MM {
                continue;
            }
            hidden += 1;
            if added_index
                .as_ref()
                .is_some_and(|a| a.nearest_one(p).1 * 1e3 <= COVERED_MM)
            {
                covered += 1;
            }
        }
    }
    CompletionScore {
        object: object.to_string(),
        seed,
        visible: seen.len(),
        added: added.len(),
        mean_mm,
        p90_mm,
        covered,
        hidden,
    }
}

/// Scores `trials` placements (seeds `seed`…) of each object; returns every score.
pub fn run_completion(
    objects: &[String],
    trials: usize,
    seed: u64,
    testdata: &Path,
    opts: &TrialOptions,
) -> Result<Vec<CompletionScore>, SimError> {
    // The scene needs a hand; the smallest built-in one stays parked out of view.
    let hand = SimHand::load("robotiq_2f85", &testdata.join("hands"))?;
    let mut out = Vec::new();
    for name in objects {
        let obj = SimObject::load(&testdata.join("objects"), name)?;
        let scene = Scene::build(&hand, &[(&obj, on_table(0.0, 0.0, 0.0))])?;
        for s in seed..seed + trials as u64 {
            out.push(score_completion(&scene, name, s, opts));
        }
    }
    Ok(out)
}

/// The scores as a markdown table, one row per object (means over its seeds) and a total row.
pub fn markdown(scores: &[CompletionScore]) -> String {
    let mut objects: Vec<&str> = Vec::new();
    for s in scores {
        if !objects.contains(&s.object.as_str()) {
            objects.push(&s.object);
        }
    }
    let mut md = String::from(
        "| object | views | added points | error mean (mm) | error p90 (mm) | unseen side covered |\n\
         |---|---:|---:|---:|---:|---:|\n",
    );
    let row = |name: &str, of: &[&CompletionScore]| {
        let n = of.len().max(1) as f64;
        let mean = |f: fn(&CompletionScore) -> f64| of.iter().map(|s| f(s)).sum::<f64>() / n;
        let (covered, hidden): (usize, usize) = of
            .iter()
            .fold((0, 0), |(c, h), s| (c + s.covered, h + s.hidden));
        format!(
            "| {name} | {} | {:.0} | {:.1} | {:.1} | {:.0} % |\n",
            of.len(),
            mean(|s| s.added as f64),
            mean(|s| s.mean_mm),
            mean(|s| s.p90_mm),
            100.0 * covered as f64 / hidden.max(1) as f64,
        )
    };
    for o in &objects {
        let of: Vec<&CompletionScore> = scores.iter().filter(|s| s.object == *o).collect();
        md += &row(o, &of);
    }
    let all: Vec<&CompletionScore> = scores.iter().collect();
    md += &row("**all**", &all);
    md
}
