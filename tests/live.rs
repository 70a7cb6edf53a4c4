//! `ubf run --live` and `ubf drive --live` watched by the official Foxglove
//! client library (npm `@foxglove/ws-protocol`, through
//! `scripts/foxglove-live-check.sh`), not by our own code: the topics it
//! receives, their schemas, and that a viewer who stops reading slows
//! nothing.

mod common;

use common::{emulator, wait_for, Killed};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::process::{ChildStderr, Command, Stdio};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Starts `ubf ARGS` with its stderr piped, and reads stderr until the
/// live view says where it is: its `ws://` address, and the rest of
/// stderr.
fn start_live(args: &[&str]) -> (Killed, String, BufReader<ChildStderr>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(args)
        .env_remove("RUST_LOG")
        .current_dir(root())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let child = Killed(child);
    let mut line = String::new();
    loop {
        line.clear();
        assert!(err.read_line(&mut line).unwrap() > 0, "ubf ended without serving the live view");
        if let Some(rest) = line.strip_prefix("live view on ") {
            let url = rest.split_whitespace().next().unwrap().trim_end_matches(',').to_owned();
            return (child, url, err);
        }
    }
}

/// What the official client saw in `seconds` at `url`.
fn watch(url: &str, seconds: f64, stall: bool) -> Value {
    let mut command = Command::new(root().join("scripts/foxglove-live-check.sh"));
    command.args([url, &seconds.to_string()]);
    if stall {
        command.arg("--stall");
    }
    let output = command.output().expect("scripts/foxglove-live-check.sh needs Node.js and npm");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    serde_json::from_slice(&output.stdout).unwrap()
}

/// The advertised channel of `topic`.
fn channel<'a>(seen: &'a Value, topic: &str) -> &'a Value {
    let channels = seen["channels"].as_array().unwrap();
    channels.iter().find(|c| c["topic"] == topic).unwrap_or_else(|| panic!("no {topic} advertised: {seen}"))
}

/// What a viewer needs of every live view: the robot's pose, the scene and
/// the tree, each with the schema Foxglove's panels know it by, and
/// messages that follow it.
fn assert_shows_pose_scene_and_tree(seen: &Value, pose_topic: &str) {
    assert_eq!(seen["subprotocol"], "foxglove.sdk.v1", "{seen}");
    assert!(seen["server"].as_str().unwrap().starts_with("ubf "), "{seen}");
    assert_eq!(seen["errors"], serde_json::json!([]), "{seen}");
    for (topic, schema) in
        [(pose_topic, "foxglove.PoseInFrame"), ("/scene", "foxglove.SceneUpdate"), ("/tree", "ubf.Tick")]
    {
        let advertised = channel(seen, topic);
        assert_eq!(advertised["encoding"], "json", "{advertised}");
        assert_eq!(advertised["schemaName"], schema, "{advertised}");
        assert_eq!(advertised["schemaEncoding"], "jsonschema", "{advertised}");
        assert_eq!(advertised["schema"]["type"], "object", "{advertised}");
        assert!(seen["received"][topic].as_u64().unwrap_or(0) > 0, "no {topic} received: {seen}");
    }
    let pose = &seen["first"][pose_topic]["pose"];
    assert!(pose["position"]["x"].is_number() && pose["orientation"]["w"].is_number(), "{pose}");
    let tree = &seen["first"]["/tree"];
    let nodes = tree["nodes"].as_array().unwrap();
    assert!(!nodes.is_empty(), "{tree}");
    assert!(nodes.iter().all(|n| n["path"].is_string() && n["vote"].is_number() && n["won"].is_boolean()), "{tree}");
    assert!(tree["winner"].is_string(), "{tree}");
}

#[test]
fn a_foxglove_client_watches_a_run_live() {
    let args = ["run", "scenarios/corridor-box.ron", "--live", "127.0.0.1:0", "--speed", "4"];
    let (mut run, url, _err) = start_live(&args);
    let seen = watch(&url, 2.0, false);
    assert_shows_pose_scene_and_tree(&seen, "/pose/true");
    // The walls, drawn as lines.
    let scene = &seen["first"]["/scene"]["entities"][0];
    assert_eq!(scene["id"], "world", "{scene}");
    assert!(scene["lines"][0]["points"].as_array().unwrap().len() >= 2, "{scene}");
    assert_eq!(seen["first"]["/run"]["scenario"], "corridor-box", "{seen}");
    assert!(seen["received"]["/ranges"].as_u64().unwrap_or(0) > 0, "{seen}");
    assert!(seen["received"]["/pose/odometry"].as_u64().unwrap_or(0) > 0, "{seen}");
    let status = wait_for(&mut run, 120.0).expect("the run ends");
    assert!(status.success(), "{status}");
}

#[test]
fn a_viewer_is_shown_at_most_twenty_ticks_a_second() {
    // At ten times real time the run ticks 100 times a second; a viewer is
    // shown one tick in each `SHOW_EVERY` (50 ms), so each tick's topics
    // come at most 20 times a second. (The log keeps every tick:
    // tests/mcap.rs.)
    let args = ["run", "scenarios/corridor-box.ron", "--live", "127.0.0.1:0", "--speed", "10"];
    let (mut run, url, _err) = start_live(&args);
    let seconds = 2.0;
    let seen = watch(&url, seconds, false);
    // One more for the tick shown first, and a few for ticks that added a
    // collision, which are shown whatever the time.
    let most = (seconds / ubf::live::SHOW_EVERY.as_secs_f64()).round() as u64 + 5;
    for topic in ["/pose/true", "/pose/odometry", "/tree", "/ranges"] {
        let received = seen["received"][topic].as_u64().unwrap_or(0);
        assert!(received > 0 && received <= most, "{received} on {topic} in {seconds} s, at most {most}: {seen}");
    }
    let status = wait_for(&mut run, 120.0).expect("the run ends");
    assert!(status.success(), "{status}");
}

