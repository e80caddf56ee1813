//! Criterion benchmark of one plan (stage 1 + stage 2, with and without the opposition stage) on
//! 2,000-point single views of YCB objects, for each built-in hand, with the service's defaults.
//! `cargo bench -p graspd-core --bench plan`. The table beside the dissertation's Table 5.1 comes
//! from the `table_5_1` bench binary.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use graspd_core::HandCatalog;
use graspd_core::planning::{PlanHints, PlanInput, PlannerMode, PlannerOptions, plan};
use graspd_testkit::view::standard_view;
use graspd_testkit::ycb::Object;
use std::hint::black_box;
use std::time::Duration;

fn bench_plan(c: &mut Criterion) {
    let catalog = HandCatalog::builtin();
    let mut group = c.benchmark_group("plan_2000_points");
    group
        .sample_size(30)
        .measurement_time(Duration::from_secs(4));
    for object in [Object::TomatoSoupCan, Object::MustardBottle] {
        let view = standard_view(object, 2000, 1);
        for hand in ["parallel_gripper", "barrett", "shadow"] {
            for (label, mode) in [
                ("with", PlannerMode::DualStage),
                ("without", PlannerMode::WithoutOpposition),
            ] {
                let input = PlanInput {
                    cloud: view.object_cloud(),
                    hand: catalog.get(hand).unwrap().clone(),
                    hints: PlanHints {
                        support_plane: Some(view.support_plane),
                        viewpoint: Some(view.viewpoint),
                        ..Default::default()
                    },
                    options: PlannerOptions {
                        seed: 1,
                        mode,
                        ..Default::default()
                    },
                    kinematics: None,
                    grasp_quality: None,
                };
                let id =
                    BenchmarkId::new(format!("{hand}/{label}_opposition"), object.short_name());
                group.bench_with_input(id, &input, |b, input| {
                    b.iter(|| plan(black_box(input.clone())).unwrap())
                });
            }
        }
    }
    group.finish();
}

criterion_group!(benches, bench_plan);
criterion_main!(benches);
