//! The pan-tilt head's driver against the emulated PTU, over a real
//! pseudo-terminal pair and over TCP loopback.

use std::net::TcpListener;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use ubf_core::{Aim, NullRobot, PanTilt, Robot, RobotError, State, StereoCamera};
use ubf_perception::features::FeatureConfig;
use ubf_perception::source::ImageDirectory;
use ubf_robots::arcos::link::{self, Link};
use ubf_robots::camera::CameraRobot;
use ubf_robots::ptu::{serve_ptu, Ptu, PtuConfig, PtuEmulatorConfig, PtuEmulatorReport};

/// An emulated head serving clients one after another until stopped; the
/// report of the first client it served.
struct Emulator {
    connection: String,
    stop: Arc<AtomicBool>,
    thread: JoinHandle<PtuEmulatorReport>,
}

impl Emulator {
    fn finish(self) -> PtuEmulatorReport {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.join().unwrap()
    }
}

#[cfg(unix)]
fn on_pty(config: PtuEmulatorConfig) -> Emulator {
    let (master, path) = link::pseudo_terminal().unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let thread = std::thread::spawn(move || loop {
        // Until a client opens the other end, the master reads EIO.
        let link: Box<dyn Link> = Box::new(master.try_clone_native().unwrap());
        let report = serve_ptu(link, &config, &flag).unwrap();
        if report.commands > 0 || flag.load(Ordering::Relaxed) {
            return report;
        }
        std::thread::sleep(Duration::from_millis(10));
    });
    Emulator { connection: path, stop, thread }
}

fn on_tcp(config: PtuEmulatorConfig) -> Emulator {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let connection = format!("tcp://{}", listener.local_addr().unwrap());
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let thread = std::thread::spawn(move || {
        let (stream, _) = listener.accept().unwrap();
        stream.set_read_timeout(Some(link::READ_TIMEOUT)).unwrap();
        serve_ptu(Box::new(stream), &config, &flag).unwrap()
    });
    Emulator { connection, stop, thread }
}

