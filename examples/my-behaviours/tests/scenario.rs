//! The crate's behaviour runs from its scenario file by name, and stops
//! short of the wall ahead.

use std::process::Command;

fn run(seed: &str) -> serde_json::Value {
    let out = Command::new(env!("CARGO_BIN_EXE_my-behaviours"))
        .args(["run", "my-behaviours.ron", "--json", "--seed", seed])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    report.as_object_mut().unwrap().remove("wall_time_s");
    report
}

#[test]
fn cruise_runs_from_its_scenario_file_and_stops_short_of_the_wall() {
    let report = run("1");
    assert_eq!(report["scenario"], "my-behaviours");
    assert_eq!(report["collisions"], 0, "{report}");
    let x = report["final_true_pose"]["x"].as_f64().unwrap();
    // The end wall is at x = 12 m: it halts short of it, sonar noise and
    // the robot's half length (0.45 m) apart.
    assert!(x > 10.0 && x < 11.3, "{report}");
}

#[test]
fn the_same_seed_gives_the_same_run() {
    assert_eq!(run("1"), run("1"));
}