#[test]
fn a_viewer_that_stops_reading_slows_nothing() {
    // A camera that renders pairs, watched at ten times real time by a
    // viewer that reads one message and then nothing for ten minutes: its
    // queue fills, and the server drops its messages instead of waiting
    // for it. A run that waited for it could end only once it left, so
    // the run must end while the viewer is still there, stalled. (No
    // bound on the run's time: on a busy machine it is slow anyway.)
    let paced = ["run", "scenarios/rendered-corridor.ron", "--live", "127.0.0.1:0", "--speed", "10", "--json"];
    let (mut run, url, mut err) = start_live(&paced);
    let mut viewer = Command::new(root().join("scripts/foxglove-live-check.sh"));
    viewer.args([&url, "600", "--stall"]).stdout(Stdio::null()).stderr(Stdio::piped());
    let mut viewer = Killed(viewer.spawn().unwrap());
    let viewer_err = BufReader::new(viewer.0.stderr.take().unwrap());
    let said: Vec<String> = viewer_err.lines().map_while(Result::ok).take_while(|l| l != "stalled").collect();
    assert!(viewer.0.try_wait().unwrap().is_none(), "the viewer ended before it stalled: {said:?}");
    let status = wait_for(&mut run, 300.0).expect("the run ends while a viewer stalls");
    let mut rest = String::new();
    err.read_to_string(&mut rest).unwrap();
    assert!(status.success(), "{status}; stderr: {rest}");
    assert!(viewer.0.try_wait().unwrap().is_none(), "the viewer left before the run ended; stderr: {rest}");
    let mut stdout = String::new();
    run.0.stdout.take().unwrap().read_to_string(&mut stdout).unwrap();
    let report: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(report["end"], "goal_reached", "{report}");
}

#[test]
fn a_foxglove_client_watches_a_drive_live() {
    let (_emulator, address, _emulator_out) = emulator();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    let robot = format!(
        r#"RobotConfig(
            name: "live",
            connection: "{address}",
            model: Powerbot,
            log: "{}",
            goal: (x: 2.0, y: 0.0, tolerance: 0.2),
            root: Composite(arbiter: CommandFusion, children: [
                (behavior: Stop(), weight: 1.0),
                (behavior: GoTo(cruise_speed: 0.4)),
            ]),
        )"#,
        dir.path().join("log.csv").display()
    );
    std::fs::write(&file, robot).unwrap();
    let (mut drive, url, _err) =
        start_live(&["drive", file.to_str().unwrap(), "--live", "127.0.0.1:0", "--until-goal"]);
    let seen = watch(&url, 2.0, false);
    assert_shows_pose_scene_and_tree(&seen, "/pose/odometry");
    assert_eq!(seen["first"]["/run"]["scenario"], "drive (Powerbot)", "{seen}");
    assert_eq!(seen["first"]["/goal"]["pose"]["position"]["x"], 2.0, "{seen}");
    let status = wait_for(&mut drive, 60.0).expect("the drive ends at its goal");
    assert!(status.success(), "{status}");
}

/// Sends `count` WebSocket text messages of `text` to the live view at
/// `url` (`ws://host:port`) as fast as the socket takes them, after the
/// Foxglove handshake: a client that speaks the protocol badly.
fn send_raw_messages(url: &str, text: &str, count: usize) {
    use std::io::Write;
    let address = url.trim_start_matches("ws://");
    let mut socket = std::net::TcpStream::connect(address).unwrap();
    let upgrade = format!(
        "GET / HTTP/1.1\r\nHost: {address}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\
         Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n"
    );
    socket.write_all(upgrade.as_bytes()).unwrap();
    let mut reply = BufReader::new(socket.try_clone().unwrap());
    let mut status = String::new();
    reply.read_line(&mut status).unwrap();
    assert!(status.contains(" 101 "), "the view refused the handshake: {status}");
    // A text frame, final, masked with a zero mask (a client's frames must
    // be masked), its length in one byte.
    assert!(text.len() < 126);
    let mut frame = vec![0x81, 0x80 | text.len() as u8, 0, 0, 0, 0];
    frame.extend_from_slice(text.as_bytes());
    for _ in 0..count {
        if socket.write_all(&frame).is_err() {
            break; // dropped by the server: what it may do
        }
    }
}

#[test]
fn a_client_sending_garbage_cannot_flood_the_log() {
    // The server library says ERROR for every malformed message it reads:
    // 160 lines in this test's second before the budget, 13 667 in five
    // seconds from a client that kept sending.
    let (run, url, mut err) = start_live(&["run", "scenarios/goto-open-floor.ron", "--live", "127.0.0.1:0"]);
    let started = std::time::Instant::now();
    send_raw_messages(&url, r#"{"op":"no such op"}"#, 2_000);
    std::thread::sleep(std::time::Duration::from_millis(500));
    let seconds = started.elapsed().as_secs() + 1;
    drop(run);
    let mut rest = String::new();
    err.read_to_string(&mut rest).unwrap();
    let lines = rest.lines().filter(|l| l.contains("foxglove")).count() as u64;
    assert!(lines > 0, "the client's messages were not seen: {rest}");
    assert!(lines <= 10 * seconds, "{lines} lines in {seconds} s: {rest}");
}
