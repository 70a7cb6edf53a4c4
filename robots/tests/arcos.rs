//! The ARCOS client against the emulator over real byte streams: TCP
//! loopback and a pseudo-terminal pair. No mocked traits.

use std::io::Write;
use std::net::TcpListener;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;
use ubf_core::{Command, Robot, State, Turn};
use ubf_robots::arcos::client::ArcosRobot;
use ubf_robots::arcos::emulator::{serve, EmulatorConfig, EmulatorReport};
use ubf_robots::arcos::link::{self, Link};
use ubf_robots::model::RobotModel;

struct Emulator {
    address: String,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<EmulatorReport>>,
}

impl Emulator {
    fn tcp(model: RobotModel) -> Emulator {
        Self::tcp_with(EmulatorConfig::new(model))
    }

    fn tcp_with(config: EmulatorConfig) -> Emulator {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let address = format!("tcp://{}", listener.local_addr().unwrap());
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        let thread = std::thread::spawn(move || {
            let (stream, _) = listener.accept().unwrap();
            stream.set_read_timeout(Some(link::READ_TIMEOUT)).unwrap();
            serve(Box::new(stream), &config, &flag).unwrap()
        });
        Emulator { address, stop, thread: Some(thread) }
    }

    fn finish(mut self) -> EmulatorReport {
        std::thread::sleep(Duration::from_millis(100));
        self.stop.store(true, Ordering::Relaxed);
        self.thread.take().unwrap().join().unwrap()
    }
}

/// Drives `robot` at `command` for `seconds`, sensing every 100 ms.
fn drive(robot: &mut ArcosRobot, command: Command, seconds: f64, state: &mut State) {
    let ticks = (seconds / 0.1).round() as usize;
    for _ in 0..ticks {
        robot.sense(state).unwrap();
        robot.act(&command).unwrap();
        std::thread::sleep(Duration::from_millis(100));
    }
    robot.sense(state).unwrap();
}

#[test]
fn handshake_drive_and_close_over_tcp() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let link = link::open(&emulator.address, 9600).unwrap();
    let mut robot = ArcosRobot::connect(link, RobotModel::powerbot(), true).unwrap();
    assert_eq!(robot.identity().subclass, "powerbot");
    let mut state = State::default();
    drive(&mut robot, Command::Drive { velocity: 0.4, turn: Turn::Rate(0.0) }, 1.5, &mut state);
    assert!(state.motors_enabled);
    assert!((state.velocity - 0.4).abs() < 0.01, "{}", state.velocity);
    // About 1.5 s at 0.4 m/s, give or take the SIP timing.
    assert!(state.pose.x > 0.35 && state.pose.x < 0.8, "{:?}", state.pose);
    assert_eq!(state.ranges.len(), 28);
    assert!(state.ranges.iter().all(|r| r.range.is_none()), "open space reads as no echo");
    drive(&mut robot, Command::Drive { velocity: 0.0, turn: Turn::Rate(0.5) }, 1.0, &mut state);
    assert!(state.pose.theta > 0.2, "{:?}", state.pose);
    assert!((state.rot_velocity - 0.5).abs() < 0.02, "{}", state.rot_velocity);
    robot.shutdown().unwrap();
    let report = emulator.finish();
    assert!(report.closed);
    assert_eq!(report.bad_checksums, 0);
}

#[test]
fn the_wrong_robot_is_refused() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let link = link::open(&emulator.address, 9600).unwrap();
    let err = ArcosRobot::connect(link, RobotModel::p3dx(), true).err().unwrap();
    assert!(err.to_string().contains("expects a Pioneer p3dx"), "{err}");
    emulator.finish();
}

#[test]
fn the_watchdog_stops_a_silent_client() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let link = link::open(&emulator.address, 9600).unwrap();
    let mut robot = ArcosRobot::connect(link, RobotModel::powerbot(), true).unwrap();
    let mut state = State::default();
    drive(&mut robot, Command::Drive { velocity: 0.3, turn: Turn::Rate(0.0) }, 0.5, &mut state);
    assert!(state.velocity > 0.25);
    // Silence: no command, no pulse, for longer than the 2 s watchdog.
    std::thread::sleep(Duration::from_millis(2600));
    robot.sense(&mut state).unwrap();
    assert_eq!(state.velocity, 0.0);
    robot.shutdown().unwrap();
    assert_eq!(emulator.finish().watchdog_stops, 1);
}

