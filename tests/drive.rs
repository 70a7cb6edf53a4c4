//! `ubf drive` against `ubf emulate-powerbot`, both as real processes over
//! TCP loopback: drive to a goal, stop on SIGTERM, close the session, keep
//! the log.

mod common;

use common::{emulator, emulator_with, ptu_emulator, wait_for, Killed};
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::Duration;

/// A loopback address nothing listens on: a port the system just handed
/// out and took back (a fixed one may be held by another program).
fn unused_address() -> String {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    listener.local_addr().unwrap().to_string()
}

fn config(address: &str, log: &std::path::Path, extra: &str) -> String {
    format!(
        r#"RobotConfig(
            name: "test",
            connection: "{address}",
            model: Powerbot,
            log: "{}",
            goal: (x: 1.0, y: 0.0, tolerance: 0.2),
            {extra}
            root: Composite(arbiter: CommandFusion, children: [
                (behavior: Stop(), weight: 1.0),
                (behavior: GoTo(cruise_speed: 0.4)),
            ]),
        )"#,
        log.display()
    )
}

#[test]
fn drives_to_the_goal_and_stops_safely_on_sigterm() {
    let (mut emulator, address, mut emulator_out) = emulator();
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv");
    let file = dir.path().join("robot.ron");
    std::fs::write(&file, config(&address, &log, "")).unwrap();
    let mut drive = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).spawn().unwrap();
    std::thread::sleep(Duration::from_secs(6));
    let status = Command::new("kill").args(["-TERM", &drive.id().to_string()]).status().unwrap();
    assert!(status.success());
    assert_eq!(drive.wait().unwrap().code(), Some(130), "ubf drive exits as interrupted on SIGTERM");

    // The emulator saw the session closed, with the robot at the goal.
    let mut line = String::new();
    emulator_out.read_line(&mut line).unwrap();
    assert!(line.contains("closed true"), "{line}");
    let x: f64 = line.split('(').nth(1).unwrap().split(',').next().unwrap().parse().unwrap();
    assert!((0.75..=1.05).contains(&x), "{line}");
    emulator.kill().unwrap();

    let text = std::fs::read_to_string(&log).unwrap();
    assert!(text.lines().count() > 20, "the log was flushed");
    assert!(text.lines().last().unwrap().contains("root/Stop"), "stopped at the goal");
}

#[test]
fn a_drive_whose_stderr_nobody_reads_reaches_its_goal_and_ends_with_its_own_status() {
    // A pipe whose reader went away: each line said fails. eprintln! made
    // that a panic (exit 101) at the first line, before the robot moved.
    let (mut emulator, address, mut emulator_out) = emulator();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    std::fs::write(&file, config(&address, &dir.path().join("log.csv"), "")).unwrap();
    let mut drive = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["drive", file.to_str().unwrap(), "--until-goal"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(drive.stderr.take());
    let status = wait_for(&mut drive, 60.0).expect("the drive ended");
    assert_eq!(status.code(), Some(0), "the drive ended as it would with its stderr read");
    let mut line = String::new();
    emulator_out.read_line(&mut line).unwrap();
    assert!(line.contains("closed true"), "{line}");
    emulator.kill().unwrap();
}

#[test]
fn bad_configurations_and_unreachable_robots_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    let nobody = format!("tcp://{}", unused_address());
    std::fs::write(&file, config(&nobody, &dir.path().join("l.csv"), "speed: 2,")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("speed"));
    // Nothing listens there: with on_link_loss Exit, a clean error.
    std::fs::write(&file, config(&nobody, &dir.path().join("l.csv"), "on_link_loss: Exit,")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains(&nobody[6..]));
}

#[cfg(unix)]
#[test]
fn the_emulator_on_a_pseudo_terminal_serves_one_client_after_another() {
    let (mut emulator, path, mut emulator_out) = emulator_with(&["--pty", "--room", "8x4"]);
    assert!(path.starts_with("/dev/"), "{path}");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    std::fs::write(&file, config(&path, &dir.path().join("l.csv"), "max_time_s: 1.5,")).unwrap();
    for _ in 0..2 {
        let out = Command::new(env!("CARGO_BIN_EXE_ubf"))
            .args(["drive", "--dry-run", file.to_str().unwrap()])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
        assert!(text.contains("controller      Pioneer powerbot, serial EMU-0001"), "{text}");
        assert!(text.contains("motors          left disabled"), "{text}");
        // The room's side wall is 2 m from the centre; the nearest echo is
        // the side transducers', 2 − 0.278 m.
        assert!(text.contains("nearest sonar echo 1.72 m"), "{text}");
        let mut line = String::new();
        emulator_out.read_line(&mut line).unwrap();
        assert!(line.contains("closed true"), "{line}");
    }
    emulator.kill().unwrap();
}

#[test]
fn reconnects_after_the_robot_vanishes_and_stops_cleanly() {
    let (mut first, address, _) = emulator();
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv");
    let file = dir.path().join("robot.ron");
    std::fs::write(&file, config(&address, &log, "on_link_loss: Reconnect,")).unwrap();
    let mut drive = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["drive", file.to_str().unwrap()])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs(2));
    // The robot side dies without a word, then comes back on the same port.
    first.kill().unwrap();
    first.wait().unwrap();
    assert!(wait_for(&mut drive, 2.0).is_none(), "ubf drive keeps trying");
    let listen = address.trim_start_matches("tcp://");
    let (mut second, _, mut second_out) = emulator_with(&["--listen", listen]);
    std::thread::sleep(Duration::from_secs(4));
    Command::new("kill").args(["-TERM", &drive.id().to_string()]).status().unwrap();
    let status = wait_for(&mut drive, 10.0).expect("ubf drive exits on SIGTERM");
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut drive.stderr.take().unwrap(), &mut stderr).unwrap();
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("link lost"), "{stderr}");
    assert_eq!(stderr.matches("connected to").count(), 2, "{stderr}");
    let mut line = String::new();
    second_out.read_line(&mut line).unwrap();
    assert!(line.contains("closed true"), "the new session was closed: {line}");
    second.kill().unwrap();
    // One log per session, each flushed.
    for path in [log.clone(), log.with_extension("2.csv")] {
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.lines().count() > 5, "{}", path.display());
    }
}

#[test]
fn exits_when_the_robot_vanishes_if_so_configured() {
    let (mut emulator, address, _) = emulator();
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv");
    let file = dir.path().join("robot.ron");
    std::fs::write(&file, config(&address, &log, "on_link_loss: Exit,")).unwrap();
    let mut drive = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).spawn().unwrap();
    std::thread::sleep(Duration::from_secs(2));
    emulator.kill().unwrap();
    let status = wait_for(&mut drive, 10.0).expect("ubf drive gives up");
    assert_eq!(status.code(), Some(1));
    assert!(std::fs::read_to_string(&log).unwrap().lines().count() > 5, "the log was flushed");
}

