//! `ubf drive` against a ROS 2 robot nobody here wrote: Eclipse Cyclone
//! DDS (PyPI `cyclonedds`, installed by `scripts/ros2/robot.py` into its
//! own environment) plays a differential-drive base that takes
//! `geometry_msgs/msg/Twist` on `/cmd_vel` and publishes
//! `nav_msgs/msg/Odometry` on `/odom`. Each test runs in a private network
//! namespace (`scripts/ros2/netns.sh`), so its DDS traffic neither needs
//! nor disturbs a network, and the tests cannot hear each other.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The robot file of the ROS 2 issue, unchanged but for `extra` settings.
fn robot_file(dir: &Path, goal_x: f64, extra: &str) -> PathBuf {
    let path = dir.join("robot.ron");
    let text = format!(
        r#"RobotConfig(
    name: "ros2-robot",
    connection: "ros2",
    model: Powerbot,
    period_s: 0.1,
    log: "drive-log.csv",
    on_link_loss: Exit,
    goal: (x: {goal_x}, y: 0.0, tolerance: 0.2),
    {extra}
    root: Composite(arbiter: CommandFusion, children: [(behavior: Stop(), weight: 1.0), (behavior: GoTo(cruise_speed: 0.3))]),
)"#
    );
    std::fs::write(&path, text).unwrap();
    path
}

/// What a test session left: ubf's exit and stderr, what the robot
/// recorded (every twist it received, then its summary), and what the
/// listener heard, if one listened.
struct Session {
    ubf: Output,
    twists: Vec<Value>,
    summary: Value,
    heard: Option<Value>,
}

/// The robot's Python environment (Cyclone DDS from PyPI) is made outside
/// the namespace, which has no network.
fn install_cyclone() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let setup = Command::new("python3").arg(root.join("scripts/ros2/robot.py")).arg("--help").output().unwrap();
    assert!(setup.status.success(), "installing cyclonedds: {}", String::from_utf8_lossy(&setup.stderr));
}

/// Runs `script` in a private network namespace with the environment
/// `vars`; `None` (said on stderr) where namespaces are not available.
///
/// The script may call `await_line FILE PID TEXT`: it waits (a minute at
/// most) until FILE holds TEXT, and fails early if process PID has ended.
/// A busy machine can take seconds to start a Python process, so whatever
/// must be heard or driven waits for its "ready" line rather than a guess.
fn in_namespace(script: &str, vars: &[(&str, &std::ffi::OsStr)]) -> Option<Output> {
    const AWAIT_LINE: &str = r#"await_line() {
    for _ in $(seq 600); do grep -qsF "$3" "$1" && return 0; kill -0 "$2" 2>/dev/null || break; sleep 0.1; done
    grep -qsF "$3" "$1"
}
"#;
    let root = env!("CARGO_MANIFEST_DIR");
    let out = Command::new(Path::new(root).join("scripts/ros2/netns.sh"))
        .args(["bash", "-c", &format!("{AWAIT_LINE}{script}")])
        .env("ROOT", root)
        .env("UBF", env!("CARGO_BIN_EXE_ubf"))
        .envs(vars.iter().copied())
        .env_remove("ROS_DOMAIN_ID")
        .output()
        .unwrap();
    if out.status.code() == Some(77) {
        eprintln!("skipped: {}", String::from_utf8_lossy(&out.stderr));
        return None;
    }
    Some(out)
}

/// Runs the Cyclone robot with `robot_args` and `ubf drive FILE --until-goal`
/// beside it, in a private network namespace; `None` where namespaces are
/// not available (the test is then skipped, said on stderr). With
/// `interrupt`, ubf is interrupted by that shell (`sleep 3; kill -TERM
/// $ubf`) instead.
fn drive_beside_robot(dir: &Path, robot_args: &str, file: &Path, interrupt: Option<&str>) -> Option<Session> {
    drive_and_listen(dir, robot_args, file, interrupt, None)
}

/// The shell that starts a Cyclone listener (`listen.py` with the arguments
/// `topics`) writing to `$HEARD`, as `$listener`, and waits until it has
/// subscribed (exit 4 if it never does).
fn listener_script(topics: &str) -> String {
    format!(
        r#"python3 "$ROOT/scripts/ros2/listen.py" {topics} >"$HEARD" 2>"$LISTEN_ERR" & listener=$!
await_line "$LISTEN_ERR" $listener "listen ready" || {{ cat "$LISTEN_ERR" >&2; exit 4; }}"#
    )
}