/// Waits up to 3 s for the head to read within `tolerance` of `pan`.
fn settle(ptu: &mut Ptu, pan: f64, tolerance: f64) -> Aim {
    let deadline = Instant::now() + Duration::from_secs(3);
    loop {
        let aim = ptu.measured().unwrap();
        if (aim.pan - pan).abs() <= tolerance || Instant::now() > deadline {
            return aim;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[cfg(unix)]
#[test]
fn the_head_turns_where_it_is_sent_over_a_pseudo_terminal() {
    let emulator = on_pty(PtuEmulatorConfig::default());
    let mut ptu = Ptu::connect(PtuConfig::new(&emulator.connection)).unwrap();
    // The unit's own resolution (185.1428″ a step) and limits (±3090).
    let axes = ptu.axes();
    assert!((axes.pan_step.to_degrees() - 0.051_428).abs() < 1e-5, "{axes:?}");
    assert_eq!(axes.pan_limits, [-3090, 3090]);
    assert!(ptu.measured().unwrap().pan.abs() < 1e-9);
    // 30° to the left, read back to the encoders' step.
    ptu.command(Aim { pan: 30f64.to_radians(), tilt: 0.0 }).unwrap();
    let aim = settle(&mut ptu, 30f64.to_radians(), axes.pan_step);
    assert!((aim.pan.to_degrees() - 30.0).abs() <= axes.pan_step.to_degrees(), "{aim:?}");
    // Beyond the limit: held at it, not refused.
    ptu.command(Aim { pan: 170f64.to_radians(), tilt: 0.0 }).unwrap();
    let limit = 3090.0 * axes.pan_step;
    let aim = settle(&mut ptu, limit, 1e-9);
    assert!((aim.pan - limit).abs() < 1e-9, "{aim:?}");
    drop(ptu);
    let report = emulator.finish();
    assert!((report.pan - limit).abs() < 1e-9, "{report:?}");
}

#[test]
fn an_inverted_unit_still_turns_left_for_a_positive_pan() {
    // This head counts clockwise; told so, the driver sends it the other
    // way, and reads it back the other way.
    let emulator = on_tcp(PtuEmulatorConfig { clockwise_positive: true, ..PtuEmulatorConfig::default() });
    let mut ptu = Ptu::connect(PtuConfig { invert_pan: true, ..PtuConfig::new(&emulator.connection) }).unwrap();
    ptu.command(Aim { pan: 20f64.to_radians(), tilt: 0.0 }).unwrap();
    let step = ptu.axes().pan_step;
    let aim = settle(&mut ptu, 20f64.to_radians(), step);
    assert!((aim.pan.to_degrees() - 20.0).abs() < 0.06, "{aim:?}");
    drop(ptu);
    let report = emulator.finish();
    assert!((report.pan.to_degrees() - 20.0).abs() < 0.06, "truly turned left: {report:?}");
}

#[test]
fn a_silent_head_is_reported_not_read_as_holding_still() {
    let emulator = on_tcp(PtuEmulatorConfig::default());
    let mut ptu = Ptu::connect(PtuConfig::new(&emulator.connection)).unwrap();
    assert!(ptu.measured().is_ok());
    emulator.finish();
    // Within the answer wait (1 s) plus the staleness limit (0.5 s).
    std::thread::sleep(Duration::from_millis(1600));
    let error = ptu.measured().unwrap_err();
    // A head's fault, never the robot's lost link: nothing reconnects for it.
    assert!(matches!(error, RobotError::PanTilt { .. }) && !error.is_link_loss(), "{error:?}");
    let error = error.to_string();
    assert!(error.contains("pan-tilt unit on tcp://"), "{error}");
    assert!(ptu.command(Aim::default()).is_err());
}

#[test]
fn a_dropped_driver_halts_the_head_where_it_is() {
    let emulator = on_tcp(PtuEmulatorConfig::default());
    // 10°/s: a 90° turn takes 9 s.
    let mut ptu = Ptu::connect(PtuConfig { max_rate_deg_s: 10.0, ..PtuConfig::new(&emulator.connection) }).unwrap();
    ptu.command(Aim { pan: 90f64.to_radians(), tilt: 0.0 }).unwrap();
    std::thread::sleep(Duration::from_millis(500));
    drop(ptu);
    std::thread::sleep(Duration::from_millis(300));
    let report = emulator.finish();
    assert!(report.pan > 0.0 && report.pan.to_degrees() < 20.0, "stopped on the way: {report:?}");
}

#[test]
fn nothing_answering_is_a_clear_error() {
    // A listener that accepts and never answers.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let connection = format!("tcp://{}", listener.local_addr().unwrap());
    let error = Ptu::connect(PtuConfig::new(&connection)).err().unwrap().to_string();
    assert!(error.contains("no answer to `ED`"), "{error}");
    let error = Ptu::connect(PtuConfig::new("/dev/no-such-ptu")).err().unwrap().to_string();
    assert!(error.contains("/dev/no-such-ptu"), "{error}");
}

#[test]
fn a_head_reporting_its_limits_out_of_order_is_refused_not_panicked_on() {
    let config = PtuEmulatorConfig { pan_limits: [3090, -3090], ..PtuEmulatorConfig::default() };
    let emulator = on_tcp(config);
    let error = Ptu::connect(PtuConfig::new(&emulator.connection)).err().expect("refused").to_string();
    assert!(error.contains("limits out of order"), "{error}");
    emulator.stop.store(true, Ordering::Relaxed);
}

/// Two blank pairs, half a second apart, in `dir`, and the camera they
/// suit.
fn blank_pairs(dir: &std::path::Path) -> (Box<ImageDirectory>, StereoCamera) {
    let camera = StereoCamera { width_px: 64, height_px: 48, focal_px: 50.0, ..StereoCamera::default() };
    for side in ["left", "right"] {
        std::fs::create_dir(dir.join(side)).unwrap();
        for k in 0..2 {
            image::GrayImage::new(64, 48).save(dir.join(format!("{side}/{k}.png"))).unwrap();
        }
    }
    std::fs::write(
        dir.join("frames.csv"),
        "time_s,left,right\n0.0,left/0.png,right/0.png\n0.5,left/1.png,right/1.png\n",
    )
    .unwrap();
    (Box::new(ImageDirectory::open(dir).unwrap()), camera)
}

#[test]
fn camera_frames_are_stamped_with_the_controllers_clock() {
    // The controller's clock reads 1000 s; the camera's thread started a
    // moment ago. A frame's time is on the controller's clock, so that the
    // tick and the frame can be compared.
    let dir = tempfile::tempdir().unwrap();
    let (source, camera) = blank_pairs(dir.path());
    let mut robot = CameraRobot::new(NullRobot::default(), source, camera, FeatureConfig::default(), true).unwrap();
    let mut state = State { time: 1000.0, ..State::default() };
    let deadline = Instant::now() + Duration::from_secs(5);
    while state.stereo.number < 1 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        robot.sense(&mut state).unwrap();
    }
    assert_eq!(state.stereo.number, 1);
    assert!((999.0..=1000.0).contains(&state.stereo.time), "frame at {} s", state.stereo.time);
    robot.shutdown().unwrap();
}

#[test]
fn a_camera_on_the_head_is_aimed_by_the_tree_and_its_frames_carry_the_angles_read() {
    // Two blank pairs stand in for the cameras; the head is the emulated PTU.
    let dir = tempfile::tempdir().unwrap();
    let (source, camera) = blank_pairs(dir.path());
    let emulator = on_tcp(PtuEmulatorConfig::default());
    let head = Ptu::connect(PtuConfig::new(&emulator.connection)).unwrap();
    let step = head.axes().pan_step;
    let robot = CameraRobot::new(NullRobot::default(), source, camera, FeatureConfig::default(), true).unwrap();
    let mut robot = robot.with_pan_tilt(Box::new(head));
    robot.aim_camera(25f64.to_radians()).unwrap();
    // The second pair comes 0.5 s after the first, by when the head is there.
    let mut state = State::default();
    let deadline = Instant::now() + Duration::from_secs(5);
    while state.stereo.number < 2 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        robot.sense(&mut state).unwrap();
    }
    assert_eq!(state.stereo.number, 2);
    let aim = state.camera_aim.expect("the head's angles are in the state");
    assert!((aim.pan.to_degrees() - 25.0).abs() <= step.to_degrees(), "{aim:?}");
    let mount = state.stereo.calibration.unwrap().mount;
    assert!((mount.pan_deg - aim.pan.to_degrees()).abs() < 1e-9, "{mount:?} {aim:?}");
    robot.shutdown().unwrap();
    let report = emulator.finish();
    assert!((report.pan.to_degrees() - 25.0).abs() <= step.to_degrees(), "{report:?}");
}

/// A head at 10° whose readings scatter by ±1°, one way then the other,
/// counting how often it is read.
struct ScatteringHead {
    reads: Arc<AtomicUsize>,
}

impl PanTilt for ScatteringHead {
    fn command(&mut self, _: Aim) -> Result<(), RobotError> {
        Ok(())
    }

    fn measured(&mut self) -> Result<Aim, RobotError> {
        let n = self.reads.fetch_add(1, Ordering::Relaxed);
        let scatter = if n.is_multiple_of(2) { 1.0 } else { -1.0 };
        Ok(Aim { pan: (10.0_f64 + scatter).to_radians(), tilt: 0.0 })
    }
}

#[test]
fn frames_before_the_head_is_sent_anywhere_carry_the_mean_of_many_readings() {
    let dir = tempfile::tempdir().unwrap();
    let (source, camera) = blank_pairs(dir.path());
    let reads = Arc::new(AtomicUsize::new(0));
    let robot = CameraRobot::new(NullRobot::default(), source, camera, FeatureConfig::default(), true).unwrap();
    let mut robot = robot.with_pan_tilt(Box::new(ScatteringHead { reads: reads.clone() }));
    let (mut state, mut ticks, mut pans) = (State::default(), 0, Vec::new());
    let deadline = Instant::now() + Duration::from_secs(5);
    while pans.len() < 2 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        robot.sense(&mut state).unwrap();
        ticks += 1;
        if state.stereo.number > pans.len() as u64 {
            pans.push(state.stereo.calibration.unwrap().mount.pan_deg);
        }
    }
    // The head was never sent anywhere: both frames take the first tick's
    // reading, the mean of many.
    assert_eq!(pans.len(), 2, "two frames");
    assert!(pans.iter().all(|pan| (pan - 10.0).abs() < 1e-9), "{pans:?}");
    // Many readings on the first tick, one on each after.
    assert_eq!(reads.load(Ordering::Relaxed), ticks - 1 + ubf_core::ANCHOR_READINGS, "{ticks} ticks");
    robot.shutdown().unwrap();
}

