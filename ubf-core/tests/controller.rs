//! The control loop: records, sinks, shutdown.

use std::sync::{Arc, Mutex};
use ubf_core::arbiter::{CommandFusion, HighestPriority};
use ubf_core::{
    from_fn, Action, BackgroundSink, Command, Composite, Controller, GroundTruth, Hold, Limits, NullRobot, Pose2,
    Robot, RobotError, SafetyGuard, SafetyPolicy, SimClock, State, TickRecord, TickSink, TreeLayout, Turn,
};

#[derive(Default)]
struct Log {
    layout: Option<TreeLayout>,
    records: Vec<TickRecord>,
    finished: bool,
}

/// Shared as `Arc<Mutex<Log>>`, which is itself a sink.
impl TickSink for Log {
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.layout = Some(layout.clone());
        Ok(())
    }
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        self.records.push(record.clone());
        Ok(())
    }
    fn finish(&mut self) -> std::io::Result<()> {
        self.finished = true;
        Ok(())
    }
}

fn tree() -> Composite {
    let drive = Composite::new("drive", CommandFusion)
        .child(from_fn("fast", |_: &State| Action::with_vote(1.0).velocity(0.8)), 3.0)
        .child(from_fn("slow", |_: &State| Action::with_vote(1.0).velocity(0.4).rot_velocity(0.1)), 1.0);
    Composite::new("root", HighestPriority)
        .child(from_fn("halt", |s: &State| if s.time >= 0.25 { Action::stop(1.0) } else { Action::none() }), 2.0)
        .child(drive, 1.0)
}

#[test]
fn every_tick_records_every_node_and_the_command() {
    let log = Arc::new(Mutex::new(Log::default()));
    let mut controller = Controller::new(NullRobot::default(), Box::new(tree()), Box::new(SimClock::new(0.1)));
    controller.add_sink(Box::new(log.clone()));
    for _ in 0..4 {
        controller.tick().unwrap();
    }
    controller.shutdown().unwrap();

    let log = log.lock().unwrap();
    let layout = log.layout.as_ref().unwrap();
    let paths: Vec<&str> = layout.nodes.iter().map(|n| n.path.as_str()).collect();
    assert_eq!(paths, ["root", "root/halt", "root/drive", "root/drive/fast", "root/drive/slow"]);
    assert!(log.finished);
    assert_eq!(log.records.len(), 4);

    let first = &log.records[0];
    assert_eq!((first.tick, first.time()), (0, 0.0));
    // Fused velocity (3·0.8 + 1·0.4) / 4 = 0.7; only "slow" sets a turn, so
    // the turn is its 0.1 undiluted.
    match first.command {
        Command::Drive { velocity, turn: Turn::Rate(rate) } => {
            assert!((velocity - 0.7).abs() < 1e-12);
            assert!((rate - 0.1).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
    assert!(!first.nodes[1].won && first.nodes[2].won && first.nodes[3].won);
    assert_eq!(first.nodes[3].weight, 0.75);
    assert_eq!(layout.winning_leaf(first), Some(3));

    let last = &log.records[3];
    assert!((last.time() - 0.3).abs() < 1e-12);
    assert_eq!(last.command, Command::Stop);
    assert_eq!(layout.winning_leaf(last), Some(1));
}

#[test]
fn shutdown_stops_the_robot_and_flushes_sinks_even_when_a_sink_fails() {
    struct Broken;
    impl TickSink for Broken {
        fn record(&mut self, _: &TickRecord) -> std::io::Result<()> {
            Err(std::io::Error::other("disk full"))
        }
        fn finish(&mut self) -> std::io::Result<()> {
            Err(std::io::Error::other("disk still full"))
        }
    }
    let log = Arc::new(Mutex::new(Log::default()));
    let mut controller = Controller::new(NullRobot::default(), Box::new(tree()), Box::new(SimClock::new(0.1)));
    controller.add_sink(Box::new(Broken));
    controller.add_sink(Box::new(log.clone()));
    assert!(controller.tick().unwrap_err().to_string().contains("disk full"));
    assert!(controller.shutdown().is_err());
    assert!(controller.robot().shut_down);
    assert_eq!(controller.robot().last_command, Command::Stop);
    assert!(log.lock().unwrap().finished, "the healthy sink was still flushed");
}

/// A tree whose `flaky` leaf, deep inside, panics from 0.2 s on.
fn tree_with_a_panic() -> Composite {
    let inner = Composite::new("drive", CommandFusion).child(
        from_fn("flaky", |s: &State| if s.time >= 0.2 { panic!("index out of range") } else { Action::none() }),
        1.0,
    );
    Composite::new("root", HighestPriority)
        .child(inner, 2.0)
        .child(from_fn("cruise", |_: &State| Action::with_vote(1.0).velocity(0.5)), 1.0)
}

#[test]
fn a_panicking_behaviour_is_caught_named_and_the_robot_stopped() {
    let mut controller =
        Controller::new(NullRobot::default(), Box::new(tree_with_a_panic()), Box::new(SimClock::new(0.1)));
    controller.tick().unwrap();
    controller.tick().unwrap();
    assert!(matches!(controller.robot().last_command, Command::Drive { .. }));
    let err = controller.tick().unwrap_err();
    assert!(
        matches!(&err, ubf_core::ControllerError::BehaviorPanicked(p)
        if p.path == "root/drive/flaky" && p.message == "index out of range"),
        "{err}"
    );
    assert_eq!(controller.robot().last_command, Command::Stop, "the robot was stopped");
}

#[test]
fn a_panicking_behaviour_can_be_skipped_for_the_rest_of_the_run() {
    let mut controller =
        Controller::new(NullRobot::default(), Box::new(tree_with_a_panic()), Box::new(SimClock::new(0.1)));
    controller.set_on_behavior_panic(ubf_core::OnBehaviorPanic::SkipBehavior);
    for _ in 0..3 {
        controller.tick().unwrap();
    }
    assert_eq!(controller.last_record().command, Command::Stop, "the tick that caught it stops");
    for _ in 0..3 {
        controller.tick().unwrap();
        assert!(matches!(controller.last_record().command, Command::Drive { velocity, .. } if velocity == 0.5));
    }
}

/// A robot that knows where it really is: a simulator, in miniature.
struct Truthful(NullRobot);

impl Robot for Truthful {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        self.0.sense(state)
    }
    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        self.0.act(command)
    }
    fn shutdown(&mut self) -> Result<(), RobotError> {
        self.0.shutdown()
    }
    fn limits(&self) -> Limits {
        self.0.limits()
    }
    fn ground_truth(&self) -> Option<GroundTruth> {
        Some(GroundTruth { pose: Pose2::new(1.0, 2.0, 0.5), collisions: 3 })
    }
}

#[test]
fn records_carry_what_was_sensed_the_ground_truth_and_the_guards_hold() {
    let mut robot = NullRobot::default();
    robot.reported.pose = Pose2::new(0.9, 2.1, 0.4);
    // Data a second old: the guard holds the robot still.
    robot.reported.sensor_age = 1.0;
    let policy = SafetyPolicy { link_lost_after_s: 10.0, ..SafetyPolicy::default() };
    let guarded = SafetyGuard::new(Truthful(robot), policy);
    let mut controller = Controller::new(guarded, Box::new(tree()), Box::new(SimClock::new(0.1)));
    let record = controller.tick().unwrap();
    assert_eq!(record.state.pose, Pose2::new(0.9, 2.1, 0.4), "the state the behaviours saw");
    assert_eq!(record.truth, Some(GroundTruth { pose: Pose2::new(1.0, 2.0, 0.5), collisions: 3 }));
    assert_eq!(record.hold, Some(Hold::StaleData));
    assert_ne!(record.command, Command::Stop, "the tree's command, which the guard replaced with STOP");

    // A real robot has no ground truth to give.
    let mut plain = Controller::new(NullRobot::default(), Box::new(tree()), Box::new(SimClock::new(0.1)));
    let record = plain.tick().unwrap();
    assert_eq!((record.truth, record.hold), (None, None));
}

#[test]
fn a_background_sink_writes_every_record_in_order_on_its_own_thread() {
    let log = Arc::new(Mutex::new(Log::default()));
    let mut controller = Controller::new(NullRobot::default(), Box::new(tree()), Box::new(SimClock::new(0.1)));
    controller.add_sink(Box::new(BackgroundSink::spawn("log", log.clone(), 64).unwrap()));
    for _ in 0..20 {
        controller.tick().unwrap();
    }
    controller.shutdown().unwrap();
    let log = log.lock().unwrap();
    assert!(log.finished && log.layout.is_some());
    let ticks: Vec<u64> = log.records.iter().map(|r| r.tick).collect();
    assert_eq!(ticks, (0..20).collect::<Vec<_>>());
    assert_eq!(log.records[3].command, Command::Stop);
}

/// A sink that fails on its third record, or panics there.
struct Failing {
    panics: bool,
}

impl TickSink for Failing {
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        match record.tick {
            2 if self.panics => panic!("the disk caught fire"),
            2 => Err(std::io::Error::other("no space left on device")),
            _ => Ok(()),
        }
    }
}