/// [`drive_beside_robot`] with a Cyclone listener (`listen.py` with the
/// arguments `listen`) hearing the drive.
fn drive_and_listen(
    dir: &Path,
    robot_args: &str,
    file: &Path,
    interrupt: Option<&str>,
    listen: Option<&str>,
) -> Option<Session> {
    install_cyclone();
    let record = dir.join("robot.jsonl");
    let robot_out = dir.join("robot.out");
    let ubf_err = dir.join("ubf.err");
    let drive = match interrupt {
        None => "timeout 60 \"$UBF\" drive \"$FILE\" --until-goal 2>\"$UBF_ERR\"; code=$?".to_owned(),
        Some(interrupt) => {
            format!("\"$UBF\" drive \"$FILE\" --until-goal 2>\"$UBF_ERR\" & ubf=$!; {interrupt}; wait $ubf; code=$?")
        }
    };
    let (heard_path, listen_err) = (dir.join("heard.json"), dir.join("listen.err"));
    let listener = match listen {
        Some(topics) => listener_script(topics),
        None => "listener=".to_owned(),
    };
    let script = format!(
        r#"{listener}
python3 "$ROOT/scripts/ros2/robot.py" --record "$RECORD" --duration 90 {robot_args} >"$ROBOT_OUT" 2>&1 & robot=$!
await_line "$ROBOT_OUT" $robot "robot ready" || {{ cat "$ROBOT_OUT" >&2; [ -z "$listener" ] || kill $listener; exit 3; }}
cd "$DIR"
{drive}
kill -TERM $robot; wait $robot
[ -z "$listener" ] || wait $listener
exit $code"#
    );
    let vars = [
        ("FILE", file.as_os_str()),
        ("DIR", dir.as_os_str()),
        ("RECORD", record.as_os_str()),
        ("ROBOT_OUT", robot_out.as_os_str()),
        ("UBF_ERR", ubf_err.as_os_str()),
        ("HEARD", heard_path.as_os_str()),
        ("LISTEN_ERR", listen_err.as_os_str()),
    ];
    let out = in_namespace(&script, &vars)?;
    let said = String::from_utf8_lossy(&out.stderr);
    assert_ne!(out.status.code(), Some(3), "the Cyclone robot did not start: {said}");
    assert_ne!(out.status.code(), Some(4), "the Cyclone listener did not start: {said}");
    let lines: Vec<Value> =
        std::fs::read_to_string(&record).unwrap().lines().map(|line| serde_json::from_str(line).unwrap()).collect();
    let (summary, twists) = lines.split_last().expect("the robot wrote its summary");
    let ubf = Output { status: out.status, stdout: Vec::new(), stderr: std::fs::read(&ubf_err).unwrap() };
    let heard = listen.map(|_| serde_json::from_slice(&std::fs::read(&heard_path).unwrap()).unwrap());
    Some(Session { ubf, twists: twists.to_vec(), summary: summary["summary"].clone(), heard })
}

fn stderr(session: &Session) -> String {
    String::from_utf8_lossy(&session.ubf.stderr).into_owned()
}

fn is_zero(twist: &Value) -> bool {
    ["linear", "angular"].iter().all(|part| ["x", "y", "z"].iter().all(|axis| twist[part][axis] == 0.0))
}

/// The robot's pose from its summary: (x, y, θ).
fn pose(summary: &Value) -> (f64, f64, f64) {
    let p = &summary["pose"];
    (p["x"].as_f64().unwrap(), p["y"].as_f64().unwrap(), p["theta"].as_f64().unwrap())
}

#[test]
fn a_cyclone_robot_reaches_a_goal_2_m_ahead_and_is_left_with_a_zero_twist() {
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 2.0, "");
    // Odometry that does not start at zero: the goal is in the frame where
    // the robot stood when the drive began.
    let (x0, y0, theta0): (f64, f64, f64) = (3.0, -1.0, 0.7);
    let args = format!("--start-x {x0} --start-y {y0} --start-theta {theta0}");
    let listen = "/ubf/tick=ubf_msgs/msg/Tick /ubf/goal=geometry_msgs/msg/PoseStamped \
                  /tf_static=tf2_msgs/msg/TFMessage:latched --min 3 --duration 30";
    let Some(session) = drive_and_listen(dir.path(), &args, &file, None, Some(listen)) else { return };
    assert_eq!(session.ubf.status.code(), Some(0), "{}", stderr(&session));
    assert!(stderr(&session).contains("at the goal"), "{}", stderr(&session));
    let (x, y, _) = pose(&session.summary);
    let goal = (x0 + 2.0 * theta0.cos(), y0 + 2.0 * theta0.sin());
    let miss = (x - goal.0).hypot(y - goal.1);
    assert!(miss <= 0.25, "ended ({x:.3}, {y:.3}), {miss:.3} m from the goal {goal:?}");
    assert!(session.twists.iter().any(|t| t["twist"]["linear"]["x"].as_f64().unwrap() > 0.2), "it drove");
    assert!(is_zero(&session.summary["last_twist"]), "last twist {}", session.summary["last_twist"]);
    // The drive's logs are there.
    assert!(dir.path().join("drive-log.csv").exists() && dir.path().join("drive-log.mcap").exists());
    // And a ROS 2 subscriber heard the tree and the goal (2 m ahead, in
    // the frame of the drive's start).
    let heard = session.heard.unwrap();
    let tick = &heard["/ubf/tick"]["last"];
    assert!(heard["/ubf/tick"]["count"].as_u64().unwrap() >= 3, "{heard}");
    let paths: Vec<&str> = tick["nodes"].as_array().unwrap().iter().map(|n| n["path"].as_str().unwrap()).collect();
    assert_eq!(paths, ["root", "root/Stop", "root/GoTo"], "{tick}");
    let goal = &heard["/ubf/goal"]["last"];
    assert_eq!(goal["pose"]["position"]["x"], 2.0, "{heard}");
    // In a frame of the drive's own, which ubf places in the robot's odom
    // frame for tf: composed as RViz would, the goal is where the robot
    // drove to by its own odometry.
    assert_eq!(goal["header"]["frame_id"], "ubf_world", "{goal}");
    let placed = &heard["/tf_static"]["last"]["transforms"][0];
    assert_eq!((&placed["header"]["frame_id"], &placed["child_frame_id"]), (&"odom".into(), &"ubf_world".into()));
    let (t, q) = (&placed["transform"]["translation"], &placed["transform"]["rotation"]);
    let number = |v: &Value| v.as_f64().unwrap();
    let yaw = 2.0 * number(&q["z"]).atan2(number(&q["w"]));
    let (gx, gy) = (number(&goal["pose"]["position"]["x"]), number(&goal["pose"]["position"]["y"]));
    let in_odom =
        (number(&t["x"]) + gx * yaw.cos() - gy * yaw.sin(), number(&t["y"]) + gx * yaw.sin() + gy * yaw.cos());
    let miss = (x - in_odom.0).hypot(y - in_odom.1);
    assert!(miss <= 0.25, "the goal placed in odom at {in_odom:?}, the robot ended at ({x:.3}, {y:.3})");
}

