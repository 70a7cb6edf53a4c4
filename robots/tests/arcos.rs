//! The ARCOS client against the emulator over real byte streams: TCP
//! loopback and a pseudo-terminal pair. No mocked traits.

use std::io::Write;
use std::net::TcpListener;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;
use ubf_core::{Command, Robot, State, Turn};
use ubf_robots::arcos::client::{Accelerations, ArcosRobot, ConnectOptions};
use ubf_robots::arcos::emulator::{serve, EmulatorConfig, EmulatorReport};
use ubf_robots::arcos::link::{self, Link};
use ubf_robots::emergency::EmergencyStop;
use ubf_robots::model::RobotModel;

mod common;
use common::{drive, watch};

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

    /// A Powerbot client connected to this emulator, motors on.
    fn connect(&self) -> ArcosRobot {
        self.connect_with(&ConnectOptions::default())
    }

    /// A Powerbot client connected with `options`.
    fn connect_with(&self, options: &ConnectOptions) -> ArcosRobot {
        let link = link::open(&self.address, 9600).unwrap();
        ArcosRobot::connect(link, RobotModel::powerbot(), options).unwrap()
    }

    fn finish(mut self) -> EmulatorReport {
        std::thread::sleep(Duration::from_millis(100));
        self.stop.store(true, Ordering::Relaxed);
        self.thread.take().unwrap().join().unwrap()
    }
}

#[test]
fn handshake_drive_and_close_over_tcp() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let mut robot = emulator.connect();
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
    let err = ArcosRobot::connect(link, RobotModel::p3dx(), &ConnectOptions::default()).err().unwrap();
    assert!(err.to_string().contains("expects a Pioneer p3dx"), "{err}");
    // Not a lost link: a new session would meet the same robot.
    assert!(matches!(err, ubf_core::RobotError::WrongRobot { .. }) && !err.is_link_loss(), "{err:?}");
    emulator.finish();
}

#[test]
fn the_watchdog_stops_a_silent_client() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let mut robot = emulator.connect();
    let mut state = State::default();
    drive(&mut robot, Command::Drive { velocity: 0.3, turn: Turn::Rate(0.0) }, 1.0, &mut state);
    assert!(state.velocity > 0.25, "{}", state.velocity);
    // Silence: no command, no pulse, for longer than the 2 s watchdog and
    // the 0.6 s the default deceleration takes to stop.
    std::thread::sleep(Duration::from_millis(3200));
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
    let mut robot = ArcosRobot::connect(link, RobotModel::powerbot(), &ConnectOptions::default()).unwrap();
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
    let mut robot = ArcosRobot::connect(Box::new(slave), RobotModel::powerbot(), &ConnectOptions::default()).unwrap();
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
    let brisk = Accelerations { translation: 2.0, rotation_deg: 300.0 };
    let mut robot = emulator.connect_with(&ConnectOptions { accelerations: Some(brisk), ..ConnectOptions::default() });
    let mut state = State::default();
    drive(&mut robot, Command::Drive { velocity: 1.0, turn: Turn::Rate(0.0) }, 1.0, &mut state);
    // Relative to the first SIP: about +0.75 m (after a 0.5 s ramp), not
    // −18 m.
    assert!(state.pose.x > 0.4 && state.pose.x < 1.4, "{:?}", state.pose);
    // Back past the start: about −1.25 m.
    drive(&mut robot, Command::Drive { velocity: -1.0, turn: Turn::Rate(0.0) }, 3.0, &mut state);
    assert!(state.pose.x < -0.4 && state.pose.x > -2.4, "{:?}", state.pose);
    robot.shutdown().unwrap();
    emulator.finish();
}

