//! Simulator speed: a whole 40 m corridor run (16 landmarks, the sonar ring,
//! the stereo camera), and a 30-seed sweep of it.
//! Run with `cargo bench --bench simulation`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;
use std::path::Path;
use ubf::run::run;
use ubf::scenario::Scenario;
use ubf::sweep::{sweep, SweepItem};

fn corridor() -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/thesis-corridor.ron");
    Scenario::load(&ubf::registry(), &path).expect("the shipped scenario loads")
}

fn simulation(c: &mut Criterion) {
    let scenario = corridor();
    let ticks = run(&scenario, 1, None).expect("the run succeeds").ticks;
    let mut group = c.benchmark_group("simulation");
    group.throughput(Throughput::Elements(ticks));
    group.bench_function("thesis_corridor_40m_run", |b| b.iter(|| black_box(run(&scenario, 1, None).unwrap().ticks)));
    group.finish();

    let items = [SweepItem { scenario, label: "corridor".into() }];
    let out = tempfile::tempdir().expect("a temporary directory");
    let mut group = c.benchmark_group("sweep_30_seeds");
    group.sample_size(10);
    for jobs in [1, 2] {
        group.bench_function(format!("jobs_{jobs}"), |b| {
            b.iter(|| black_box(sweep(&items, 0..30, jobs, out.path(), false).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(benches, simulation);
criterion_main!(benches);
