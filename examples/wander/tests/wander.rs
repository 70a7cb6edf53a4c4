//! The user's behaviour runs from a scenario file by name, repeatably.

use std::process::Command;

fn wander(seed: &str) -> serde_json::Value {
    let out = Command::new(env!("CARGO_BIN_EXE_wander"))
        .args(["run", "wander.ron", "--json", "--seed", seed])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    report.as_object_mut().unwrap().remove("wall_time_s");
    report
}

#[test]
fn wander_runs_from_its_scenario_file() {
    let report = wander("3");
    assert_eq!(report["scenario"], "wander");
    assert_eq!(report["end"], "time_limit");
    // 60 s at up to 0.4 m/s, after accelerating.
    let distance = report["distance_m"].as_f64().unwrap();
    assert!(distance > 20.0 && distance <= 24.0, "{distance}");
}

#[test]
fn the_seed_decides_the_wander() {
    assert_eq!(wander("3"), wander("3"));
    assert_ne!(wander("3")["final_true_pose"], wander("4")["final_true_pose"]);
}