/// Senses and stops `robot` every 50 ms, `tries` times at most, until one
/// of them fails: that error.
fn first_failure(robot: &mut ArcosRobot, state: &mut State, tries: usize) -> Option<ubf_core::RobotError> {
    for _ in 0..tries {
        if let Err(e) = robot.sense(state).and_then(|()| robot.act(&Command::Stop)) {
            return Some(e);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    None
}

#[test]
fn a_dead_robot_is_reported_not_waited_for() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let mut robot = emulator.connect();
    let mut state = State::default();
    drive(&mut robot, Command::Drive { velocity: 0.2, turn: Turn::Rate(0.0) }, 0.3, &mut state);
    // The robot side goes away mid-run.
    emulator.finish();
    std::thread::sleep(Duration::from_millis(300));
    let failed = first_failure(&mut robot, &mut state, 20).expect("a vanished robot must surface as an error");
    // The drive reopens the link on a lost link, and only on one.
    assert!(failed.is_link_loss(), "{failed:?}");
    assert!(state.sensor_age > 0.3, "and the state says its data is old: {}", state.sensor_age);
}

/// A TCP proxy to the emulator at `upstream` (`tcp://host:port`): its
/// address. Once `armed` is set, it moves every SIP's x position on by
/// 16 000 units (9.3 m on a Powerbot), as corrupt data would.
fn jumping_proxy(upstream: &str, armed: Arc<AtomicBool>) -> String {
    use std::io::Read;
    use ubf_robots::arcos::codec::{frame, Sip, StreamDecoder};
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = format!("tcp://{}", listener.local_addr().unwrap());
    let upstream = upstream.trim_start_matches("tcp://").to_owned();
    std::thread::spawn(move || {
        let (mut client, _) = listener.accept().unwrap();
        let mut robot = std::net::TcpStream::connect(upstream).unwrap();
        let (mut commands, mut to_robot) = (client.try_clone().unwrap(), robot.try_clone().unwrap());
        std::thread::spawn(move || std::io::copy(&mut commands, &mut to_robot));
        let mut decoder = StreamDecoder::new();
        let mut buffer = [0u8; 4096];
        while let Ok(n @ 1..) = robot.read(&mut buffer) {
            decoder.push(&buffer[..n]);
            while let Some(body) = decoder.next_body() {
                let body = match Sip::parse(&body) {
                    Ok(mut sip) if armed.load(Ordering::Relaxed) => {
                        sip.xpos = sip.xpos.wrapping_add(16_000) & 0x7FFF;
                        sip.body()
                    }
                    _ => body,
                };
                if client.write_all(&frame(&body)).is_err() {
                    return;
                }
            }
        }
    });
    address
}

#[test]
fn odometry_that_jumps_further_than_any_robot_drives_ends_the_link() {
    // Steered by, it drove the robot anywhere and could fake a goal reached;
    // before, the client took it without a word.
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let armed = Arc::new(AtomicBool::new(false));
    let address = jumping_proxy(&emulator.address, Arc::clone(&armed));
    let link = link::open(&address, 9600).unwrap();
    let mut robot = ArcosRobot::connect(link, RobotModel::powerbot(), &ConnectOptions::default()).unwrap();
    let mut state = State::default();
    drive(&mut robot, Command::Drive { velocity: 0.3, turn: Turn::Rate(0.0) }, 0.5, &mut state);
    armed.store(true, Ordering::Relaxed);
    let failed = first_failure(&mut robot, &mut state, 40).expect("corrupt odometry must surface as an error");
    assert!(failed.is_link_loss(), "{failed:?}");
    // 9.30 m and whatever the robot drove in the same SIP's time.
    assert!(failed.to_string().contains("the odometry jumped 9."), "{failed}");
    assert!(state.pose.x < 1.0, "the jump was never taken as the pose: {:?}", state.pose);
    robot.shutdown().unwrap();
    emulator.finish();
}

#[test]
fn config_is_read_and_the_controllers_tops_bound_the_model() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    // A model file claiming more than the controller's 2 m/s and 360°/s.
    let mut optimistic = RobotModel::powerbot();
    optimistic.max_velocity = 3.0;
    optimistic.max_rot_velocity_deg = 500.0;
    let robot =
        ArcosRobot::connect(link::open(&emulator.address, 9600).unwrap(), optimistic, &ConnectOptions::default())
            .unwrap();
    let config = robot.config().expect("the emulator answers CONFIG");
    assert_eq!((config.subtype.as_str(), config.trans_vel_top, config.sip_cycle_ms), ("powerbot", 2000, 100));
    assert_eq!(robot.limits().max_velocity, 2.0);
    assert!((robot.limits().max_rot_velocity - 360f64.to_radians()).abs() < 1e-12);
    drop(robot);
    assert!(emulator.finish().closed, "dropping the robot closes the session");
}