/// Records `count` rendered pairs of the rendered corridor into
/// `dir/frames`, to stand in for the cameras.
fn record_frames(dir: &std::path::Path, count: u32) {
    let record = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["frames", "scenarios/rendered-corridor.ron", "--max-frames", &count.to_string(), "--out"])
        .arg(dir.join("frames"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(record.status.success(), "{}", String::from_utf8_lossy(&record.stderr));
}

#[test]
fn a_dry_run_with_a_camera_shows_live_landmark_counts() {
    // Recorded rendered pairs stand in for the cameras: replayed at their
    // own pace (2 Hz) through the pipeline and egomotion while the robot
    // stays still with its motors off.
    let dir = tempfile::tempdir().unwrap();
    record_frames(dir.path(), 8);
    let (mut emulator, address, _) = emulator();
    let file = dir.path().join("robot.ron");
    let extra = r#"max_time_s: 3.5,
            camera: (source: Directory("frames"), stereo: (focal_px: 554.3)),
            egomotion: (estimator: Rigid()),"#;
    std::fs::write(&file, config(&address, &dir.path().join("l.csv"), extra)).unwrap();
    let out =
        Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", "--dry-run", file.to_str().unwrap()]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    let counts: Vec<(u64, usize)> = text
        .lines()
        .filter_map(|l| l.strip_prefix("camera          frame "))
        .map(|l| {
            let (frame, rest) = l.split_once(": ").unwrap();
            (frame.parse().unwrap(), rest.split(' ').next().unwrap().parse().unwrap())
        })
        .collect();
    assert!(counts.len() >= 2, "{text}");
    let (last_frame, last_count) = *counts.last().unwrap();
    assert!(last_frame >= 4 && last_count > 10, "{text}");
    assert!(text.contains("egomotion") && !text.contains("egomotion 0 steps"), "{text}");
    // Cameras this build cannot open are a clean error, not a panic: without
    // the `v4l` feature it says how to get it; with it, the device is named.
    let extra = r#"camera: (source: V4l(left: "/dev/video-left-missing", right: "/dev/video-right-missing")),"#;
    std::fs::write(&file, config(&address, &dir.path().join("l.csv"), extra)).unwrap();
    let out =
        Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", "--dry-run", file.to_str().unwrap()]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("--features v4l") || stderr.contains("video-left-missing"), "{stderr}");
    emulator.kill().unwrap();
    // Egomotion without a camera is refused when the file is read.
    std::fs::write(&file, config(&address, &dir.path().join("l.csv"), "egomotion: (),")).unwrap();
    let out =
        Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", "--dry-run", file.to_str().unwrap()]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("egomotion needs a camera"));
}

#[test]
fn a_dry_run_turns_a_pan_tilt_head_left_and_back_and_shows_its_angles() {
    // The head is `ubf emulate-ptu` on a pseudo-terminal, as its serial
    // port would be; the robot `ubf emulate-powerbot` over TCP.
    let dir = tempfile::tempdir().unwrap();
    record_frames(dir.path(), 2);
    let (mut emulator, address, _) = emulator();
    let mut head =
        Command::new(env!("CARGO_BIN_EXE_ubf")).args(["emulate-ptu", "--pty"]).stdout(Stdio::piped()).spawn().unwrap();
    let mut head_out = BufReader::new(head.stdout.take().unwrap());
    let mut head = Killed(head);
    let mut line = String::new();
    head_out.read_line(&mut line).unwrap();
    let device = line.trim().strip_prefix("emulating a pan-tilt unit on ").expect("the device is named").to_owned();
    let file = dir.path().join("robot.ron");
    let extra = format!(
        r#"max_time_s: 5.5,
            camera: (source: Directory("frames"), stereo: (focal_px: 554.3), pan_tilt: (connection: "{device}")),"#
    );
    std::fs::write(&file, config(&address, &dir.path().join("l.csv"), &extra)).unwrap();
    let out =
        Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", "--dry-run", file.to_str().unwrap()]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    // (commanded, measured) once a second: 20° left for 3 s, then ahead.
    let angles: Vec<(f64, f64)> = text
        .lines()
        .filter_map(|l| l.strip_prefix("pan-tilt        commanded "))
        .map(|l| {
            let (commanded, rest) = l.split_once("°, measured ").unwrap();
            (commanded.parse().unwrap(), rest.split('°').next().unwrap().parse().unwrap())
        })
        .collect();
    assert!(angles.len() >= 4, "{text}");
    assert!(angles.iter().any(|&(c, m)| c == 20.0 && (m - 20.0).abs() < 0.06), "reached 20° left: {text}");
    let &(commanded, measured) = angles.last().unwrap();
    assert!(commanded == 0.0 && measured.abs() < 0.06, "back ahead: {text}");
    head.kill().unwrap();
    emulator.kill().unwrap();
    // A head that does not answer stops the dry run before it starts.
    let extra = r#"camera: (source: Directory("frames"), pan_tilt: (connection: "/dev/no-such-head")),"#;
    std::fs::write(&file, config(&address, &dir.path().join("l.csv"), extra)).unwrap();
    let out =
        Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", "--dry-run", file.to_str().unwrap()]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("pan-tilt unit on /dev/no-such-head"), "{stderr}");
}

/// A robot file with `root` as its tree and `extra` fields.
fn robot_file(address: &str, log: &std::path::Path, extra: &str, root: &str) -> String {
    format!(
        r#"RobotConfig(name: "test", connection: "{address}", model: Powerbot, log: "{}", {extra} root: {root})"#,
        log.display()
    )
}

/// `name=value` from the emulator's report line, `None` for `-`.
fn field(line: &str, name: &str) -> Option<f64> {
    let value = line.split(&format!("{name}=")).nth(1)?.split([' ', ',']).next()?;
    value.trim().parse().ok()
}

/// The emulator's next report line.
fn report_line(out: &mut BufReader<std::process::ChildStdout>) -> String {
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    line
}

const GO_ONLY: &str = "Composite(arbiter: CommandFusion, children: [(behavior: GoTo(cruise_speed: 0.3))])";

/// Drives `root` to its end on an emulator started with `emulator_args`,
/// the robot file carrying `extra`: the drive's output, the emulator's
/// report line on the session, and the directory with `log.csv`.
fn drive_on(emulator_args: &[&str], extra: &str, root: &str) -> (std::process::Output, String, tempfile::TempDir) {
    let (mut emulator, address, mut out) = emulator_with(emulator_args);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    std::fs::write(&file, robot_file(&address, &dir.path().join("log.csv"), extra, root)).unwrap();
    let drive = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["drive", file.to_str().unwrap()])
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap();
    let line = report_line(&mut out);
    emulator.kill().unwrap();
    (drive, line, dir)
}