#[test]
fn a_run_published_on_ros2_is_heard_by_cyclone() {
    install_cyclone();
    let dir = tempfile::tempdir().unwrap();
    // The run lasts a few seconds: the listener subscribes first.
    let script = format!(
        r#"{}
"$UBF" run "$ROOT/scenarios/goto-open-floor.ron" --ros2 --speed 4 >/dev/null & run=$!
wait $listener; code=$?; wait $run
[ $code = 0 ] || cat "$LISTEN_ERR" >&2
cat "$HEARD"; exit $code"#,
        listener_script(
            "/odom=nav_msgs/msg/Odometry /tf=tf2_msgs/msg/TFMessage \
    /scan=sensor_msgs/msg/LaserScan:best_effort /ubf/tick=ubf_msgs/msg/Tick \
    /ubf/goal=geometry_msgs/msg/PoseStamped /ubf/pose/true=geometry_msgs/msg/PoseStamped \
    /ubf/pose/steered=geometry_msgs/msg/PoseStamped --min 5 --duration 30"
        )
    );
    let (heard, listen_err) = (dir.path().join("heard.json"), dir.path().join("listen.err"));
    let vars = [("HEARD", heard.as_os_str()), ("LISTEN_ERR", listen_err.as_os_str())];
    let Some(out) = in_namespace(&script, &vars) else { return };
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let heard: Value = serde_json::from_slice(&out.stdout).unwrap();
    let odom = &heard["/odom"]["last"];
    assert_eq!(
        (odom["header"]["frame_id"].as_str(), odom["child_frame_id"].as_str()),
        (Some("odom"), Some("base_link"))
    );
    let transform = &heard["/tf"]["last"]["transforms"][0];
    assert_eq!(transform["child_frame_id"], "base_link");
    // The transform is the odometry's pose, tick by tick. The listener stops
    // once every topic is heard, so their last samples may be a tick apart:
    // the samples are paired by stamp.
    let recent = |topic: &str| heard[topic]["recent"].as_array().unwrap().clone();
    let odometry = recent("/odom");
    let pairs: Vec<(Value, Value)> = recent("/tf")
        .iter()
        .filter_map(|tf| {
            let transform = &tf["transforms"][0];
            let odom = odometry.iter().find(|o| o["header"]["stamp"] == transform["header"]["stamp"])?;
            Some((transform["transform"]["translation"]["x"].clone(), odom["pose"]["pose"]["position"]["x"].clone()))
        })
        .collect();
    assert!(!pairs.is_empty(), "no /tf and /odom of the same stamp: {heard}");
    assert!(pairs.iter().all(|(tf, odom)| tf == odom), "{pairs:?}");
    // Stamped with the wall clock, as tf2 wants: after 2026.
    assert!(odom["header"]["stamp"]["sec"].as_i64().unwrap() > 1_767_225_600, "{odom}");
    assert_eq!(heard["/ubf/goal"]["last"]["pose"]["position"]["x"], 8.0);
    assert_eq!(heard["/ubf/pose/steered"]["last"]["header"]["frame_id"], "odom", "{heard}");
    let scan = &heard["/scan"]["last"];
    assert_eq!(scan["ranges"].as_array().unwrap().len(), 360);
    assert!(heard["/ubf/tick"]["last"]["nodes"].as_array().unwrap().len() >= 2);
}

#[test]
fn odometry_that_stops_coming_stops_the_robot_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 20.0, "");
    let Some(session) = drive_beside_robot(dir.path(), "--stop-odom-after 1", &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(1), "{}", stderr(&session));
    assert!(stderr(&session).contains("no odometry on /odom"), "{}", stderr(&session));
    // The first zero twist after the robot moved came within a few
    // periods of the last odometry (3 periods of 0.1 s, plus a tick).
    let moved = session.twists.iter().position(|t| !is_zero(&t["twist"])).expect("it drove");
    let stop = session.twists[moved..].iter().find(|t| is_zero(&t["twist"])).expect("a zero twist");
    let age = stop["odom_age"].as_f64().unwrap();
    assert!(age < 0.6, "the zero twist came {age:.3} s after the last odometry");
    assert!(is_zero(&session.summary["last_twist"]));
}