#[test]
fn accelerations_are_set_and_obeyed() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let options = ConnectOptions {
        accelerations: Some(Accelerations { translation: 0.5, rotation_deg: 90.0 }),
        ..ConnectOptions::default()
    };
    let mut robot =
        ArcosRobot::connect(link::open(&emulator.address, 9600).unwrap(), RobotModel::powerbot(), &options).unwrap();
    let mut state = State::default();
    // 1 m/s asked for; at 0.5 m/s² the robot is near half that after 1 s.
    drive(&mut robot, Command::Drive { velocity: 1.0, turn: Turn::Rate(0.0) }, 1.0, &mut state);
    assert!(state.velocity > 0.3 && state.velocity < 0.7, "{}", state.velocity);
    robot.shutdown().unwrap();
    assert_eq!(emulator.finish().accelerations, Some((500, 90)));
}

#[test]
fn sonar_echoes_off_the_walls_of_the_room() {
    // The robot in the middle of an 6 m × 4 m room, facing along it.
    let emulator = Emulator::tcp_with(EmulatorConfig::new(RobotModel::powerbot()).in_room(6.0, 4.0));
    let mut robot = emulator.connect();
    let mut state = State::default();
    drive(&mut robot, Command::Stop, 0.3, &mut state);
    let range_of = |state: &State, heading_deg: f64| {
        let model = RobotModel::powerbot();
        let slot = model.sonar.iter().position(|s| s.heading_deg == heading_deg).unwrap();
        state.ranges[slot].range
    };
    // The 5° transducer sits 0.332 m ahead of the centre: the wall 3 m ahead
    // is (3 − 0.332)/cos 5° away along its axis; the left one (90°, 0.278 m
    // out) 2 − 0.278.
    let ahead = range_of(&state, 5.0).unwrap();
    assert!((ahead - (3.0 - 0.332) / 5f64.to_radians().cos()).abs() < 0.01, "{ahead}");
    let left = range_of(&state, 90.0).unwrap();
    assert!((left - (2.0 - 0.278)).abs() < 0.01, "{left}");
    drive(&mut robot, Command::Drive { velocity: 0.5, turn: Turn::Rate(0.0) }, 1.0, &mut state);
    let closer = range_of(&state, 5.0).unwrap();
    assert!(
        (ahead - closer - state.pose.x / 5f64.to_radians().cos()).abs() < 0.02,
        "{ahead} {closer} {:?}",
        state.pose
    );
    robot.shutdown().unwrap();
    emulator.finish();
}

#[test]
fn drives_a_square_on_its_own_odometry() {
    // Closed loop on the odometry the client decodes: four 1 m legs with
    // 90° turns. The client's pose must agree with the emulator's truth, and
    // the square must close.
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let mut robot = emulator.connect();
    let state = common::drive_square(&mut robot);
    robot.shutdown().unwrap();
    let truth = emulator.finish().pose;
    let (tx, ty) = (truth.0 / 1000.0, truth.1 / 1000.0);
    assert!((tx - state.pose.x).hypot(ty - state.pose.y) < 0.01, "odometry {:?} vs truth ({tx}, {ty})", state.pose);
}

