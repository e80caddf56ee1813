//! The Bayesian search against the Monte-Carlo search (issue 18, dissertation §3.2.3): the
//! quality each reaches against the network calls it makes, with the shipped grasp-quality
//! network on the candidates `options.mode = learned_quality` chooses among (2,000-point single
//! views of the Table 5.2 objects × 5 seeds, 300 candidates each, as the planner samples them).
//! The Monte-Carlo baseline rates the whole pool (300 calls) and takes the best; it is also run
//! with 60 calls (the Bayesian search's budget). One thread.
//! `cargo bench -p graspd-core --bench learned_quality` (needs ONNX Runtime: `$ORT_DYLIB_PATH`).

use graspd_core::cloud::CloudIndex;
use graspd_core::planning::bayesian_search::{SearchOptions, bayesian_search, monte_carlo_search};
use graspd_core::planning::grasp_quality::GraspQualityModel;
use graspd_core::planning::grasp_quality::candidates::{
    features, object_from_view, sample_candidates,
};
use graspd_core::planning::grasp_quality::crop::grasp_view;
use graspd_core::planning::parallel_grasp::TableFrame;
use graspd_testkit::view::standard_view;
use graspd_testkit::ycb::Object;
use rand::SeedableRng;
use std::convert::Infallible;
use std::time::Instant;

/// The Robotiq 2F-85's opening, m.
const OPENING: f64 = 0.085;
const POOL: usize = 300;
/// A search reached the Monte-Carlo best when it found a quality this close to it (the
/// network's probabilities saturate near 1: 0.99998 against 0.99999 is no better grasp).
const REACHED: f64 = 0.01;

fn main() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/grasp_quality/grasp_quality.onnx"
    );
    let net = GraspQualityModel::load(std::path::Path::new(path), 1).expect("the shipped model");
    println!(
        "object           searches  MC best (300 calls)  MC best (60 calls)  BO best  BO calls (median)  BO within 0.01 of MC-300  BO calls to reach it (median)  BO ms  MC-300 ms"
    );
    let (mut all_reached, mut all_runs, mut all_calls, mut all_to_reach) =
        (0, 0, Vec::new(), Vec::new());
    for object in Object::TABLE_5_2 {
        let (mut mc300, mut mc60, mut bo, mut calls, mut to_reach, mut reached) = (
            Vec::new(),
            Vec::new(),
            Vec::new(),
            Vec::new(),
            Vec::new(),
            0,
        );
        let (mut bo_ms, mut mc_ms) = (Vec::new(), Vec::new());
        for seed in 1..=5u64 {
            let v = standard_view(object, 2000, seed);
            let (visible, completed) =
                object_from_view(&v.object_cloud().points, &v.support_plane, &v.viewpoint);
            let index = CloudIndex::new(&completed);
            let lowest = completed
                .iter()
                .min_by(|a, b| a.z.total_cmp(&b.z))
                .expect("points");
            let table = TableFrame::under(
                lowest,
                &v.support_plane.normal,
                v.support_plane.distance(lowest),
            );
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let pool = sample_candidates(&completed, &index, &table, OPENING, POOL, &mut rng);
            if pool.is_empty() {
                continue;
            }
            // The network once over the pool: every search below reads these qualities and
            // counts its calls (the same values the network would return one by one).
            let views: Vec<_> = pool
                .iter()
                .map(|g| grasp_view(&visible, &table, g))
                .collect();
            let q = net.quality(&views).expect("inference");
            let rate = |idx: &[usize]| Ok::<_, Infallible>(idx.iter().map(|&i| q[i]).collect());
            let t = Instant::now();
            let full = monte_carlo_search(pool.len(), rate, POOL, seed)
                .unwrap()
                .unwrap();
            mc_ms.push(t.elapsed().as_secs_f64() * 1e3);
            let short = monte_carlo_search(pool.len(), rate, 60, seed)
                .unwrap()
                .unwrap();
            let feats: Vec<Vec<f64>> = pool.iter().map(|g| features(g, &table)).collect();
            let t = Instant::now();
            let b = bayesian_search(
                &feats,
                rate,
                &SearchOptions {
                    seed,
                    ..Default::default()
                },
            )
            .unwrap()
            .unwrap();
            bo_ms.push(t.elapsed().as_secs_f64() * 1e3);
            mc300.push(full.quality);
            mc60.push(short.quality);
            bo.push(b.quality);
            calls.push(b.calls as f64);
            if let Some(k) = b
                .best_after
                .iter()
                .position(|&x| x >= full.quality - REACHED)
            {
                reached += 1;
                to_reach.push((k + 1) as f64);
            }
        }
        let n = bo.len();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        println!(
            "{:16} {n:8}  {:19.3}  {:18.3}  {:7.3}  {:17}  {reached:>15}/{n}  {:>29}  {:5.1}  {:9.3}",
            format!("{object:?}"),
            mean(&mc300),
            mean(&mc60),
            mean(&bo),
            median(&mut calls.clone()),
            if to_reach.is_empty() {
                "-".to_string()
            } else {
                format!("{}", median(&mut to_reach.clone()))
            },
            median(&mut bo_ms),
            median(&mut mc_ms),
        );
        all_reached += reached;
        all_runs += n;
        all_calls.extend(calls);
        all_to_reach.extend(to_reach);
    }
    println!(
        "all: BO came within 0.01 of the 300-call Monte-Carlo best in {all_reached}/{all_runs} searches, median {} calls to reach it, median {} calls in all (the Monte-Carlo search: 300)",
        median(&mut all_to_reach),
        median(&mut all_calls)
    );
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}