#[test]
fn garbage_and_bad_checksums_mid_stream_are_survived() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let link = link::open(&emulator.address, 9600).unwrap();
    let mut side = link.try_clone_link().unwrap();
    let mut robot = ArcosRobot::connect(link, RobotModel::powerbot(), true).unwrap();
    let mut state = State::default();
    drive(&mut robot, Command::Drive { velocity: 0.2, turn: Turn::Rate(0.0) }, 0.3, &mut state);
    let mut corrupt = ubf_robots::arcos::codec::ClientCommand::Vel(900).packet();
    *corrupt.last_mut().unwrap() ^= 0x55;
    side.write_all(&[0x13, 0xFA, 0x00, 0xFB, 0xFA]).unwrap();
    side.write_all(&corrupt).unwrap();
    drive(&mut robot, Command::Drive { velocity: 0.2, turn: Turn::Rate(0.0) }, 0.5, &mut state);
    assert!((state.velocity - 0.2).abs() < 0.01, "the corrupt VEL 900 was not obeyed: {}", state.velocity);
    robot.shutdown().unwrap();
    let report = emulator.finish();
    assert!(report.bad_checksums >= 1 && report.skipped_bytes >= 3, "{report:?}");
}

#[cfg(unix)]
#[test]
fn handshake_and_drive_over_a_pseudo_terminal() {
    use serialport::SerialPort;
    let (mut master, mut slave) = serialport::TTYPort::pair().unwrap();
    master.set_timeout(link::READ_TIMEOUT).unwrap();
    slave.set_timeout(link::READ_TIMEOUT).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let emulator = std::thread::spawn(move || {
        serve(Box::new(master) as Box<dyn Link>, &EmulatorConfig::new(RobotModel::powerbot()), &flag).unwrap()
    });
    let mut robot = ArcosRobot::connect(Box::new(slave), RobotModel::powerbot(), true).unwrap();
    let mut state = State::default();
    drive(&mut robot, Command::Drive { velocity: 0.3, turn: Turn::Rate(0.0) }, 1.0, &mut state);
    assert!(state.pose.x > 0.15, "{:?}", state.pose);
    robot.shutdown().unwrap();
    std::thread::sleep(Duration::from_millis(100));
    stop.store(true, Ordering::Relaxed);
    assert!(emulator.join().unwrap().closed);
}

#[test]
fn odometry_stays_continuous_across_the_wrap_and_below_zero() {
    // The Powerbot's 15-bit accumulators wrap every 32768 × 0.5813 mm ≈ 19 m.
    // Start the emulated robot 0.2 m short of the wrap and drive across it at
    // 1 m/s, then back past the start into negative coordinates.
    let mut config = EmulatorConfig::new(RobotModel::powerbot());
    config.start_mm = (32768.0 * 0.5813 - 200.0, 0.0);
    let emulator = Emulator::tcp_with(config);
    let mut robot =
        ArcosRobot::connect(link::open(&emulator.address, 9600).unwrap(), RobotModel::powerbot(), true).unwrap();
    let mut state = State::default();
    drive(&mut robot, Command::Drive { velocity: 1.0, turn: Turn::Rate(0.0) }, 1.0, &mut state);
    // Relative to the first SIP: about +1 m, not −18 m.
    assert!(state.pose.x > 0.6 && state.pose.x < 1.4, "{:?}", state.pose);
    drive(&mut robot, Command::Drive { velocity: -1.0, turn: Turn::Rate(0.0) }, 2.0, &mut state);
    assert!(state.pose.x < -0.4 && state.pose.x > -1.4, "{:?}", state.pose);
    robot.shutdown().unwrap();
    emulator.finish();
}

#[test]
fn a_dead_robot_is_reported_not_waited_for() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let mut robot =
        ArcosRobot::connect(link::open(&emulator.address, 9600).unwrap(), RobotModel::powerbot(), true).unwrap();
    let mut state = State::default();
    drive(&mut robot, Command::Drive { velocity: 0.2, turn: Turn::Rate(0.0) }, 0.3, &mut state);
    // The robot side goes away mid-run.
    emulator.finish();
    std::thread::sleep(Duration::from_millis(300));
    let mut failed = false;
    for _ in 0..20 {
        if robot.sense(&mut state).is_err() || robot.act(&Command::Stop).is_err() {
            failed = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(failed, "a vanished robot must surface as an error");
    assert!(state.sensor_age > 0.3, "and the state says its data is old: {}", state.sensor_age);
}