/// A head turning steadily at 20°/s from `start`, read without error.
struct TurningHead {
    start: Instant,
}

impl PanTilt for TurningHead {
    fn command(&mut self, _: Aim) -> Result<(), RobotError> {
        Ok(())
    }

    fn measured(&mut self) -> Result<Aim, RobotError> {
        Ok(Aim { pan: (20.0 * self.start.elapsed().as_secs_f64()).to_radians(), tilt: 0.0 })
    }
}

#[test]
fn a_frame_carries_the_angles_the_head_had_when_the_pair_was_taken() {
    // Ticks 0.15 s apart: a frame reaches the loop up to a tick after it
    // was taken, when the head has turned up to 3° further (about 2° here
    // when the frame took the angles read as it arrived). The bound allows
    // 25 ms between a reading and its timestamp on a busy machine.
    let dir = tempfile::tempdir().unwrap();
    let (source, camera) = blank_pairs(dir.path());
    let start = Instant::now();
    let robot = CameraRobot::new(NullRobot::default(), source, camera, FeatureConfig::default(), true).unwrap();
    let mut robot = robot.with_pan_tilt(Box::new(TurningHead { start }));
    robot.aim_camera(1.0).unwrap();
    let (mut state, mut seen) = (State::default(), 0);
    let deadline = Instant::now() + Duration::from_secs(5);
    while seen < 2 && Instant::now() < deadline {
        state.time = start.elapsed().as_secs_f64();
        robot.sense(&mut state).unwrap();
        if state.stereo.number > seen {
            seen = state.stereo.number;
            let (pan, taken) = (state.stereo.calibration.unwrap().mount.pan_deg, state.stereo.time);
            assert!((pan - 20.0 * taken).abs() < 0.5, "frame {seen}: {pan:.3}° for {:.3}°", 20.0 * taken);
        }
        std::thread::sleep(Duration::from_millis(150));
    }
    assert_eq!(seen, 2, "two frames came");
    robot.shutdown().unwrap();
}