#[test]
fn stale_data_stops_motion_and_the_link_is_declared_lost_on_time() {
    // SIPs stop 3 s into the session while commands still reach the robot:
    // a tree with nothing but GoTo would command motion blind.
    let extra = "on_link_loss: Exit, goal: (x: 20.0, y: 0.0),";
    let (drive, line, dir) = drive_on(&["--listen", "127.0.0.1:0", "--silence", "3:5"], extra, GO_ONLY);
    let stderr = String::from_utf8_lossy(&drive.stderr);
    assert_eq!(drive.status.code(), Some(1), "{stderr}");
    assert!(line.contains("closed true"), "{line}");
    assert_eq!(field(&line, "motion_before_first_sip"), Some(0.0), "{line}");
    // Documented: no motion command once data is 0.25 s old, so the last
    // one leaves within that and a tick; STOP follows on the next tick.
    let last_motion = field(&line, "last_motion_after_silence_s").unwrap_or(0.0);
    let stop = field(&line, "stop_after_silence_s").expect("a STOP during the silence");
    assert!(last_motion <= 0.6 && stop <= 0.7, "{line}");
    // Documented: the link is lost after 1.3 s without data.
    let lost: f64 = stderr.split("no sensor data for ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!((1.3..2.0).contains(&lost), "{stderr}");
    let log = std::fs::read_to_string(dir.path().join("log.csv")).unwrap();
    assert!(log.lines().next().unwrap().contains(",winner,hold,") && !log.contains("true_x"), "{log}");
    assert!(log.contains(",stale_data"), "the log says why the robot was held");
}

#[test]
fn the_goal_keeps_its_place_across_a_reconnect() {
    // Every session freezes after 4 s (about 2 m in); the driver reconnects and the
    // emulated controller starts its odometry from zero again, as a
    // restarted simulator does. The goal 3 m ahead must still be 3 m from
    // where the drive began.
    let (mut emulator, address, mut out) = emulator_with(&["--listen", "127.0.0.1:0", "--silence", "4:60"]);
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv");
    let file = dir.path().join("robot.ron");
    let root = "Composite(arbiter: CommandFusion, children: [
        (behavior: Stop(), weight: 1.0), (behavior: GoTo(cruise_speed: 0.6))])";
    // The second session reaches the goal about 10 s in, however loaded
    // the machine: 6 s to spare.
    let extra = "on_link_loss: Reconnect, max_time_s: 16.0, goal: (x: 3.0, y: 0.0, tolerance: 0.1),";
    std::fs::write(&file, robot_file(&address, &log, extra, root)).unwrap();
    let drive = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).output().unwrap();
    let stderr = String::from_utf8_lossy(&drive.stderr);
    assert!(drive.status.success(), "{stderr}");
    let sessions = stderr.matches("connected to").count();
    let mut travelled = 0.0;
    for _ in 0..sessions {
        let line = report_line(&mut out);
        travelled += line.split('(').nth(1).unwrap().split(',').next().unwrap().parse::<f64>().unwrap();
    }
    emulator.kill().unwrap();
    assert!(sessions >= 2, "{stderr}");
    assert!(
        (travelled - 3.0).abs() < 0.25,
        "drove {travelled:.3} m in {sessions} sessions toward a 3 m goal: {stderr}"
    );
    // One log per session, each named once, none overwritten.
    assert!(stderr.contains(&format!("logs: {}, ", log.display())), "{stderr}");
    assert!(log.with_extension("2.csv").exists());
    // Each session's MCAP log beside its CSV one, readable and whole.
    for mcap in [log.with_extension("mcap"), log.with_extension("2.mcap")] {
        let replayed = ubf::replay::read(&mcap).unwrap();
        assert!(replayed.cut_short.is_none() && replayed.timeline.time.len() > 5, "{}", mcap.display());
        assert!(replayed.run.unwrap().scenario.starts_with("drive"));
    }
}

#[test]
fn sigterm_ends_a_flooded_and_suspended_drive_promptly() {
    // 10 000 SIPs a second, and the driver suspended for 3 s meanwhile.
    let (mut emulator, address, mut out) = emulator_with(&["--listen", "127.0.0.1:0", "--sip-period-ms", "0.1"]);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    let extra = "goal: (x: 20.0, y: 0.0),";
    std::fs::write(&file, robot_file(&address, &dir.path().join("log.csv"), extra, GO_ONLY)).unwrap();
    let mut drive = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).spawn().unwrap();
    std::thread::sleep(Duration::from_secs(2));
    let pid = drive.id().to_string();
    Command::new("kill").args(["-STOP", &pid]).status().unwrap();
    std::thread::sleep(Duration::from_secs(3));
    Command::new("kill").args(["-CONT", &pid]).status().unwrap();
    std::thread::sleep(Duration::from_millis(300));
    Command::new("kill").args(["-TERM", &pid]).status().unwrap();
    // The documented bound is 1.5 s; a hang is what this catches.
    let status = wait_for(&mut drive, 5.0).expect("ubf drive exits on SIGTERM");
    assert_eq!(status.code(), Some(130));
    let line = report_line(&mut out);
    emulator.kill().unwrap();
    assert!(line.contains("closed true") && field(&line, "sips").unwrap() > 10_000.0, "{line}");
    assert!(std::fs::read_to_string(dir.path().join("log.csv")).unwrap().lines().count() > 10);
}

/// The fastest the log's odometry moved over any half second, m/s.
fn fastest_odometry_speed(log: &str) -> f64 {
    let mut lines = log.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|&h| h == name).unwrap();
    let (t, x, y) = (column("time_s"), column("odom_x"), column("odom_y"));
    let rows: Vec<(f64, f64, f64)> = lines
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            Some((f.get(t)?.parse().ok()?, f.get(x)?.parse().ok()?, f.get(y)?.parse().ok()?))
        })
        .collect();
    let mut fastest = 0.0_f64;
    for (i, a) in rows.iter().enumerate() {
        if let Some(b) = rows[i..].iter().find(|b| b.0 - a.0 >= 0.5) {
            fastest = fastest.max((b.1 - a.1).hypot(b.2 - a.2) / (b.0 - a.0));
        }
    }
    fastest
}

#[test]
fn sigterm_at_speed_brakes_before_the_motors_go_off() {
    let (status, stderr, line) = interrupt_at_speed("kill -TERM $PID");
    assert_eq!(status.code(), Some(130), "{stderr}");
    let speed = field(&line, "speed_at_disable_mm_s").expect("ENABLE 0 arrived");
    assert!(speed.abs() <= 20.0, "motors switched off at {speed} mm/s: {line}");
}

/// `ubf drive` on the emulator at 1 m/s, where the emulated Powerbot needs
/// 2 s to brake at its 0.5 m/s²: interrupted after 4 s by `signal` (a shell
/// given `$PID`); its exit status, its stderr and the emulator's report
/// line.
fn interrupt_at_speed(signal: &str) -> (std::process::ExitStatus, String, String) {
    let (mut emulator, address, mut out) = emulator();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    let fast = "Composite(arbiter: CommandFusion, children: [(behavior: GoTo(cruise_speed: 1.0))])";
    std::fs::write(&file, robot_file(&address, &dir.path().join("log.csv"), "goal: (x: 40.0, y: 0.0),", fast)).unwrap();
    let mut drive = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["drive", file.to_str().unwrap()])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs(4));
    Command::new("sh").args(["-c", signal]).env("PID", drive.id().to_string()).status().unwrap();
    let status = wait_for(&mut drive, 10.0).expect("ubf drive exits");
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut drive.stderr.take().unwrap(), &mut stderr).unwrap();
    let line = report_line(&mut out);
    emulator.kill().unwrap();
    let fastest = fastest_odometry_speed(&std::fs::read_to_string(dir.path().join("log.csv")).unwrap());
    assert!(fastest > 0.9, "the robot was at speed when told to stop: {fastest} m/s");
    // Even exiting at once leaves the MCAP log readable up to its last
    // second.
    let said = mcap_check(&["--cut-short".as_ref(), dir.path().join("log.mcap").as_os_str()]);
    assert!(said.contains("| /pose/odometry |"), "{said}");
    (status, stderr, line)
}