#[test]
fn odometry_that_jumps_further_than_any_robot_drives_stops_the_robot() {
    // Steered by, it once drove the robot 6 m past its goal without a word.
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 20.0, "");
    let Some(session) = drive_beside_robot(dir.path(), "--odom-jump-after 1", &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(1), "{}", stderr(&session));
    assert!(stderr(&session).contains("the odometry jumped 100.0"), "{}", stderr(&session));
    assert!(session.twists.iter().any(|t| !is_zero(&t["twist"])), "it drove before the jump");
    assert!(is_zero(&session.summary["last_twist"]), "last twist {}", session.summary["last_twist"]);
}

#[test]
fn a_second_odometry_publisher_stops_the_robot() {
    // The reader kept one writer's messages, and a stray one at x = -10 m
    // once took over and spun the robot round.
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 20.0, "");
    let Some(session) = drive_beside_robot(dir.path(), "--second-odom-after 1", &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(1), "{}", stderr(&session));
    assert!(stderr(&session).contains("/odom: two writers publish on it at once"), "{}", stderr(&session));
    assert!(is_zero(&session.summary["last_twist"]), "last twist {}", session.summary["last_twist"]);
}

#[test]
fn a_reader_of_the_commands_that_stops_acknowledging_does_not_stop_the_drive() {
    // A `ros2 topic echo /cmd_vel` stopped (Ctrl-Z) while the robot drives:
    // with the writer's send window as small as its history (10), the
    // commands blocked after a second and the drive ended as a lost link.
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 2.0, "");
    let stall = "(sleep 0.5; kill -STOP $listener; sleep 8; kill -CONT $listener) & true";
    let listen = "/cmd_vel=geometry_msgs/msg/Twist --duration 12";
    let Some(session) = drive_and_listen(dir.path(), "", &file, Some(stall), Some(listen)) else { return };
    assert_eq!(session.ubf.status.code(), Some(0), "{}", stderr(&session));
    assert!(stderr(&session).contains("at the goal"), "{}", stderr(&session));
}

#[test]
fn a_base_that_reads_stamped_commands_is_sent_them_and_reaches_its_goal() {
    // As ros2_control's diff drive controller from Jazzy on: TwistStamped
    // only, read off the base's reader by discovery.
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 2.0, "");
    let Some(session) = drive_beside_robot(dir.path(), "--stamped-cmd-vel", &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(0), "{}", stderr(&session));
    let (x, y, _) = pose(&session.summary);
    assert!((x - 2.0).hypot(y) <= 0.25, "ended at ({x:.3}, {y:.3})");
    assert!(is_zero(&session.summary["last_twist"]), "last twist {}", session.summary["last_twist"]);
    assert!(
        stderr(&session).contains("commands as geometry_msgs/msg/TwistStamped, no scan yet"),
        "{}",
        stderr(&session)
    );
    // In base_link, stamped zero: the base's own clock times them out.
    for line in &session.twists {
        let header = &line["header"];
        assert_eq!(header["frame_id"], "base_link", "{line}");
        assert_eq!((&header["stamp"]["sec"], &header["stamp"]["nanosec"]), (&0.into(), &0.into()), "{line}");
    }
}

#[test]
fn commands_of_a_type_the_base_does_not_read_end_the_drive_before_it_moves() {
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 2.0, "ros2: (cmd_vel_stamped: false),");
    let Some(session) = drive_beside_robot(dir.path(), "--stamped-cmd-vel", &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(1), "{}", stderr(&session));
    let said = stderr(&session);
    assert!(
        said.contains("/cmd_vel is read as geometry_msgs/msg/TwistStamped, and ubf sends geometry_msgs/msg/Twist"),
        "{said}"
    );
    assert!(said.contains("set `cmd_vel_stamped: true`"), "{said}");
    assert_eq!(pose(&session.summary).0, 0.0, "{said}");
}

#[test]
fn a_base_whose_stamped_reader_comes_after_its_odometry_is_waited_for() {
    // Its reader of the commands 2 s after its odometry: within the
    // connect timeout (5 s), so the type is read off it.
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 2.0, "");
    let robot = "--stamped-cmd-vel --cmd-vel-reader-after 2";
    let Some(session) = drive_beside_robot(dir.path(), robot, &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(0), "{}", stderr(&session));
    let (x, y, _) = pose(&session.summary);
    assert!((x - 2.0).hypot(y) <= 0.25, "ended at ({x:.3}, {y:.3})");
}