/// A head that answers as a PTU-D46 in terse mode, holding still at 0,
/// except where `fault` answers a query (its text and how many of that
/// query came before it) in its own way: for faults the emulator does not
/// make.
fn faulty_head(mut fault: impl FnMut(&str, usize) -> Option<String> + Send + 'static) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let connection = format!("tcp://{}", listener.local_addr().unwrap());
    std::thread::spawn(move || {
        let (mut stream, _) = listener.accept().unwrap();
        let mut asked = std::collections::HashMap::<String, usize>::new();
        let mut query = Vec::new();
        let mut byte = [0u8; 1];
        use std::io::{Read, Write};
        while stream.read(&mut byte).is_ok_and(|n| n == 1) {
            if !(byte[0] == b' ' || byte[0] == b'\r') {
                query.push(byte[0]);
                continue;
            }
            let text = String::from_utf8_lossy(&std::mem::take(&mut query)).into_owned();
            let count = asked.entry(text.clone()).or_default();
            let answer = fault(&text, *count).unwrap_or_else(|| match text.as_str() {
                "PR" | "TR" => "* 185.1428".into(),
                "PN" => "* -3090".into(),
                "PX" => "* 3090".into(),
                "TN" => "* -907".into(),
                "TX" => "* 604".into(),
                "PP" | "TP" => "* 0".into(),
                _ => "*".into(),
            });
            *count += 1;
            if stream.write_all(format!("{answer}\r\n").as_bytes()).is_err() {
                return;
            }
        }
    });
    connection
}