/// A TCP proxy to the emulator at `upstream` (`tcp://host:port`): its
/// address, for one drive. `after` the drive connects, it half-closes the
/// link towards the drive (the drive reads its end, as from a robot whose
/// sending side failed) while still passing the drive's commands on.
fn half_closing_proxy(upstream: &str, after: Duration) -> String {
    use std::io::{Read, Write};
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let address = format!("tcp://{}", listener.local_addr().unwrap());
    let upstream = upstream.trim_start_matches("tcp://").to_owned();
    std::thread::spawn(move || {
        let (mut drive, _) = listener.accept().unwrap();
        let mut robot = std::net::TcpStream::connect(upstream).unwrap();
        let (mut commands, mut to_robot) = (drive.try_clone().unwrap(), robot.try_clone().unwrap());
        std::thread::spawn(move || {
            let _ = std::io::copy(&mut commands, &mut to_robot);
            // The drive has gone: the emulator's session ends, and it reports.
            let _ = to_robot.shutdown(std::net::Shutdown::Both);
        });
        robot.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
        let started = std::time::Instant::now();
        let mut buffer = [0u8; 4096];
        let mut passing = true;
        loop {
            if passing && started.elapsed() >= after {
                drive.shutdown(std::net::Shutdown::Write).unwrap();
                passing = false;
            }
            match robot.read(&mut buffer) {
                Ok(0) => return,
                Err(e) if !matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => return,
                // Still read once the drive no longer hears them, so that
                // the emulator never blocks writing its SIPs.
                Ok(n) if passing => drive.write_all(&buffer[..n]).unwrap(),
                _ => {}
            }
        }
    });
    address
}

#[test]
fn a_link_half_closed_at_speed_still_brakes_before_the_motors_go_off() {
    // The drive reads the link's end 4 s in, at 1 m/s; its STOP and ENABLE 0
    // still reach the robot, so ENABLE 0 must wait out the braking as after
    // any STOP. It came 11 ms after STOP, at 240 mm/s, before.
    let (mut emulator, upstream, mut out) = emulator();
    let address = half_closing_proxy(&upstream, Duration::from_secs(4));
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    let fast = "Composite(arbiter: CommandFusion, children: [(behavior: GoTo(cruise_speed: 1.0))])";
    let extra = "goal: (x: 40.0, y: 0.0), on_link_loss: Exit,";
    std::fs::write(&file, robot_file(&address, &dir.path().join("log.csv"), extra, fast)).unwrap();
    let drive = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).output().unwrap();
    let line = report_line(&mut out);
    emulator.kill().unwrap();
    let stderr = String::from_utf8_lossy(&drive.stderr);
    assert_eq!(drive.status.code(), Some(1), "the link was lost: {stderr}");
    let fastest = fastest_odometry_speed(&std::fs::read_to_string(dir.path().join("log.csv")).unwrap());
    assert!(fastest > 0.9, "the robot was at speed when the link half-closed: {fastest} m/s");
    let speed = field(&line, "speed_at_disable_mm_s").expect("ENABLE 0 arrived");
    assert!(speed.abs() <= 20.0, "motors switched off at {speed} mm/s: {line}\n{stderr}");
    assert!(stderr.contains("no sensor data after STOP; waited the"), "{stderr}");
}

#[test]
fn a_second_interrupt_forces_the_exit_after_stop() {
    // Half a second into the 2 s of braking the first one started.
    let (status, stderr, line) = interrupt_at_speed("kill -INT $PID; sleep 0.5; kill -INT $PID");
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted twice: robot sent STOP, ENABLE 0 and CLOSE; exiting now"), "{stderr}");
    assert!(line.contains("closed true"), "STOP, ENABLE 0 and CLOSE went out: {line}");
    let speed = field(&line, "speed_at_disable_mm_s").expect("ENABLE 0 arrived");
    assert!(speed.abs() > 100.0, "the motors went off without waiting to brake, not at {speed} mm/s: {line}");
}

#[test]
fn a_signal_sent_twice_at_once_is_one_interrupt() {
    // As GNU `timeout` sends it, to the process and to its process group:
    // the orderly stop, braking before the motors go off. (50 ms apart, as
    // two signals closer than the handler takes them may merge into one.)
    let (status, stderr, line) = interrupt_at_speed("kill -TERM $PID; sleep 0.05; kill -TERM $PID");
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(!stderr.contains("interrupted twice"), "{stderr}");
    let speed = field(&line, "speed_at_disable_mm_s").expect("ENABLE 0 arrived");
    assert!(speed.abs() <= 20.0, "motors switched off at {speed} mm/s: {line}");
}

#[test]
fn a_control_loop_that_stops_ticking_has_the_robot_stopped_from_outside_it() {
    // The loop hangs 2 s into the drive for 8 s, the robot driving on its
    // last command: the watch sends STOP once the ticks have been silent
    // for `link_lost_after_s` (1.3 s), long before the hang ends (without
    // it, the robot's own watchdog stops the motors, and STOP comes when
    // the hang ends in a panic, 10 s in).
    let hanging = "Composite(arbiter: CommandFusion, children: [(behavior: InjectFault(after_s: 2.0, hang_s: 8.0)), \
                   (behavior: GoTo(cruise_speed: 0.3))])";
    let began = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs_f64();
    let (drive, line, _dir) = drive_on(&[], "goal: (x: 20.0, y: 0.0),", hanging);
    let stderr = String::from_utf8_lossy(&drive.stderr);
    assert!(stderr.contains("error: the control loop has not ticked for 1."), "{stderr}");
    assert!(stderr.contains("robot stopped and held still"), "{stderr}");
    let stopped = field(&line, "motion_stopped_at").expect("a STOP after motion") - began;
    assert!(stopped < 6.0, "STOP came {stopped:.1} s into the drive: {line}");
    // The hang ends in the fault's panic, which ends the drive as ever.
    assert_eq!(drive.status.code(), Some(1), "{stderr}");
}

#[test]
fn a_stall_latches_a_stop_until_the_operator_allows_motion() {
    // Driven into the wall of a 4 m room with nothing to avoid it: the
    // robot stalls once and then stays stopped.
    let extra = "goal: (x: 5.0, y: 0.0), max_time_s: 8.0, safety: (resume_after_s: None),";
    let (drive, line, dir) = drive_on(&["--listen", "127.0.0.1:0", "--room", "4x4"], extra, GO_ONLY);
    assert!(drive.status.success(), "{}", String::from_utf8_lossy(&drive.stderr));
    let stalled = field(&line, "stalled_cycles").unwrap();
    // Held on the first stall report: a few cycles, against one every
    // 0.2 s for the whole run when nothing latched.
    assert!((1.0..=5.0).contains(&stalled), "stalled for {stalled} SIP cycles: {line}");
    let log = std::fs::read_to_string(dir.path().join("log.csv")).unwrap();
    assert!(log.lines().last().unwrap().contains(",contact,"), "{log}");
}

#[test]
fn a_released_contact_is_not_driven_into_again() {
    // Its goal beyond the wall of a 4 m room and half a second's hold
    // after a stall: the latch used to release the robot straight back
    // into the wall, stalling again every couple of seconds.
    let extra = "goal: (x: 5.0, y: 0.0), max_time_s: 12.0, safety: (resume_after_s: Some(0.5)),";
    let (drive, line, dir) = drive_on(&["--listen", "127.0.0.1:0", "--room", "4x4"], extra, GO_ONLY);
    assert!(drive.status.success(), "{}", String::from_utf8_lossy(&drive.stderr));
    let stalled = field(&line, "stalled_cycles").unwrap();
    assert!((1.0..=5.0).contains(&stalled), "stalled for {stalled} SIP cycles: {line}");
    let log = std::fs::read_to_string(dir.path().join("log.csv")).unwrap();
    assert!(log.lines().last().unwrap().contains(",contact,"), "still held off the wall at the end: {log}");
}