#[test]
fn a_stamped_reader_that_comes_after_the_drive_began_ends_it_saying_so() {
    // After the connect timeout (1 s): commands went as Twist, which the
    // base does not read, so it would never move while the drive ran on.
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 2.0, "ros2: (connect_timeout_s: 1.0),");
    let robot = "--stamped-cmd-vel --cmd-vel-reader-after 6";
    let Some(session) = drive_beside_robot(dir.path(), robot, &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(1), "{}", stderr(&session));
    let said = stderr(&session);
    assert!(said.contains("nothing reads /cmd_vel yet: commands go as geometry_msgs/msg/Twist"), "{said}");
    assert!(said.contains("the robot's reader came after the type was chosen"), "{said}");
    assert!(said.contains("set `cmd_vel_stamped: true`"), "{said}");
}

#[test]
fn commands_read_as_both_types_end_the_drive_before_it_moves() {
    // A base that reads TwistStamped and a node that reads Twist: which
    // one is the base cannot be told.
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 2.0, "");
    let listen = "/cmd_vel=geometry_msgs/msg/Twist --duration 8";
    let Some(session) = drive_and_listen(dir.path(), "--stamped-cmd-vel", &file, None, Some(listen)) else { return };
    assert_eq!(session.ubf.status.code(), Some(1), "{}", stderr(&session));
    let said = stderr(&session);
    assert!(said.contains("is read as both"), "{said}");
    assert_eq!(pose(&session.summary).0, 0.0, "{said}");
}

#[test]
fn a_stranger_s_unreadable_odometry_is_skipped_and_the_robot_drives_on() {
    // A message named odometry that holds a header only, from another
    // participant: one of them used to end the drive.
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 2.0, "");
    let Some(session) = drive_beside_robot(dir.path(), "--short-odom-after 0.5", &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(0), "{}", stderr(&session));
    let said = stderr(&session);
    assert!(said.contains("at the goal"), "{said}");
    // Said at most every 10 s.
    let said_times = said.matches("could not be read as nav_msgs/msg/Odometry").count();
    assert!((1..=2).contains(&said_times), "{said}");
}

/// Drives towards a goal 20 m ahead beside the Cyclone robot run with
/// `robot_args`, and checks that the drive failed, saying each of
/// `sayings`, and left the robot with a zero twist.
fn assert_stopped_saying(robot_args: &str, sayings: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 20.0, "");
    let Some(session) = drive_beside_robot(dir.path(), robot_args, &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(1), "{}", stderr(&session));
    let said = stderr(&session);
    for saying in sayings {
        assert!(said.contains(saying), "{saying:?} not said: {said}");
    }
    assert!(is_zero(&session.summary["last_twist"]), "last twist {}", session.summary["last_twist"]);
}

#[test]
fn odometry_that_cannot_be_read_stops_the_robot_and_says_why() {
    // The robot's own odometry stops and only unreadable messages come.
    assert_stopped_saying(
        "--stop-odom-after 1 --short-odom-after 0.5",
        &["the odometry on /odom: it could not be read as nav_msgs/msg/Odometry", "no odometry on /odom"],
    );
}

#[test]
fn a_scan_that_cannot_be_read_stops_the_robot_as_no_scan() {
    // Taken as no message at all, it left the robot driving blind, with
    // nothing to stop it.
    assert_stopped_saying(
        "--short-scan-after 0.5",
        &["the scan on /scan: it could not be read as sensor_msgs/msg/LaserScan", "no usable scan on /scan for"],
    );
}

#[test]
fn a_scan_whose_every_beam_is_invalid_stops_the_robot() {
    // Taken as open space, it let the robot drive through a wall. It is
    // taken as no scan, so the robot stops as for a silent scanner.
    assert_stopped_saying(
        "--scan --wall-x 10 --scan-nan-after 1",
        &["the scan on /scan: all of its", "no usable scan on /scan for"],
    );
}

#[test]
fn sigterm_leaves_the_robot_with_a_zero_twist() {
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 20.0, "");
    let Some(session) = drive_beside_robot(
        dir.path(),
        "",
        &file,
        Some(r#"await_line "$UBF_ERR" $ubf "connected to"; sleep 1.5; kill -TERM $ubf"#),
    ) else {
        return;
    };
    assert_eq!(session.ubf.status.code(), Some(130), "{}", stderr(&session));
    assert!(session.twists.iter().any(|t| !is_zero(&t["twist"])), "it drove before the signal");
    assert!(is_zero(&session.summary["last_twist"]), "last twist {}", session.summary["last_twist"]);
}