/// What the head's driver fails with, waited for up to 3 s.
fn failure_of(connection: &str) -> String {
    let mut ptu = match Ptu::connect(PtuConfig::new(connection)) {
        Ok(ptu) => ptu,
        Err(e) => return e.to_string(),
    };
    let deadline = Instant::now() + Duration::from_secs(3);
    while Instant::now() < deadline {
        if let Err(e) = ptu.measured() {
            return e.to_string();
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    panic!("the head's driver took its readings")
}

#[test]
fn a_reading_no_head_can_give_is_refused() {
    // Beyond the unit's own limits (±3090 steps), a hundred digits long.
    let far = faulty_head(|query, n| (query == "PP" && n == 5).then(|| format!("* 1{}", "0".repeat(100))));
    let error = failure_of(&far);
    assert!(error.contains("`PP` read 1e100: outside the limits the unit reported, -3090 to 3090 steps"), "{error}");
    // Turned 154° between two readings 20 ms apart, at 60°/s.
    let jumping = faulty_head(|query, n| (query == "PP" && n == 5).then(|| "* 3000".into()));
    let error = failure_of(&jumping);
    assert!(error.contains("the pan moved 154.3°") && error.contains("faster than the 60.0°/s"), "{error}");
}

#[test]
fn an_answer_nobody_asked_for_is_refused_not_taken_for_the_next() {
    // One reading answered twice: every answer after it would be the
    // answer to the query before.
    let twice = faulty_head(|query, n| (query == "PP" && n == 3).then(|| "* 0\r\n* 0".into()));
    let error = failure_of(&twice);
    assert!(error.contains("an answer nobody asked for came before `TP`: `* 0`"), "{error}");
}

#[test]
fn a_head_describing_itself_as_no_ptu_is_refused() {
    let coarse = failure_of(&faulty_head(|query, _| (query == "PR").then(|| "* 7200".into())));
    assert!(coarse.contains("unusable resolution"), "{coarse}");
    let endless = failure_of(&faulty_head(|query, _| (query == "PN").then(|| "* -99999999".into())));
    assert!(endless.contains("limits beyond a full turn"), "{endless}");
    // Its words are shown, never obeyed by the terminal.
    let escaping = faulty_head(|query, _| (query == "FT").then(|| format!("! \x1b[2J{}", "x".repeat(500))));
    let error = failure_of(&escaping);
    assert!(error.contains("`FT` refused: \\u{1b}[2Jxxx") && !error.contains('\x1b'), "{error}");
    assert!(error.len() < 200, "cut short: {error}");
}

#[test]
fn a_head_that_answers_each_query_just_in_time_does_not_hold_the_drive_for_long() {
    // Each answer 0.9 s late, within the wait for one (1 s): a dozen of
    // them took 11 s, deaf to Ctrl-C.
    let slow = faulty_head(|_, _| {
        std::thread::sleep(Duration::from_millis(900));
        None
    });
    let started = Instant::now();
    let error = Ptu::connect(PtuConfig::new(&slow)).err().expect("refused").to_string();
    assert!(error.contains("no answer to"), "{error}");
    assert!(started.elapsed() < Duration::from_secs(5), "{:?}", started.elapsed());
}

#[test]
fn a_head_that_talks_before_it_is_asked_and_answers_late_at_times_is_taken() {
    // A reset's limit notices and its end, trickling in before the first
    // command; then a pan turning at the speed set (1167 steps/s), whose
    // every other reading is answered 0.3 s late.
    let started = Instant::now();
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let turning = format!("tcp://{}", listener.local_addr().unwrap());
    let upstream = faulty_head(move |query, n| match query {
        "PP" => {
            if n % 2 == 1 {
                std::thread::sleep(Duration::from_millis(300));
            }
            Some(format!("* {}", (1167.0 * started.elapsed().as_secs_f64()).min(3090.0).round()))
        }
        _ => None,
    });
    std::thread::spawn(move || {
        let (mut client, _) = listener.accept().unwrap();
        use std::io::Write;
        for notice in ["!T", "!T", "!P", "!P*"] {
            client.write_all(format!("{notice}\r\n").as_bytes()).unwrap();
            std::thread::sleep(Duration::from_millis(30));
        }
        // And one more after a pause, as an axis reaching its limit late.
        std::thread::sleep(Duration::from_millis(150));
        client.write_all(b"!T!T!P!P*\r\n").unwrap();
        let mut head = std::net::TcpStream::connect(upstream.trim_start_matches("tcp://")).unwrap();
        let (mut to_head, mut from_head) = (client.try_clone().unwrap(), head.try_clone().unwrap());
        std::thread::spawn(move || std::io::copy(&mut to_head, &mut head));
        let _ = std::io::copy(&mut from_head, &mut client);
    });
    let mut ptu = Ptu::connect(PtuConfig::new(&turning)).unwrap();
    let deadline = Instant::now() + Duration::from_secs(3);
    while Instant::now() < deadline {
        ptu.measured().unwrap();
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(ptu.measured().unwrap().pan.to_degrees() > 100.0, "it turned");
}