#[test]
fn a_robot_that_gets_nowhere_is_stopped_and_the_drive_gives_up() {
    // Pressed against the wall of a 4 m room, its goal beyond: without a
    // progress check the drive would hold it there until the time limit
    // (which it would say instead of "no progress").
    let extra = "goal: (x: 5.0, y: 0.0), max_time_s: 60.0, progress: (radius_m: 0.3, window_s: 2.0),";
    let (drive, line, _dir) = drive_on(&["--listen", "127.0.0.1:0", "--room", "4x4"], extra, GO_ONLY);
    let stderr = String::from_utf8_lossy(&drive.stderr);
    assert_eq!(drive.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no progress"), "{stderr}");
    assert!(line.contains("closed true"), "STOP, ENABLE 0 and CLOSE went out: {line}");
}

#[test]
fn a_drive_with_the_wall_compass_reaches_its_goal_down_a_room() {
    // The compass between the ARCOS client and the tree: the emulator's
    // sonar ring sees the room's side walls 2 m away as the robot drives
    // 3 m along it.
    let extra = "goal: (x: 3.0, y: 0.0, tolerance: 0.2), until_goal: true, max_time_s: 60.0, wall_compass: (),";
    let (drive, line, _dir) = drive_on(&["--listen", "127.0.0.1:0", "--room", "12x4"], extra, GO_ONLY);
    let stderr = String::from_utf8_lossy(&drive.stderr);
    assert_eq!(drive.status.code(), Some(0), "{stderr}");
    assert!(line.contains("closed true"), "STOP, ENABLE 0 and CLOSE went out: {line}");
}

#[test]
fn a_panicking_behaviour_stops_the_robot_and_is_named() {
    let root = "Composite(arbiter: CommandFusion, children: [
        (behavior: InjectFault(after_s: 1.5, message: \"lost my mind\")), (behavior: GoTo(cruise_speed: 0.3))])";
    let (drive, line, dir) = drive_on(&["--listen", "127.0.0.1:0"], "goal: (x: 20.0, y: 0.0),", root);
    let stderr = String::from_utf8_lossy(&drive.stderr);
    assert_eq!(drive.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("error: behaviour root/InjectFault panicked: lost my mind"), "{stderr}");
    assert!(line.contains("closed true"), "{line}");
    assert!(std::fs::read_to_string(dir.path().join("log.csv")).unwrap().lines().count() > 10);
}

#[test]
fn a_killed_drive_keeps_its_log_up_to_the_last_second() {
    let (mut emulator, address, _) = emulator();
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv");
    let file = dir.path().join("robot.ron");
    std::fs::write(&file, robot_file(&address, &log, "goal: (x: 20.0, y: 0.0),", GO_ONLY)).unwrap();
    let mut drive = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).spawn().unwrap();
    let rows = || std::fs::read_to_string(&log).map_or(0, |t| t.lines().count().saturating_sub(1));
    // From the first rows on disk, 4 s of ticking: 40 rows.
    let deadline = std::time::Instant::now() + Duration::from_secs(20);
    while rows() == 0 && std::time::Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    let before = rows();
    std::thread::sleep(Duration::from_secs(4));
    drive.kill().unwrap();
    drive.wait().unwrap();
    emulator.kill().unwrap();
    // At most a second's worth (10 rows) may be lost, and a little for a
    // loaded machine's late ticks.
    let after = rows();
    assert!(after >= before + 25, "{before} rows, then {after} after 4 s");
    // The MCAP log beside it opens in the MCAP project's own reader, which
    // needs a footer at the end of the file, and holds the same ticks less
    // at most the last second's.
    let check = Command::new("python3")
        .arg(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/mcap-check.py"))
        .arg("--cut-short")
        .arg(log.with_extension("mcap"))
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&check.stdout);
    assert!(check.status.success(), "{said}{}", String::from_utf8_lossy(&check.stderr));
    let poses: usize = said
        .lines()
        .find(|l| l.starts_with("| /pose/odometry |"))
        .and_then(|l| l.trim_end_matches(" |").rsplit("| ").next()?.parse().ok())
        .unwrap_or_else(|| panic!("{said}"));
    assert!(poses + 12 >= after, "{poses} poses in the MCAP log against {after} rows in the CSV one");
}

#[test]
fn a_camera_no_pair_could_have_is_refused_before_connecting() {
    let (mut emulator, address, _) = emulator();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    let extra = r#"camera: (source: Directory("frames"), stereo: (focal_px: 1e-9)), egomotion: (),"#;
    std::fs::write(&file, robot_file(&address, &dir.path().join("log.csv"), extra, GO_ONLY)).unwrap();
    for args in [vec!["drive"], vec!["check"]] {
        let out = Command::new(env!("CARGO_BIN_EXE_ubf")).args(&args).arg(&file).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("robot.ron:1:") && stderr.contains("focal_px"), "{stderr}");
    }
    emulator.kill().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_ubf")).arg("check").arg("robots/config/emulator.ron").output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && stdout.contains("ok, robot file \"powerbot-emulator\""), "{stdout}");
}

#[test]
fn live_state_is_shown_when_asked_and_quiet_when_piped() {
    let (mut emulator, address, _) = emulator();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    let extra = "goal: (x: 20.0, y: 0.0), max_time_s: 2.5,";
    std::fs::write(&file, robot_file(&address, &dir.path().join("log.csv"), extra, GO_ONLY)).unwrap();
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_ubf")).args(args).arg(&file).output().unwrap();
        assert!(out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let shown = run(&["drive", "--status"]);
    assert!(
        shown.lines().any(|l| l.contains(" s old | pose (") && l.ends_with("| winner root/GoTo | hold -")),
        "{shown}"
    );
    let piped = run(&["drive"]);
    assert!(!piped.contains("winner"), "{piped}");
    emulator.kill().unwrap();
}

#[test]
fn a_camera_to_rectify_takes_its_calibration_from_the_camera_info_files() {
    let dir = tempfile::tempdir().unwrap();
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("perception/tests/data");
    for name in ["left.yaml", "right.yaml"] {
        std::fs::copy(data.join(name), dir.path().join(name)).unwrap();
    }
    let file = dir.path().join("robot.ron");
    let write = |rectify: &str| {
        std::fs::write(
            &file,
            format!(
                r#"RobotConfig(name: "r", connection: "tcp://127.0.0.1:1", model: Powerbot, root: Stop(),
                    camera: (source: Directory("frames"), stereo: (mount: (height: 1.3)), rectify: {rectify}))"#
            ),
        )
        .unwrap();
    };
    write(r#"(left: "left.yaml", right: "right.yaml")"#);
    let (config, _) = ubf::drive::DriveConfig::load(&ubf::registry(), &file).unwrap();
    let stereo = config.camera.unwrap().stereo;
    assert_eq!((stereo.width_px, stereo.height_px), (1280, 720));
    assert!((stereo.focal_px - 906.3).abs() < 1e-9 && (stereo.baseline_m - 0.12).abs() < 1e-3);
    assert_eq!(stereo.mount.height, 1.3, "the mount is the file's own");
    write(r#"(left: "right.yaml", right: "left.yaml")"#);
    let err = ubf::drive::DriveConfig::load(&ubf::registry(), &file).unwrap_err().to_string();
    assert!(err.contains("robot.ron: camera.rectify:") && err.contains("to the right"), "{err}");
}

#[test]
fn a_camera_fault_stops_the_drive_and_never_reconnects_the_motors() {
    // A pair that cannot be read mid-drive is a camera fault: the robot is
    // stopped and the drive ends non-zero, naming the camera. It is not a
    // lost link: with `on_link_loss: Reconnect` (the default) the drive
    // used to reconnect, enabling the motors again, every second or two.
    let dir = tempfile::tempdir().unwrap();
    record_frames(dir.path(), 4);
    std::fs::write(dir.path().join("frames/left/000003.png"), b"not a PNG").unwrap();
    let (mut emulator, address, _) = emulator();
    let file = dir.path().join("robot.ron");
    let extra = r#"max_time_s: 8.0,
            camera: (source: Directory("frames"), stereo: (focal_px: 554.3)),"#;
    std::fs::write(&file, config(&address, &dir.path().join("l.csv"), extra)).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).output().unwrap();
    emulator.kill().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("camera:"), "{stderr}");
    assert_eq!(stderr.matches("connected to").count(), 1, "{stderr}");
}

