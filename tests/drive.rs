//! `ubf drive` against `ubf emulate-powerbot`, both as real processes over
//! TCP loopback: drive to a goal, stop on SIGTERM, close the session, keep
//! the log.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

fn emulator() -> (Child, String, BufReader<std::process::ChildStdout>) {
    emulator_with(&["--listen", "127.0.0.1:0"])
}

/// `ubf emulate-powerbot ARGS`, with the address it serves on.
fn emulator_with(args: &[&str]) -> (Child, String, BufReader<std::process::ChildStdout>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .arg("emulate-powerbot")
        .args(args)
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    assert!(line.starts_with("emulating a Powerbot on "), "{line}");
    let address = line.trim().rsplit(' ').next().unwrap().to_owned();
    (child, address, out)
}

/// Waits up to `seconds` for `child` to exit.
fn wait_for(child: &mut Child, seconds: f64) -> Option<std::process::ExitStatus> {
    let deadline = std::time::Instant::now() + Duration::from_secs_f64(seconds);
    while std::time::Instant::now() < deadline {
        if let Some(status) = child.try_wait().unwrap() {
            return Some(status);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    None
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
    assert!(drive.wait().unwrap().success(), "ubf drive exits cleanly on SIGTERM");

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
fn bad_configurations_and_unreachable_robots_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    std::fs::write(&file, config("tcp://127.0.0.1:9", &dir.path().join("l.csv"), "speed: 2,")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("speed"));
    // Nothing listens on port 9: with on_link_loss Exit, a clean error.
    std::fs::write(&file, config("tcp://127.0.0.1:9", &dir.path().join("l.csv"), "on_link_loss: Exit,")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_ubf")).args(["drive", file.to_str().unwrap()]).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("127.0.0.1:9"));
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
    assert!(status.success(), "{stderr}");
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

#[test]
fn a_dry_run_with_a_camera_shows_live_landmark_counts() {
    // Recorded rendered pairs stand in for the cameras: replayed at their
    // own pace (2 Hz) through the pipeline and egomotion while the robot
    // stays still with its motors off.
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    let record = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["frames", "scenarios/rendered-corridor.ron", "--max-frames", "8", "--out"])
        .arg(&frames)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(record.status.success(), "{}", String::from_utf8_lossy(&record.stderr));
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