#[test]
fn sigterm_stops_the_robot_while_the_control_loop_hangs() {
    // The loop hangs 2 s into the drive, the robot still driving on its
    // last twist: the first SIGTERM stops it from outside the loop, the
    // second one ends the process with the robot still stopped.
    let dir = tempfile::tempdir().unwrap();
    // The loop's own watch, which would stop it 1.3 s into the hang, is
    // given longer, so that the signals do it here.
    let file = robot_file(dir.path(), 20.0, "safety: (link_lost_after_s: 20.0, stale_after_s: 0.25),");
    let hanging = "root: Composite(arbiter: CommandFusion, children: [(behavior: InjectFault(after_s: 2.0, hang_s: \
                   30.0)), (behavior: GoTo(cruise_speed: 0.3))]),";
    let text = std::fs::read_to_string(&file).unwrap();
    let root = text.lines().find(|line| line.trim_start().starts_with("root:")).unwrap();
    std::fs::write(&file, text.replace(root, hanging)).unwrap();
    // Timed from the connection, however long connecting takes: the hang
    // comes 2 s into the drive.
    let interrupt =
        r#"await_line "$UBF_ERR" $ubf "connected to"; sleep 3.5; kill -TERM $ubf; sleep 2.5; kill -TERM $ubf"#;
    let Some(session) = drive_beside_robot(dir.path(), "", &file, Some(interrupt)) else { return };
    let said = stderr(&session);
    assert_eq!(session.ubf.status.code(), Some(130), "{said}");
    assert!(said.contains("interrupted twice: robot sent a zero twist on /cmd_vel; exiting now"), "{said}");
    // Driving until the first SIGTERM, a zero twist from then on.
    let first_zero = session.twists.iter().rposition(|t| !is_zero(&t["twist"])).expect("it drove") + 1;
    let stopped = &session.twists[first_zero..];
    assert!(!stopped.is_empty() && stopped.iter().all(|t| is_zero(&t["twist"])), "{:?}", session.twists);
    let (hung, stop) = (session.twists[first_zero - 1]["t"].as_f64().unwrap(), stopped[0]["t"].as_f64().unwrap());
    // The first SIGTERM came about 1.5 s into the hang, the second 4 s.
    assert!((1.0..2.8).contains(&(stop - hung)), "the loop hung {:.2} s before the zero twist, not 1.5 s", stop - hung);
}

#[test]
fn a_sandbox_without_netlink_is_named() {
    // As under a systemd unit whose address families leave netlink out:
    // DDS would find no network interface and every topic would be silent,
    // which would look like a missing robot driver.
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 2.0, "");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/ros2/no-netlink.py");
    let out = Command::new("python3")
        .arg(script)
        .args([env!("CARGO_BIN_EXE_ubf"), "drive"])
        .arg(&file)
        .current_dir(dir.path())
        .env_remove("ROS_DOMAIN_ID")
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stderr);
    if out.status.code() == Some(77) {
        eprintln!("skipped: {said}");
        return;
    }
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(said.contains("AF_NETLINK in RestrictAddressFamilies"), "{said}");
}

#[test]
fn a_topic_of_another_type_is_named() {
    let dir = tempfile::tempdir().unwrap();
    // Odometry read from where the robot publishes its laser scans.
    let file = robot_file(dir.path(), 2.0, r#"ros2: (odom: "scan", connect_timeout_s: 2.0),"#);
    let Some(session) = drive_beside_robot(dir.path(), "--scan", &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(1), "{}", stderr(&session));
    let text = stderr(&session);
    assert!(
        text.contains("/scan is published with type `sensor_msgs::msg::dds_::LaserScan_`, but ubf reads it as"),
        "{text}"
    );
    assert!(session.twists.iter().all(|t| is_zero(&t["twist"])), "nothing but stops was sent");
}

#[test]
fn best_effort_odometry_is_named_and_heard_with_sensor_data_qos() {
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 2.0, "ros2: (connect_timeout_s: 2.0),");
    let Some(session) = drive_beside_robot(dir.path(), "--odom-best-effort", &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(1), "{}", stderr(&session));
    assert!(stderr(&session).contains("/odom is published best effort"), "{}", stderr(&session));

    let file = robot_file(dir.path(), 2.0, "ros2: (odom_qos: SensorData),");
    let Some(session) = drive_beside_robot(dir.path(), "--odom-best-effort", &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(0), "{}", stderr(&session));
}

#[test]
fn a_namespaced_robot_is_driven_under_its_namespace() {
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 1.0, r#"ros2: (namespace: "/robot1"), log_format: Ros2,"#);
    let Some(session) = drive_beside_robot(dir.path(), "--namespace robot1", &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(0), "{}", stderr(&session));
    let (x, y, _) = pose(&session.summary);
    assert!((x.hypot(y) - 1.0).abs() <= 0.25, "ended at ({x:.3}, {y:.3})");
    // The drive's rosbag2 log reads with the standard readers.
    let verdict = check_bag(&dir.path().join("drive-log-rosbag2/drive-log-rosbag2_0.mcap"), &["/odom", "/ubf/tick"]);
    assert_eq!(verdict["ok"], true, "{verdict}");
}

/// Where the robot's centre ends, driven with AvoidCollision towards a
/// goal 4 m ahead beside the Cyclone robot run with `robot_args` (a wall
/// in its scan), with `ros2` the robot file's `ros2:` settings.
fn where_the_wall_stops_the_robot(robot_args: &str, ros2: &str) -> Option<f64> {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    let robot = format!(
        r#"RobotConfig(
    name: "ros2-robot",
    connection: "ros2",
    model: Powerbot,
    ros2: ({ros2}),
    max_time_s: 12.0,
    goal: (x: 4.0, y: 0.0, tolerance: 0.2),
    root: Composite(arbiter: CommandFusion, children: [
        (behavior: Stop(), weight: 1.0),
        (behavior: AvoidCollision(), weight: 3.0),
        (behavior: GoTo(cruise_speed: 0.3)),
    ]),
)"#
    );
    std::fs::write(&file, robot).unwrap();
    let session = drive_beside_robot(dir.path(), robot_args, &file, None)?;
    assert_eq!(session.ubf.status.code(), Some(0), "{}", stderr(&session));
    Some(pose(&session.summary).0)
}

