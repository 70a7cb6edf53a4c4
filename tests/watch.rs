//! `--watch` on `ubf run` and `ubf drive`: a tree edited while it runs is
//! swapped in at a tick boundary; an edit that fails its check, or changes
//! more than the tree, is refused with its reason and the running tree
//! goes on.

mod common;

use common::{emulator, Killed};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::Duration;

/// Replaces `path`'s content at once, as an editor that saves by renaming
/// does: the watcher never reads half a file.
fn save(path: &Path, text: &str) {
    let temporary = path.with_extension("saving");
    std::fs::write(&temporary, text).unwrap();
    std::fs::rename(&temporary, path).unwrap();
}

/// `child`'s stderr, line by line, on a channel.
fn stderr_lines(child: &mut Child) -> Receiver<String> {
    let err = BufReader::new(child.stderr.take().unwrap());
    let (send, lines) = channel();
    std::thread::spawn(move || {
        for line in err.lines().map_while(Result::ok) {
            if send.send(line).is_err() {
                break;
            }
        }
    });
    lines
}

/// Waits for a line holding every one of `words`; the lines read on the way.
fn wait_for_line(lines: &Receiver<String>, words: &[&str]) -> Vec<String> {
    let mut seen = Vec::new();
    loop {
        match lines.recv_timeout(Duration::from_secs(30)) {
            Ok(line) => {
                let found = words.iter().all(|w| line.contains(w));
                seen.push(line);
                if found {
                    return seen;
                }
            }
            Err(_) => panic!("no line with {words:?} in 30 s; stderr so far:\n{}", seen.join("\n")),
        }
    }
}

#[test]
fn a_run_takes_a_valid_edit_of_its_tree_and_refuses_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let original = std::fs::read_to_string(root.join("scenarios/corridor-box.ron")).unwrap();
    let file = dir.path().join("box.ron");
    std::fs::write(&file, &original).unwrap();
    let out = dir.path().join("out");
    let mut run = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["run", file.to_str().unwrap(), "--watch", "--speed", "5", "--out", out.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let lines = stderr_lines(&mut run);
    let mut run = Killed(run);
    std::thread::sleep(Duration::from_millis(800));

    // A behaviour that does not exist: refused with its place.
    save(&file, &original.replace("(behavior: GoTo(cruise_speed: 0.5))", "(behavior: GoToo(cruise_speed: 0.5))"));
    let refused = wait_for_line(&lines, &["edit refused", "the running tree goes on"]);
    let place = format!("{}:", file.display());
    assert!(refused.iter().any(|l| l.contains(&place) && l.contains("GoToo")), "{refused:#?}");

    // A goal moved: more than the tree, so refused as a whole.
    let moved = original.replace("(behavior: GoTo(cruise_speed: 0.5))", "(behavior: GoTo(cruise_speed: 0.9))");
    save(&file, &moved.replace("goal: (x: 16.0", "goal: (x: 12.0"));
    wait_for_line(&lines, &["`goal` changed", "restart"]);

    // The tree alone: taken.
    save(&file, &moved);
    wait_for_line(&lines, &["edited; the new tree runs from the next tick"]);
    let status = run.0.wait().unwrap();
    assert!(status.success(), "{status}");

    // Before the edit GoTo asked for 0.5 m/s at most, after it for 0.9:
    // the faster tree drove, and the goal stayed where it was.
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let v = header.iter().position(|c| *c == "cmd_velocity").unwrap();
    let speeds: Vec<f64> = csv.lines().skip(1).map(|l| l.split(',').nth(v).unwrap().parse().unwrap()).collect();
    let first_fast = speeds.iter().position(|s| *s > 0.51).expect("the edited tree drove faster");
    assert!(first_fast > 10, "the first ticks ran the first tree");
    assert!(speeds[..first_fast].iter().all(|s| *s <= 0.5 + 1e-9));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["reached_goal"], true, "{report}");
    assert!((report["final_true_pose"]["x"].as_f64().unwrap() - 16.0).abs() < 0.5, "{report}");
}

#[test]
fn a_drive_takes_a_new_tree_without_stopping_and_refuses_a_new_connection() {
    let (_emulator, address, _emulator_out) = emulator();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("robot.ron");
    let robot = |connection: &str, root: &str| {
        format!(
            r#"RobotConfig(
                name: "watched",
                connection: "{connection}",
                model: Powerbot,
                log: "{}",
                goal: (x: 1.0, y: 0.0, tolerance: 0.2),
                root: {root},
            )"#,
            dir.path().join("log.csv").display()
        )
    };
    // It starts with a tree that only stops: it would never reach its goal.
    std::fs::write(&file, robot(&address, "Stop()")).unwrap();
    let mut drive = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["drive", file.to_str().unwrap(), "--watch", "--until-goal"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let lines = stderr_lines(&mut drive);
    let mut drive = Killed(drive);
    wait_for_line(&lines, &["connected to"]);

    let go = "Composite(arbiter: CommandFusion, children: [(behavior: Stop(), weight: 1.0), (behavior: GoTo(cruise_speed: 0.4))])";
    save(&file, &robot("tcp://127.0.0.1:9", go));
    wait_for_line(&lines, &["`connection` changed", "restart"]);
    save(&file, &robot(&address, go));
    wait_for_line(&lines, &["edited; the new tree runs from the next tick"]);
    let status = drive.0.wait().unwrap();
    assert!(status.success(), "the new tree drove to the goal: {status}");
    let log = std::fs::read_to_string(dir.path().join("log.csv")).unwrap();
    assert!(log.lines().any(|l| l.contains("root/GoTo")), "GoTo won once the tree changed");
}