/// `ubf drive FILE` on the emulator, with its robot file's `extra` fields,
/// run by `sh -c` after `prelude` (a ulimit, say): its output, and how
/// many times it connected.
fn drive_through_shell(
    dir: &std::path::Path,
    address: &str,
    extra: &str,
    prelude: &str,
) -> (std::process::Output, usize) {
    let file = dir.join("robot.ron");
    std::fs::write(&file, config(address, &dir.join("l.csv"), extra)).unwrap();
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("{prelude} exec \"$0\" drive \"$1\""))
        .arg(env!("CARGO_BIN_EXE_ubf"))
        .arg(&file)
        .current_dir(dir)
        .output()
        .unwrap();
    let connected = String::from_utf8_lossy(&out.stderr).matches("connected to").count();
    (out, connected)
}

#[test]
fn a_camera_thread_that_dies_stops_the_drive() {
    // A pair listed at 1e30 s could never be waited for: the camera's
    // thread used to panic on it, unnoticed, and the drive ran on blind
    // and exited 0.
    let dir = tempfile::tempdir().unwrap();
    record_frames(dir.path(), 3);
    let index = dir.path().join("frames/frames.csv");
    let text = std::fs::read_to_string(&index).unwrap();
    let last = text.lines().last().unwrap();
    let (_, names) = last.split_once(',').unwrap();
    std::fs::write(&index, text.replace(last, &format!("1e30,{names}"))).unwrap();
    let (mut emulator, address, _) = emulator();
    let extra = r#"max_time_s: 8.0, camera: (source: Directory("frames"), stereo: (focal_px: 554.3)),"#;
    let (out, connected) = drive_through_shell(dir.path(), &address, extra, "");
    emulator.kill().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("camera:") && stderr.contains("1000000000000000000000000000000"), "{stderr}");
    assert_eq!(connected, 1, "{stderr}");
}

#[test]
fn a_log_that_cannot_be_written_stops_the_drive() {
    // Files may grow to 24 kB (the disk is full, in effect): the logs
    // fill that within seconds, and the drive must not run on unrecorded.
    let dir = tempfile::tempdir().unwrap();
    let (mut emulator, address, mut out) = emulator();
    let (drive, connected) =
        drive_through_shell(dir.path(), &address, "max_time_s: 60.0,", "trap '' XFSZ; ulimit -f 48;");
    let line = report_line(&mut out);
    emulator.kill().unwrap();
    let stderr = String::from_utf8_lossy(&drive.stderr);
    assert_eq!(drive.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("log"), "the failed log is named: {stderr}");
    assert_eq!(connected, 1, "{stderr}");
    assert!(line.contains("closed true"), "the robot was stopped and closed: {line}");
}

/// `ubf drive` of an emulated robot with a camera of recorded frames in
/// `dir` on the head at `head`, its stderr piped; and the robot.
fn drive_with_head(dir: &std::path::Path, head: &str, extra: &str) -> (std::process::Child, Killed) {
    record_frames(dir, 2);
    let (emulator, address, _) = emulator();
    let extra = format!(
        r#"{extra}
            camera: (source: Directory("frames"), stereo: (focal_px: 554.3), pan_tilt: (connection: "{head}")),"#
    );
    let file = dir.join("robot.ron");
    std::fs::write(&file, config(&address, &dir.join("l.csv"), &extra)).unwrap();
    let drive =
        Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).stderr(Stdio::piped()).spawn();
    (drive.unwrap(), emulator)
}

#[test]
fn a_pan_tilt_head_that_goes_silent_stops_the_drive_without_reconnecting() {
    let dir = tempfile::tempdir().unwrap();
    let (mut head, head_address, _) = ptu_emulator();
    let (mut drive, mut emulator) = drive_with_head(dir.path(), &head_address, "max_time_s: 20.0,");
    std::thread::sleep(Duration::from_secs(3));
    head.kill().unwrap();
    let status = wait_for(&mut drive, 10.0).expect("the drive ends once the head is gone");
    emulator.kill().unwrap();
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut drive.stderr.take().unwrap(), &mut stderr).unwrap();
    assert_eq!(status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("pan-tilt unit on"), "{stderr}");
    // A head's fault is not the robot's lost link: nothing reconnects.
    assert!(!stderr.contains("link lost"), "{stderr}");
    assert_eq!(stderr.matches("connected to").count(), 1, "{stderr}");
    // Until then the log said where the head read.
    let log = std::fs::read_to_string(dir.path().join("l.csv")).unwrap();
    let header: Vec<&str> = log.lines().next().unwrap().split(',').collect();
    let pan = header.iter().position(|column| *column == "camera_pan").expect("a camera_pan column");
    let read = |row: &str| row.split(',').nth(pan).is_some_and(|v| v.parse::<f64>().is_ok());
    assert!(log.lines().skip(1).any(read), "{log}");
}

/// A TCP address in front of `upstream` whose answers each come `delay`
/// late, for one client; and word of the first answer passed on.
fn slow_answers(upstream: &str, delay: Duration) -> (String, std::sync::mpsc::Receiver<()>) {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let address = format!("tcp://{}", listener.local_addr().unwrap());
    let upstream = upstream.trim_start_matches("tcp://").to_owned();
    let (answered, first_answer) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let (client, _) = listener.accept().unwrap();
        let head = std::net::TcpStream::connect(upstream).unwrap();
        let (mut asked, mut to_head) = (client.try_clone().unwrap(), head.try_clone().unwrap());
        std::thread::spawn(move || std::io::copy(&mut asked, &mut to_head));
        let (mut answers, mut to_client, mut chunk) = (head, client, [0u8; 256]);
        use std::io::{Read, Write};
        while let Ok(n @ 1..) = answers.read(&mut chunk) {
            std::thread::sleep(delay);
            if to_client.write_all(&chunk[..n]).is_err() {
                return;
            }
            let _ = answered.send(());
        }
    });
    (address, first_answer)
}

