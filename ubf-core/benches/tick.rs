//! One controller tick: a 4-child CommandFusion composite, and a 3-level
//! tree. Run with `cargo bench -p ubf-core --bench tick`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use ubf_core::arbiter::{CommandFusion, HighestActivation, HighestPriority};
use ubf_core::{from_fn, Action, Behavior, Composite, Controller, Goal, NullRobot, RangeReading, SimClock, State};

fn leaves() -> [Box<dyn Behavior>; 4] {
    [
        Box::new(from_fn("go", |s: &State| {
            let error = s.goal.map_or(0.0, |g| s.pose.bearing_to(g.x, g.y));
            Action::with_vote(0.5).velocity(0.5 * error.cos().max(0.0)).rot_velocity(1.5 * error)
        })),
        Box::new(from_fn("avoid", |s: &State| match s.nearest_range() {
            Some(r) if r < 1.0 => Action::with_vote(0.9).rot_velocity(0.4).max_velocity(r * 0.5),
            _ => Action::none(),
        })),
        Box::new(from_fn(
            "stop",
            |s: &State| if s.goal_reached() || s.bumpers.any() { Action::stop(1.0) } else { Action::none() },
        )),
        Box::new(from_fn("aim", |_: &State| Action::with_vote(0.3).heading(0.2))),
    ]
}

fn robot() -> NullRobot {
    let mut robot = NullRobot::default();
    // The Powerbot's 32 sonars, so that sensing copies a realistic state.
    robot.reported.ranges = (0..32)
        .map(|i| RangeReading { range: Some(0.8 + i as f64 * 0.1), max_range: 5.0, ..Default::default() })
        .collect();
    robot
}

fn bench_tree(c: &mut Criterion, name: &str, root: Box<dyn Behavior>) {
    let mut controller = Controller::new(robot(), root, Box::new(SimClock::new(0.1)));
    controller.set_goal(Some(Goal { x: 40.0, y: 3.0, tolerance: 0.2 }));
    controller.tick().unwrap();
    c.bench_function(name, |b| b.iter(|| black_box(controller.tick().unwrap().command)));
}

fn ticks(c: &mut Criterion) {
    let mut flat = Composite::new("root", CommandFusion);
    for (i, leaf) in leaves().into_iter().enumerate() {
        flat.push_child(format!("leaf{i}"), leaf, 1.0 + i as f64);
    }
    bench_tree(c, "tick/command_fusion_4_children", Box::new(flat));

    let [go, avoid, stop, aim] = leaves();
    let mut drive = Composite::new("drive", CommandFusion).vote(0.6);
    drive.push_child("go".into(), go, 1.0);
    drive.push_child("aim".into(), aim, 1.0);
    let mut safety = Composite::new("safety", HighestPriority);
    safety.push_child("stop".into(), stop, 2.0);
    safety.push_child("avoid".into(), avoid, 1.0);
    let root = Composite::new("root", HighestActivation).child(safety, 2.0).child(drive, 1.0);
    bench_tree(c, "tick/three_level_tree", Box::new(root));
}

criterion_group!(benches, ticks);
criterion_main!(benches);
