//! Planning time and solution-space size with and without the pregrasping opposition, beside the
//! dissertation's Table 5.1, on 2,000-point single-view clouds of the YCB objects for each built-in
//! hand. A bench binary (not criterion): it prints Markdown tables for the README.
//!
//! `cargo bench -p graspd-core --bench table_5_1` (add `-- --quick` for fewer seeds).
//!
//! Two settings are measured:
//! * service defaults: iterations = clamp(10 % of |Φ|, 100, 1200) per stage, early stop after 250
//!   iterations without improvement — what graspd answers requests with;
//! * thesis rule: iterations = 10 % of |Φ| with no cap but a safety limit of 1,000,000, as in the
//!   text (the setting of Table 5.1: same algorithm and parameters for both variants).

use graspd_core::planning::{PlanHints, PlanInput, PlannerMode, PlannerOptions, plan};
use graspd_core::{GraspPlan, GraspType, HandCatalog};
use graspd_testkit::view::standard_view;
use graspd_testkit::ycb::Object;
use std::time::Instant;

const OBJECTS: [Object; 8] = Object::TABLE_5_2;

struct Run {
    seconds: f64,
    space: f64,
    feasible: bool,
    objective: f64,
    iterations: usize,
}

fn run(input: &PlanInput) -> Run {
    let t = Instant::now();
    let p: GraspPlan = plan(input.clone()).expect("valid input");
    let seconds = t.elapsed().as_secs_f64();
    Run {
        seconds,
        space: p.stage1.solution_space + p.stage2.solution_space,
        feasible: p.feasible,
        objective: p.quality.objective,
        iterations: p.stage1.iterations + p.stage2.iterations,
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn input(
    object: Object,
    hand: &str,
    seed: u64,
    mode: PlannerMode,
    thesis_rule: bool,
    forced: Option<GraspType>,
) -> PlanInput {
    let v = standard_view(object, 2000, seed);
    let mut options = PlannerOptions {
        seed,
        mode,
        ..Default::default()
    };
    if thesis_rule {
        options.max_iterations = 1_000_000;
        options.patience = 1_000_000;
    }
    PlanInput {
        cloud: v.object_cloud(),
        hand: HandCatalog::builtin().get(hand).unwrap().clone(),
        hints: PlanHints {
            support_plane: Some(v.support_plane),
            viewpoint: Some(v.viewpoint),
            grasp_type: forced,
            ..Default::default()
        },
        options,
        kinematics: None,
        grasp_quality: None,
    }
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let seeds: u64 = if quick { 3 } else { 11 };
    println!("# graspd planner benchmark (2,000-point single views, one thread)\n");
    println!("## Service defaults: per hand over the 8 objects × {seeds} seeds\n");
    println!(
        "| hand | median ms/plan (with) | p90 ms (with) | feasible (with) | median ms (without) | feasible (without) | median |Φ| with | median |Φ| without | with/without time |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut all_with = Vec::new();
    for hand in ["parallel_gripper", "barrett", "shadow"] {
        let (mut tw, mut to, mut sw, mut so) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let (mut fw, mut fo, mut n) = (0, 0, 0);
        for object in OBJECTS {
            for seed in 0..seeds {
                let w = run(&input(
                    object,
                    hand,
                    seed,
                    PlannerMode::DualStage,
                    false,
                    None,
                ));
                let o = run(&input(
                    object,
                    hand,
                    seed,
                    PlannerMode::WithoutOpposition,
                    false,
                    None,
                ));
                tw.push(w.seconds * 1e3);
                to.push(o.seconds * 1e3);
                sw.push(w.space);
                so.push(o.space);
                fw += usize::from(w.feasible);
                fo += usize::from(o.feasible);
                n += 1;
            }
        }
        all_with.extend(tw.iter().copied());
        let (mw, mo) = (median(&mut tw), median(&mut to));
        println!(
            "| {hand} | {mw:.2} | {:.2} | {fw}/{n} | {mo:.2} | {fo}/{n} | {:.3e} | {:.3e} | {:.0} % |",
            percentile(&mut tw, 0.9),
            median(&mut sw),
            median(&mut so),
            100.0 * mw / mo
        );
    }
    println!(
        "\nAll hands, with opposition: median {:.2} ms, p90 {:.2} ms per plan.\n",
        median(&mut all_with),
        percentile(&mut all_with, 0.9)
    );

    println!(
        "## Table 5.1 setting: tripod with the Shadow hand, thesis iteration rule (10 % of |Φ|)\n"
    );
    println!(
        "| object (#points) | with: |Φ_g| | with: time (s) | with: Q / feasible | without: |Φ_g| | without: time (s) | without: Q / feasible | time with/without |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    let table_seeds = if quick { 1 } else { 3 };
    let (mut sum_w, mut sum_o) = (0.0, 0.0);
    for object in [
        Object::TomatoSoupCan,
        Object::PottedMeatCan,
        Object::MustardBottle,
    ] {
        let (mut tw, mut to) = (Vec::new(), Vec::new());
        let (mut w_last, mut o_last) = (None, None);
        for seed in 0..table_seeds {
            let w = run(&input(
                object,
                "shadow",
                seed,
                PlannerMode::DualStage,
                true,
                Some(GraspType::Tripod),
            ));
            let o = run(&input(
                object,
                "shadow",
                seed,
                PlannerMode::WithoutOpposition,
                true,
                Some(GraspType::Tripod),
            ));
            tw.push(w.seconds);
            to.push(o.seconds);
            w_last = Some(w);
            o_last = Some(o);
        }
        let (w, o) = (w_last.unwrap(), o_last.unwrap());
        let (mw, mo) = (median(&mut tw), median(&mut to));
        sum_w += mw;
        sum_o += mo;
        println!(
            "| {} (2000) | {:.3e} | {mw:.4} | {:.3} / {} | {:.3e} ({} it.) | {mo:.3} | {:.3} / {} | {:.2} % |",
            object.short_name(),
            w.space,
            w.objective,
            w.feasible,
            o.space,
            o.iterations,
            o.objective,
            o.feasible,
            100.0 * mw / mo
        );
    }
    println!(
        "| average | | {:.4} | | | {:.3} | | {:.2} % |",
        sum_w / 3.0,
        sum_o / 3.0,
        100.0 * sum_w / sum_o
    );
    println!("| dissertation (120 points) | 6253 | 1.81 | | 120³ | 59.3 | | 3.05 % |");
}