#[test]
fn a_signal_while_the_head_connects_ends_the_drive_before_the_motors_go_on() {
    let dir = tempfile::tempdir().unwrap();
    let (_head, head_address, _) = ptu_emulator();
    // The handshake's fourteen answers take 2.1 s: the signal comes after
    // the first.
    let (slow_head, first_answer) = slow_answers(&head_address, Duration::from_millis(150));
    let (mut drive, mut emulator) = drive_with_head(dir.path(), &slow_head, "");
    first_answer.recv_timeout(Duration::from_secs(30)).expect("the head was asked something");
    assert!(Command::new("kill").args(["-TERM", &drive.id().to_string()]).status().unwrap().success());
    let status = wait_for(&mut drive, 10.0).expect("the drive ends");
    emulator.kill().unwrap();
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut drive.stderr.take().unwrap(), &mut stderr).unwrap();
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(
        !stderr.contains("connected to"),
        "the robot was connected (and its motors enabled) after the signal: {stderr}"
    );
}

#[test]
fn impossible_robot_files_are_refused_with_their_place() {
    // Each of these used to pass `ubf check` and then panic, hang, or
    // switch a safeguard off on the robot.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    let go =
        |speed: &str| format!("Composite(arbiter: CommandFusion, children: [(behavior: GoTo(cruise_speed: {speed}))])");
    let frames = r#"camera: (source: Directory("."), "#;
    let cases: [(&str, String, &str); 15] = [
        ("period_s: 1e20,", go("0.3"), "from 0.01 to 1 s"),
        ("period_s: 65535.0,", go("0.3"), "from 0.01 to 1 s"),
        ("safety: (stale_after_s: 1e300),", go("0.3"), "from 0.001 to 10 s"),
        ("safety: (link_lost_after_s: 1e300),", go("0.3"), "from 0.001 to 60 s"),
        ("safety: (stale_after_s: 2.0, link_lost_after_s: 1.3),", go("0.3"), "must not exceed link_lost_after_s"),
        ("", go("600.0"), "at most 10 m/s"),
        ("goal: (x: 8e9, y: 0.0),", go("0.3"), "from -10000 to 10000 m"),
        (
            &format!(r#"{frames}pan_tilt: (connection: "/dev/ttyUSB1", tilt_deg: 7200.0)),"#),
            go("0.3"),
            "from -90 to 90°",
        ),
        (
            &format!(r#"{frames}pan_tilt: (connection: "/dev/ttyUSB1", tilt_deg: 1e999)),"#),
            go("0.3"),
            "from -90 to 90°",
        ),
        (&format!("{frames}stereo: (width_px: 16384, height_px: 16384)),"), go("0.3"), "8 to 8192"),
        ("accelerations: (translation: 1e9, rotation_deg: 100.0),", go("0.3"), "at most 10 m/s²"),
        ("baud: 12345,", go("0.3"), "not a serial baud rate"),
        ("max_time_s: 1e30,", go("0.3"), "at most 1e7 s"),
        ("max_velocity: 600.0,", go("0.3"), "at most 10 m/s"),
        // A correction of 45° or more would take every wall for drift.
        ("wall_compass: (max_correction_deg: 60.0),", go("0.3"), "from 0.01 to 44°"),
    ];
    let check = |body: &str| {
        std::fs::write(&file, body).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["check", file.to_str().unwrap()]).output().unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let place = regex_lite_place(file.to_str().unwrap());
    for (extra, root, rule) in &cases {
        let (code, stderr) = check(&robot_file("/dev/ttyUSB0", &dir.path().join("l.csv"), extra, root));
        assert_eq!(code, Some(2), "{extra} {root}: {stderr}");
        assert!(stderr.contains(rule), "{extra} {root}: the rule is given: {stderr}");
        assert!(place(&stderr), "{extra} {root}: the place is given as file:line:col: {stderr}");
    }
    // A connection nothing can open, and a camera directory that is not there.
    let text = robot_file("htp://x", &dir.path().join("l.csv"), "", &go("0.3"));
    let (code, stderr) = check(&text);
    assert!(code == Some(2) && stderr.contains("is not a connection") && place(&stderr), "{stderr}");
    let text =
        robot_file("/dev/ttyUSB0", &dir.path().join("l.csv"), r#"camera: (source: Directory("nowhere")),"#, &go("0.3"));
    let (code, stderr) = check(&text);
    assert!(code == Some(2) && stderr.contains("nowhere"), "{stderr}");
    let sweep = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["sweep", "scenarios/goto-open-floor.ron", "--seeds", "1..2", "--jobs", "100000"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(sweep.status.code(), Some(2), "{}", String::from_utf8_lossy(&sweep.stderr));
}

/// Whether an error names `file` with a line and column (`file:12:5`).
fn regex_lite_place(file: &str) -> impl Fn(&str) -> bool + '_ {
    move |stderr: &str| {
        stderr.split(file).skip(1).any(|after| {
            let mut parts = after.splitn(3, ':');
            parts.next() == Some("")
                && parts.next().is_some_and(|l| !l.is_empty() && l.chars().all(|c| c.is_ascii_digit()))
                && parts.next().is_some_and(|rest| rest.chars().next().is_some_and(|c| c.is_ascii_digit()))
        })
    }
}

#[test]
fn the_pose_survives_three_link_cuts_while_moving() {
    // Three sessions lose their link for 1.5 s at speed, the robot driving
    // on and then braking once STOP gets through; all of it reaches the
    // driver only while it waits for standstill, and belongs in the pose
    // the next session starts from. Each emulated session restarts its
    // odometry at zero, as AMRISim does.
    let (mut emulator, address, mut out) = emulator_with(&["--listen", "127.0.0.1:0", "--cut", "2:1.5", "--cuts", "3"]);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    let root = "Composite(arbiter: CommandFusion, children: [
        (behavior: Stop(), weight: 1.0), (behavior: GoTo(cruise_speed: 0.5))])";
    let extra = "until_goal: true, max_time_s: 60.0, goal: (x: 6.0, y: 0.0, tolerance: 0.05),";
    std::fs::write(&file, robot_file(&address, &dir.path().join("log.csv"), extra, root)).unwrap();
    let drive = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).output().unwrap();
    let stderr = String::from_utf8_lossy(&drive.stderr);
    assert!(drive.status.success(), "{stderr}");
    let sessions = stderr.matches("connected to").count();
    assert_eq!(sessions, 4, "three cut sessions and the one that arrives: {stderr}");
    // Each session's travel in its own frame; the drive heads along x.
    let (mut x, mut y) = (0.0, 0.0);
    for _ in 0..sessions {
        let line = report_line(&mut out);
        let pose = line.split("pose (").nth(1).unwrap().split(')').next().unwrap();
        let (dx, dy) = pose.split_once(", ").unwrap();
        x += dx.parse::<f64>().unwrap();
        y += dy.parse::<f64>().unwrap();
    }
    emulator.kill().unwrap();
    let rest = stderr.split("came to rest at (").nth(1).expect("the final pose is said").split(')').next().unwrap();
    let (bx, by) = rest.split_once(", ").unwrap();
    let (bx, by): (f64, f64) = (bx.parse().unwrap(), by.parse().unwrap());
    let miss = (bx - x).hypot(by - y);
    eprintln!("after three cuts the pose is {miss:.4} m off");
    assert!(miss <= 0.02, "believes ({bx:.3}, {by:.3}), is at ({x:.3}, {y:.3}): {miss:.3} m off; {stderr}");
}

