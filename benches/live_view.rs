//! What the live view costs the tick, as the robot feels it: the 40 m
//! corridor run paced at ten times real time (a tick every 10 ms), and for
//! each tick the time it keeps the loop busy (sense, the tree, act, every
//! sink), alone, with the live view serving nobody, and with the live view
//! serving the official Foxglove client subscribed to every topic
//! (`scripts/foxglove-live-check.sh`; that row is left out where Node.js
//! is missing). The cases take turns, five rounds, and the table gives the
//! median and 99th percentile of the busy time over every tick of a case;
//! "alone" runs twice a round, so that its two rows show the noise.
//!
//! Run with `cargo bench --bench live_view`.

use std::ops::ControlFlow;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use ubf::json_topics::{RunMessage, WorldMessage};
use ubf::live::LiveServer;
use ubf::scenario::Scenario;
use ubf_core::{BuildContext, Clock, Controller, Ends, PacedClock, Session, TickSink};
use ubf_robots::sim::SimRobot;

/// How many times faster than real time the runs go.
const SPEED: f64 = 10.0;
const ROUNDS: usize = 5;

/// A paced clock that notes how long each tick kept the loop busy: from
/// the end of one wait to the start of the next.
struct BusyClock {
    inner: PacedClock,
    woke: Instant,
    busy: Arc<Mutex<Vec<Duration>>>,
}

impl Clock for BusyClock {
    fn now(&self) -> f64 {
        self.inner.now()
    }
    fn period(&self) -> f64 {
        self.inner.period()
    }
    fn wait_for_next_tick(&mut self) {
        self.busy.lock().unwrap().push(self.woke.elapsed());
        self.inner.wait_for_next_tick();
        self.woke = Instant::now();
    }
}

/// Runs `scenario` paced, with `sink` if given; each tick's busy time.
fn busy_times(scenario: &Scenario, sink: Option<Box<dyn TickSink>>) -> Vec<Duration> {
    let sim = SimRobot::new(&scenario.robot, &scenario.world, scenario.period_s, 1);
    let root = scenario.root.build(&BuildContext::new(1));
    let busy = Arc::new(Mutex::new(Vec::new()));
    let clock =
        BusyClock { inner: PacedClock::new(scenario.period_s, SPEED), woke: Instant::now(), busy: busy.clone() };
    let mut controller = Controller::new(sim, root, Box::new(clock));
    controller.set_goal(scenario.goal);
    if let Some(sink) = sink {
        controller.add_sink(sink);
    }
    let ends =
        Ends { at_goal: true, progress: scenario.progress, max_ticks: Some(scenario.max_ticks()), max_time_s: None };
    let mut session = Session::new(controller, ends);
    session.run(&AtomicBool::new(false), |_| ControlFlow::Continue(()));
    drop(session.finish());
    let times = busy.lock().unwrap().clone();
    times
}

fn percentile(sorted: &[Duration], p: f64) -> f64 {
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i].as_secs_f64() * 1e6
}

fn main() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/thesis-corridor.ron");
    let scenario = Scenario::load(&ubf::registry(), &path).expect("the shipped scenario loads");
    let sim = SimRobot::new(&scenario.robot, &scenario.world, scenario.period_s, 1);
    let world = WorldMessage::of(sim.world());
    let run =
        RunMessage { scenario: scenario.name.clone(), seed: 1, start: [0.0; 3], outline: [[0.0; 2]; 4], goal: None };
    let quiet = LiveServer::serve("127.0.0.1:0".parse().unwrap(), ("ubf.Report", b"{}".to_vec())).unwrap();
    let watched = LiveServer::serve("127.0.0.1:0".parse().unwrap(), ("ubf.Report", b"{}".to_vec())).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/foxglove-live-check.sh");
    let url = format!("ws://{}", watched.address());
    let viewer = Command::new(script).args([&url, "3600"]).stdout(Stdio::null()).spawn();
    if viewer.is_ok() {
        // Time to install the client on first use, connect and subscribe.
        std::thread::sleep(Duration::from_secs(20));
    }
    let view =
        |server: &LiveServer| Some(Box::new(server.view(run.clone(), world.clone()).unwrap()) as Box<dyn TickSink>);

    // "alone" twice: the difference between the two is the noise.
    let mut cases: Vec<(&str, Vec<Duration>)> = vec![
        ("alone", Vec::new()),
        ("live view, no viewer", Vec::new()),
        ("live view, one viewer", Vec::new()),
        ("alone, again", Vec::new()),
    ];
    for _ in 0..ROUNDS {
        cases[0].1.extend(busy_times(&scenario, None));
        cases[1].1.extend(busy_times(&scenario, view(&quiet)));
        if viewer.is_ok() {
            cases[2].1.extend(busy_times(&scenario, view(&watched)));
        }
        cases[3].1.extend(busy_times(&scenario, None));
    }
    if let Ok(mut viewer) = viewer {
        let _ = viewer.kill();
    }
    println!("busy time of a tick, corridor run paced at {SPEED}x, {ROUNDS} rounds");
    println!("{:<24} {:>7} {:>11} {:>11} {:>9}", "case", "ticks", "median µs", "p99 µs", "× alone");
    let mut alone = f64::NAN;
    for (name, mut times) in cases.into_iter().filter(|(_, t)| !t.is_empty()) {
        times.sort();
        let median = percentile(&times, 0.5);
        if alone.is_nan() {
            alone = median;
        }
        let p99 = percentile(&times, 0.99);
        println!("{name:<24} {:>7} {median:>11.1} {p99:>11.1} {:>9.3}", times.len(), median / alone);
    }
}
