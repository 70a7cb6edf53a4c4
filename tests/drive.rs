//! `ubf drive` against `ubf emulate-powerbot`, both as real processes over
//! TCP loopback: drive to a goal, stop on SIGTERM, close the session, keep
//! the log.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

fn emulator() -> (Child, String, BufReader<std::process::ChildStdout>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["emulate-powerbot", "--listen", "127.0.0.1:0"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    let address = line.trim().rsplit(' ').next().unwrap().to_owned();
    assert!(address.starts_with("tcp://127.0.0.1:"), "{line}");
    (child, address, out)
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
