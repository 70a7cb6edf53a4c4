//! Simulator speed: a whole 40 m corridor run (16 landmarks, the sonar ring,
//! the stereo camera), and a 30-seed sweep of it; and the simulated robot's
//! sensing alone along that corridor, and one sweep of its sonar ring at a
//! heading it keeps and at one that changes every sweep (the ring works its
//! rays' directions out again only when the heading changes).
//! Run with `cargo bench --bench simulation`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::path::Path;
use ubf::run::run;
use ubf::scenario::Scenario;
use ubf::sweep::{sweep, SweepItem};
use ubf_core::{Command, Pose2, Robot, State, Turn};
use ubf_robots::model::RobotModel;
use ubf_robots::sim::geometry::Segment;
use ubf_robots::sim::{SimRobot, Sonar, SonarConfig};

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

/// The simulated robot sensing and driving straight down the corridor for
/// as many ticks as the run takes, without the behaviour tree: the
/// simulator's own share of a run.
fn sensing(c: &mut Criterion) {
    let scenario = corridor();
    let ticks = run(&scenario, 1, None).expect("the run succeeds").ticks;
    let ahead = Command::Drive { velocity: 0.6, turn: Turn::Rate(0.0) };
    let mut group = c.benchmark_group("sensing");
    group.throughput(Throughput::Elements(ticks));
    group.bench_function("thesis_corridor_sense_and_act", |b| {
        b.iter(|| {
            let mut robot = SimRobot::new(&scenario.robot, &scenario.world, scenario.period_s, 1);
            let mut state = State::default();
            for _ in 0..ticks {
                robot.sense(&mut state).unwrap();
                robot.act(&ahead).unwrap();
            }
            black_box(state.ranges.len())
        })
    });
    group.finish();

    // The Powerbot's ring halfway down the 6 m corridor.
    let walls = [Segment::new((0.0, -3.0), (60.0, -3.0)), Segment::new((0.0, 3.0), (60.0, 3.0))];
    let mut sonar = Sonar::new(SonarConfig::default(), RobotModel::powerbot().sonar);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut readings = Vec::new();
    let mut group = c.benchmark_group("sonar_ring");
    group.bench_function("heading_kept", |b| {
        let pose = Pose2::new(30.0, 0.0, 0.0);
        b.iter(|| sonar.sense(black_box(&pose), 0.8, &walls, &[], &mut rng, &mut readings))
    });
    group.bench_function("heading_changing", |b| {
        let mut pose = Pose2::new(30.0, 0.0, 0.0);
        b.iter(|| {
            pose.theta = if pose.theta == 0.0 { 0.01 } else { 0.0 };
            sonar.sense(black_box(&pose), 0.8, &walls, &[], &mut rng, &mut readings)
        })
    });
    group.finish();
}

criterion_group!(benches, simulation, sensing);
criterion_main!(benches);