#[cfg(unix)]
#[test]
fn the_baud_switch_over_a_pseudo_terminal() {
    // The model asks for 115200: HOSTBAUD goes out, both ends follow, and the
    // session carries on at the new rate.
    use serialport::SerialPort;
    let (mut master, mut slave) = serialport::TTYPort::pair().unwrap();
    master.set_timeout(link::READ_TIMEOUT).unwrap();
    slave.set_timeout(link::READ_TIMEOUT).unwrap();
    slave.set_baud_rate(9600).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let emulator = std::thread::spawn(move || {
        serve(Box::new(master) as Box<dyn Link>, &EmulatorConfig::new(RobotModel::powerbot()), &flag).unwrap()
    });
    let mut model = RobotModel::powerbot();
    model.arcos.switch_to_baud = 115200;
    let mut robot = ArcosRobot::connect(Box::new(slave), model, &ConnectOptions::default()).unwrap();
    assert_eq!(robot.config().unwrap().host_baud, 4, "the controller reports the new rate");
    let mut state = State::default();
    drive(&mut robot, Command::Drive { velocity: 0.3, turn: Turn::Rate(0.0) }, 0.6, &mut state);
    assert!(state.pose.x > 0.05, "{:?}", state.pose);
    robot.shutdown().unwrap();
    std::thread::sleep(Duration::from_millis(100));
    stop.store(true, Ordering::Relaxed);
    assert_eq!(emulator.join().unwrap().host_baud, Some(115200));
}

#[test]
fn the_emulator_obeys_position_heading_and_wheel_commands() {
    use ubf_robots::arcos::codec::ClientCommand::*;
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let link = link::open(&emulator.address, 9600).unwrap();
    let mut raw = link.try_clone_link().unwrap();
    let mut robot = ArcosRobot::connect(link, RobotModel::powerbot(), &ConnectOptions::default()).unwrap();
    let config = robot.config().unwrap().clone();
    assert!(config.body().len() >= 123, "a CONFIG as long as a controller's: {}", config.body().len());
    assert_eq!(config.settings.trans_vel_max, 2000, "SETV is reported back");
    assert_eq!(config.settings.watchdog_ms, 2000);
    let mut send = |c: ubf_robots::arcos::codec::ClientCommand| raw.write_all(&c.packet()).unwrap();
    let mut state = State::default();

    send(Head(90));
    watch(&mut robot, 2.5, &mut state);
    assert!((state.pose.theta.to_degrees() - 90.0).abs() < 1.0, "HEAD 90: {:?}", state.pose);
    send(Move(500));
    watch(&mut robot, 3.0, &mut state);
    assert!((state.pose.y - 0.5).abs() < 0.01 && state.pose.x.abs() < 0.02, "MOVE 500: {:?}", state.pose);
    send(DHead(-90));
    watch(&mut robot, 2.5, &mut state);
    assert!(state.pose.theta.to_degrees().abs() < 1.0, "DHEAD −90: {:?}", state.pose);

    send(SetV(200));
    send(Vel(1000));
    watch(&mut robot, 1.5, &mut state);
    assert!((state.velocity - 0.2).abs() < 0.01, "VEL within SETV: {}", state.velocity);
    send(SetV(2000));
    send(Vel2(-5, 5)); // ±100 mm/s wheels: a turn on the spot
    watch(&mut robot, 1.0, &mut state);
    assert!(state.velocity.abs() < 0.01 && state.rot_velocity > 0.3, "VEL2: {} {}", state.velocity, state.rot_velocity);
    send(Vel(600));
    send(Rotate(0));
    watch(&mut robot, 1.5, &mut state);
    assert!(state.velocity > 0.55, "{}", state.velocity);
    send(EStop);
    watch(&mut robot, 0.3, &mut state);
    assert_eq!(state.velocity, 0.0, "ESTOP stops at once");
    robot.shutdown().unwrap();
    assert!(emulator.finish().closed);
}