#[test]
fn a_scan_wall_ahead_turns_the_robot_away() {
    // AvoidCollision sees the scan's wall 1.5 m ahead and the goal beyond
    // it: the robot must not drive into it.
    let Some(x) = where_the_wall_stops_the_robot("--scan --wall-x 1.5", "") else { return };
    assert!(x < 1.5 - 0.3, "the robot's centre came to x = {x:.3}, the wall is at 1.5");
}

#[test]
fn a_scanner_mounted_backwards_behind_the_centre_is_read_from_where_it_sits() {
    // Its angle 0 points backwards: read as if at the centre facing ahead,
    // the wall ahead would be behind the robot, which would drive into it.
    let mount = "scan_mount: (x: -0.3, heading_deg: 180.0)";
    let Some(x) = where_the_wall_stops_the_robot("--scan --wall-x 1.5 --laser-mount -0.3 180", mount) else { return };
    // Where the robot with its scanner at the centre stops (0.76 to 0.80
    // m): the scanner taken 0.3 m ahead instead of behind stopped it at
    // 1.15 m, read as at the centre facing ahead it ended at 1.83 m.
    assert!((0.5..1.0).contains(&x), "the robot's centre came to x = {x:.3}, the wall is at 1.5");
}

#[test]
fn a_scanner_mount_published_on_tf_static_is_read_from_where_it_sits() {
    // The same scanner, backwards 0.3 m behind the centre, its mount not
    // written but published as a robot's static broadcasters do: two
    // Cyclone writers, transient local, down a chain of frames from
    // base_footprint, before ubf joins.
    let robot = "--scan --wall-x 1.5 --laser-mount -0.3 180 --tf-static";
    let Some(x) = where_the_wall_stops_the_robot(robot, "") else { return };
    assert!((0.5..1.0).contains(&x), "the robot's centre came to x = {x:.3}, the wall is at 1.5");
}

#[test]
fn a_scanner_mount_that_moves_on_tf_static_during_the_drive_is_said() {
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 1.0, "");
    let robot = "--scan --wall-x 10 --laser-mount -0.3 180 --tf-static --tf-static-turn-after 0.3";
    let Some(session) = drive_beside_robot(dir.path(), robot, &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(0), "{}", stderr(&session));
    let said = stderr(&session);
    // Said when connected, for the operator, and when it moved.
    let connected =
        r#"commands as geometry_msgs/msg/Twist, scanner ("laser") at (-0.30, 0.00) m facing 180°, by /tf_static"#;
    assert!(said.contains(connected), "{said}");
    let moved = r#"the scanner ("laser") moved on /tf_static during the drive, from (-0.30, 0.00) m facing 180° to (-0.30, 0.00) m facing -90°"#;
    assert!(said.contains(moved), "{said}");
}

#[test]
fn a_scan_from_a_frame_no_transform_places_ends_the_drive_before_the_robot_moves() {
    let dir = tempfile::tempdir().unwrap();
    let file = robot_file(dir.path(), 2.0, "ros2: (connect_timeout_s: 1.0),");
    let robot = "--scan --wall-x 1.5 --laser-mount -0.3 180";
    let Some(session) = drive_beside_robot(dir.path(), robot, &file, None) else { return };
    assert_eq!(session.ubf.status.code(), Some(1), "{}", stderr(&session));
    let said = stderr(&session);
    assert!(
        said.contains("the scan on /scan: its scanner's mount was looked up on /tf_static, and nothing has come on it"),
        "{said}"
    );
    assert!(session.twists.iter().all(is_zero), "the robot was moved: {:?}", session.twists);
    assert_eq!(pose(&session.summary).0, 0.0);
}

/// Runs `scripts/ros2-bag-check.py` (mcap-ros2-support and rosbags, which
/// nobody here wrote) on a bag's MCAP; its JSON verdict.
fn check_bag(mcap: &Path, topics: &[&str]) -> Value {
    let mut command = Command::new("python3");
    command.arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/ros2-bag-check.py")).arg(mcap);
    for topic in topics {
        command.args(["--expect-topic", topic]);
    }
    let out = command.output().unwrap();
    assert!(out.status.success(), "{}\n{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn a_run_logged_for_ros2_decodes_with_the_standard_readers_and_repeats_its_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let ubf = |out: &Path| {
        let run = Command::new(env!("CARGO_BIN_EXE_ubf"))
            .args(["run", "scenarios/camera-sweep.ron", "--log-format", "ros2", "--out"])
            .arg(out)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        out.join("run-rosbag2")
    };
    let (a, b) = (ubf(&dir.path().join("a")), ubf(&dir.path().join("b")));
    for file in ["metadata.yaml", "run-rosbag2_0.mcap"] {
        assert!(std::fs::read(a.join(file)).unwrap() == std::fs::read(b.join(file)).unwrap(), "{file} differs");
    }
    let topics = [
        "/tf",
        "/odom",
        "/scan",
        "/ubf/tick",
        "/ubf/goal",
        "/ubf/pose/true",
        "/ubf/pose/egomotion",
        "/ubf/pose/steered",
        "/ubf/report",
    ];
    let verdict = check_bag(&a.join("run-rosbag2_0.mcap"), &topics);
    assert_eq!(verdict["ok"], true, "{verdict}");
    let report: Value = serde_json::from_slice(&std::fs::read(dir.path().join("a/report.json")).unwrap()).unwrap();
    let ticks = report["ticks"].as_u64().unwrap();
    for topic in ["/tf", "/odom", "/ubf/pose/steered", "/ubf/tick"] {
        let counted = &verdict["topics"][topic];
        assert_eq!((counted["mcap_ros2"].as_u64(), counted["rosbags"].as_u64()), (Some(ticks), Some(ticks)), "{topic}");
    }
    let tick = &verdict["topics"]["/ubf/tick"]["first"];
    assert_eq!(tick["nodes"][0]["path"], "root", "{tick}");
}