/// `scripts/mcap-check.py ARGS`: the MCAP project's own Python reader on a
/// log; its output, or a panic with it if the check failed.
fn mcap_check(args: &[&std::ffi::OsStr]) -> String {
    let check = Command::new("python3")
        .arg(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/mcap-check.py"))
        .args(args)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&check.stdout).into_owned();
    assert!(check.status.success(), "{said}{}", String::from_utf8_lossy(&check.stderr));
    said
}

#[test]
fn a_drive_that_ends_cleanly_leaves_its_report_and_its_start_in_utc() {
    let extra = "until_goal: true, goal: (x: 1.0, y: 0.0), max_time_s: 30.0,";
    let (drive, _, dir) = drive_on(&["--listen", "127.0.0.1:0"], extra, GO_ONLY);
    assert!(drive.status.success(), "{}", String::from_utf8_lossy(&drive.stderr));
    let mcap = dir.path().join("log.mcap");
    let said = mcap_check(&[mcap.as_os_str()]);
    assert!(said.contains("the run ended: goal_reached") && said.contains("started at 20"), "{said}");
    let replay = Command::new(env!("CARGO_BIN_EXE_ubf")).arg("replay").arg(&mcap).output().unwrap();
    let shown = String::from_utf8_lossy(&replay.stdout);
    assert!(shown.contains("ended           goal_reached"), "{shown}{}", String::from_utf8_lossy(&replay.stderr));
}

#[test]
fn a_drive_log_stops_taking_images_at_its_cap() {
    let dir = tempfile::tempdir().unwrap();
    record_frames(dir.path(), 12);
    let (mut emulator, address, _) = emulator();
    let extra = r#"max_time_s: 8.0, log_images: true, log_max_mb: 1.0,
        camera: (source: Directory("frames"), stereo: (focal_px: 554.3)),"#;
    let (out, _) = drive_through_shell(dir.path(), &address, extra, "");
    emulator.kill().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("it takes no more images"), "{stderr}");
    let size = std::fs::metadata(dir.path().join("l.mcap")).unwrap().len();
    assert!(size < 2_000_000, "the log holds {size} bytes");
    let said = mcap_check(&[dir.path().join("l.mcap").as_os_str()]);
    assert!(said.contains("the run ended: time_limit"), "{said}");
}

#[test]
fn a_drive_tells_systemd_it_is_ready_alive_and_stopping() {
    // systemd's side of Type=notify: a datagram socket named by
    // NOTIFY_SOCKET, with a 0.4 s watchdog.
    let dir = tempfile::tempdir().unwrap();
    let socket_path = dir.path().join("notify");
    let socket = std::os::unix::net::UnixDatagram::bind(&socket_path).unwrap();
    socket.set_read_timeout(Some(Duration::from_millis(100))).unwrap();
    // Read as systemd does, while the drive runs: its queue holds ten.
    let listener = std::thread::spawn(move || {
        let (mut said, mut buffer) = (Vec::new(), [0u8; 512]);
        let deadline = std::time::Instant::now() + Duration::from_secs(30);
        while !said.iter().any(|s: &String| s.contains("STOPPING=1")) && std::time::Instant::now() < deadline {
            if let Ok(n) = socket.recv(&mut buffer) {
                said.push(String::from_utf8_lossy(&buffer[..n]).into_owned());
            }
        }
        said
    });
    let (mut emulator, address, _) = emulator();
    let file = dir.path().join("robot.ron");
    std::fs::write(&file, robot_file(&address, &dir.path().join("l.csv"), "max_time_s: 3.0,", GO_ONLY)).unwrap();
    // systemd names the process the watchdog is for: the shell's pid,
    // which `exec` hands on to the drive.
    let out = Command::new("sh")
        .arg("-c")
        .arg("WATCHDOG_PID=$$ exec \"$0\" drive \"$1\"")
        .arg(env!("CARGO_BIN_EXE_ubf"))
        .arg(&file)
        .env("NOTIFY_SOCKET", &socket_path)
        .env("WATCHDOG_USEC", "400000")
        .output()
        .unwrap();
    emulator.kill().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let said = listener.join().unwrap();
    let position = |what: &str| said.iter().position(|s| s.lines().any(|l| l == what));
    let ready = position("READY=1").expect("READY=1 was sent");
    let pets = said.iter().filter(|s| s.lines().any(|l| l == "WATCHDOG=1")).count();
    // Three seconds of ticks at two pets per 0.4 s: about fifteen.
    assert!(pets >= 8, "{pets} watchdog pets: {said:?}");
    assert!(position("STOPPING=1").is_some_and(|stopping| stopping > ready), "{said:?}");
}

#[test]
fn a_restarted_drive_resumes_in_the_saved_world_frame() {
    // A first drive reaches its goal 1 m ahead and keeps its pose; the
    // second, as a service restarted would be, finds the pose file and
    // knows it is there already: its goal is not re-based to where the
    // robot stands.
    let dir = tempfile::tempdir().unwrap();
    let pose_file = dir.path().join("pose.ron");
    let extra =
        format!("until_goal: true, goal: (x: 1.0, y: 0.0), max_time_s: 30.0, pose_file: \"{}\",", pose_file.display());
    let (first, line, _) = drive_on(&["--listen", "127.0.0.1:0"], &extra, GO_ONLY);
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    let travelled: f64 = line.split("pose (").nth(1).unwrap().split(',').next().unwrap().parse().unwrap();
    assert!(travelled > 0.75, "the first drive went to its goal (within its 0.2 m): {line}");
    assert!(pose_file.exists());
    let (second, line, _) = drive_on(&["--listen", "127.0.0.1:0"], &extra, GO_ONLY);
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert!(second.status.success() && stderr.contains("resuming in the world frame of"), "{stderr}");
    let travelled: f64 = line.split("pose (").nth(1).unwrap().split(',').next().unwrap().parse().unwrap();
    assert!(travelled.abs() < 0.05, "the second drive went {travelled} m toward a goal it stood at: {line}");
}

#[test]
fn a_drive_never_waits_for_systemd_to_read() {
    // A notification socket nobody reads fills after ten datagrams; the
    // tick loop must go on (a blocking send hung it after two seconds).
    let dir = tempfile::tempdir().unwrap();
    let socket_path = dir.path().join("notify");
    let _unread = std::os::unix::net::UnixDatagram::bind(&socket_path).unwrap();
    let (mut emulator, address, _) = emulator();
    let file = dir.path().join("robot.ron");
    std::fs::write(&file, robot_file(&address, &dir.path().join("l.csv"), "max_time_s: 3.0,", GO_ONLY)).unwrap();
    let mut drive = Command::new("sh")
        .arg("-c")
        .arg("WATCHDOG_PID=$$ exec \"$0\" drive \"$1\" 2>/dev/null")
        .arg(env!("CARGO_BIN_EXE_ubf"))
        .arg(&file)
        .env("NOTIFY_SOCKET", &socket_path)
        .env("WATCHDOG_USEC", "100000")
        .spawn()
        .unwrap();
    let status = wait_for(&mut drive, 20.0);
    if status.is_none() {
        let _ = drive.kill();
    }
    emulator.kill().unwrap();
    assert!(status.is_some_and(|s| s.success()), "{status:?}");
}