#[test]
fn heading_commands_carry_their_rate_and_the_world_frame_is_the_callers() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let origin = ubf_core::Pose2::new(1.0, 2.0, std::f64::consts::FRAC_PI_2);
    let options = ConnectOptions { origin, max_velocity: Some(0.5), ..ConnectOptions::default() };
    let mut robot = emulator.connect_with(&options);
    assert!((robot.limits().max_velocity - 0.5).abs() < 1e-9, "the cap bounds the limits");
    let mut state = State::default();
    watch(&mut robot, 0.3, &mut state);
    assert!(state.pose.x == 1.0 && state.pose.y == 2.0, "the first SIP is the origin: {:?}", state.pose);
    // Drive forward: in the caller's frame that is +y.
    drive(&mut robot, Command::Drive { velocity: 0.3, turn: Turn::Rate(0.0) }, 1.5, &mut state);
    assert!(state.pose.y > 2.2 && (state.pose.x - 1.0).abs() < 0.02, "{:?}", state.pose);
    // Turn to the world's heading 0 at no more than 20°/s.
    let turn = Turn::Heading { heading: 0.0, max_rate: 20f64.to_radians() };
    let mut fastest = 0.0f64;
    for _ in 0..60 {
        robot.sense(&mut state).unwrap();
        fastest = fastest.max(state.rot_velocity.abs());
        robot.act(&Command::Drive { velocity: 0.0, turn }).unwrap();
        std::thread::sleep(Duration::from_millis(100));
    }
    robot.sense(&mut state).unwrap();
    assert!(state.pose.theta.abs() < 2f64.to_radians(), "{:?}", state.pose);
    assert!(fastest.to_degrees() < 20.5, "HEAD turned at {:.1}°/s", fastest.to_degrees());
    robot.shutdown().unwrap();
    let report = emulator.finish();
    assert_eq!(report.speed_limits, Some((500, 20)), "{report:?}");
}

#[test]
fn a_rate_command_after_a_slow_heading_turns_at_its_own_rate() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let mut robot = emulator.connect();
    let mut state = State::default();
    let slow = Turn::Heading { heading: 0.3, max_rate: 10f64.to_radians() };
    drive(&mut robot, Command::Drive { velocity: 0.0, turn: slow }, 0.5, &mut state);
    drive(&mut robot, Command::Drive { velocity: 0.0, turn: Turn::Rate(1.0) }, 2.0, &mut state);
    assert!(state.rot_velocity > 0.95, "SETRV was restored: {}", state.rot_velocity);
    robot.shutdown().unwrap();
    assert_eq!(emulator.finish().speed_limits.map(|l| l.1), Some(360));
}

#[test]
fn drives_to_a_goal_on_heading_commands() {
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let mut robot = emulator.connect();
    let state = common::go_to_goal(&mut robot, (1.5, 1.0));
    robot.shutdown().unwrap();
    let truth = emulator.finish().pose;
    let (tx, ty) = (truth.0 / 1000.0, truth.1 / 1000.0);
    assert!((tx - state.pose.x).hypot(ty - state.pose.y) < 0.01, "odometry {:?} vs truth ({tx}, {ty})", state.pose);
}

#[test]
fn a_halt_from_another_thread_stops_the_robot_and_holds_it() {
    // What the first Ctrl-C does while the control loop is mid-tick: STOP
    // at once, and the loop's motion commands go out as STOP from then on.
    let emulator = Emulator::tcp(RobotModel::powerbot());
    let mut robot = emulator.connect();
    let mut state = State::default();
    let go = Command::Drive { velocity: 0.4, turn: Turn::Rate(0.0) };
    drive(&mut robot, go, 1.5, &mut state);
    assert!(state.velocity > 0.3, "{}", state.velocity);
    let emergency = robot.emergency_stop().unwrap();
    std::thread::spawn(move || emergency.halt().unwrap()).join().unwrap();
    drive(&mut robot, go, 2.0, &mut state);
    assert!(state.velocity.abs() < 0.01, "still driving at {} m/s after the halt", state.velocity);
    robot.shutdown().unwrap();
    let report = emulator.finish();
    assert!(report.closed && report.motion_stopped_at.is_some());
}