#[test]
fn a_simulator_served_on_ros2_and_heard_writes_nothing_on_stderr_in_normal_use() {
    // Its scan, 1548 bytes, drew a warning from the DDS library each tick.
    install_cyclone();
    let dir = tempfile::tempdir().unwrap();
    let script = r#""$UBF" simulate "$ROOT/scenarios/corridor-box.ron" --ros2 --max-time 60 2>"$OUT/sim.err" & sim=$!
python3 "$ROOT/scripts/ros2/listen.py" /scan=sensor_msgs/msg/LaserScan:best_effort --min 10 --duration 20 >/dev/null
code=$?; kill -TERM $sim; wait $sim; exit $code"#;
    let Some(out) = in_namespace(script, &[("OUT", dir.path().as_os_str())]) else { return };
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let said = std::fs::read_to_string(dir.path().join("sim.err")).unwrap();
    assert!(!said.contains("WARN") && !said.contains("ERROR"), "{said}");
}

/// How far a Cyclone teleop (scripts/ros2/teleop.py with `teleop_args`)
/// driving forward at 0.3 m/s for 3 s moves `ubf simulate --ros2` with
/// `simulate_args`, by the odometry it hears.
fn teleop_drives_the_simulator(simulate_args: &str, teleop_args: &str) -> Option<f64> {
    install_cyclone();
    let script = format!(
        r#""$UBF" simulate "$ROOT/scenarios/goto-open-floor.ron" --ros2 --max-time 60 {simulate_args} 2>/dev/null & sim=$!
python3 "$ROOT/scripts/ros2/teleop.py" --linear 0.3 --duration 3 {teleop_args}
code=$?; kill -TERM $sim; wait $sim; [ $? -eq 130 ] || code=9; exit $code"#
    );
    let out = in_namespace(&script, &[])?;
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let heard: Value = serde_json::from_slice(&out.stdout).unwrap();
    let (first, last) = (&heard["first"], &heard["last"]);
    let dx = last["x"].as_f64().unwrap() - first["x"].as_f64().unwrap();
    let dy = last["y"].as_f64().unwrap() - first["y"].as_f64().unwrap();
    assert!(heard["odometry"].as_u64().unwrap() > 20, "{heard}");
    Some(dx.hypot(dy))
}

#[test]
fn a_cyclone_teleop_drives_the_simulator_served_on_ros2() {
    // `ubf simulate --ros2` is a ROS 2 robot: a controller nobody here
    // wrote (Cyclone DDS) drives it. 0.9 m commanded; the Powerbot's
    // acceleration and the first and last ticks take some of it, the
    // timing of the teleop's loop adds some.
    let Some(moved) = teleop_drives_the_simulator("", "") else { return };
    assert!((0.6..=1.1).contains(&moved), "moved {moved:.3} m");
}

#[test]
fn a_stamped_teleop_to_a_simulator_serving_twist_is_said() {
    install_cyclone();
    let dir = tempfile::tempdir().unwrap();
    let script = r#""$UBF" simulate "$ROOT/scenarios/goto-open-floor.ron" --ros2 --max-time 60 2>"$OUT/sim.err" & sim=$!
python3 "$ROOT/scripts/ros2/teleop.py" --linear 0.3 --duration 3 --stamped >/dev/null
code=$?; kill -TERM $sim; wait $sim; exit $code"#;
    let Some(out) = in_namespace(script, &[("OUT", dir.path().as_os_str())]) else { return };
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let said = std::fs::read_to_string(dir.path().join("sim.err")).unwrap();
    let expected = "a commander sends geometry_msgs/msg/TwistStamped on /cmd_vel, which is read as \
                    geometry_msgs/msg/Twist here: serve it with `--cmd-vel-stamped`";
    assert_eq!(said.matches(expected).count(), 1, "{said}");
}

#[test]
fn a_stamped_teleop_drives_the_simulator_served_for_stamped_commands() {
    let Some(moved) = teleop_drives_the_simulator("--cmd-vel-stamped", "--stamped") else { return };
    assert!((0.6..=1.1).contains(&moved), "moved {moved:.3} m");
}