#[test]
fn a_failed_background_writer_ends_the_session_named() {
    for panics in [false, true] {
        let sink = BackgroundSink::spawn("log /tmp/x.csv", Failing { panics }, 8).unwrap();
        let mut controller = Controller::new(NullRobot::default(), Box::new(tree()), Box::new(SimClock::new(0.1)));
        controller.add_sink(Box::new(sink));
        // The writer fails on its own thread, whenever it is scheduled: a
        // busy machine can take a while (the bound only stops a hang).
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
        let error = loop {
            std::thread::sleep(std::time::Duration::from_millis(2));
            if let Err(error) = controller.tick() {
                break error;
            }
            assert!(std::time::Instant::now() < deadline, "no tick reported the writer's failure");
        };
        let text = error.to_string();
        assert!(text.contains("log /tmp/x.csv"), "{text}");
        assert!(text.contains(if panics { "panicked" } else { "no space left" }), "{text}");
    }
}

/// A sink whose writer waits at a gate before its first record.
struct Gated {
    gate: crossbeam_channel::Receiver<()>,
    seen: Arc<Mutex<Vec<u64>>>,
}

impl TickSink for Gated {
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        let _ = self.gate.recv();
        self.seen.lock().unwrap().push(record.tick);
        Ok(())
    }
}

#[test]
fn a_stuck_writer_loses_records_not_ticks() {
    let (open, gate) = crossbeam_channel::unbounded();
    let seen = Arc::new(Mutex::new(Vec::new()));
    let mut sink = BackgroundSink::spawn("stuck", Gated { gate, seen: seen.clone() }, 3).unwrap();
    let mut controller = Controller::new(NullRobot::default(), Box::new(tree()), Box::new(SimClock::new(0.1)));
    let layout = controller.layout().clone();
    sink.start(&layout).unwrap();
    for _ in 0..10 {
        sink.record(controller.tick().unwrap()).unwrap();
    }
    // Three buffers went to the writer; the other seven ticks went on
    // without waiting for it.
    assert_eq!(sink.dropped(), 7);
    drop(open);
    sink.finish().unwrap();
    assert_eq!(*seen.lock().unwrap(), [0, 1, 2]);
}
