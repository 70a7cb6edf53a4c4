//! The same scenario and seed give the same bytes as when these outputs
//! were recorded: a restructuring of the code (how the loop, the robot
//! stack and the sinks are put together) must not change what a run
//! writes.
//!
//! The fingerprints in `tests/recorded/outputs.txt` were taken from the
//! code before such a change. A change that alters behaviour on purpose
//! records them again, and says why in its commit:
//! `UBF_RECORD_OUTPUTS=1 cargo test --test recorded_outputs`.

use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// Runs `ubf` in the repository and fails the test on a non-zero exit.
fn ubf(args: &[&str]) {
    let out =
        Command::new(env!("CARGO_BIN_EXE_ubf")).args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap();
    assert!(out.status.success(), "ubf {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

fn fingerprint(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

/// `report.json` without the one field that differs between runs.
fn report_without_wall_time(path: &Path) -> Vec<u8> {
    let mut report: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    report.as_object_mut().unwrap().remove("wall_time_s").expect("a report has its wall time");
    serde_json::to_vec_pretty(&report).unwrap()
}

/// Every output of the recorded cases, by `case/file`.
fn outputs() -> BTreeMap<String, String> {
    let scratch = tempfile::tempdir().unwrap();
    let mut prints = BTreeMap::new();
    let runs = [
        ("goto-open-floor", "1"),
        ("corridor-box", "2"),
        ("people-and-featureless-wall", "3"),
        ("camera-sweep", "1"),
        ("veering-robot", "4"),
    ];
    for (scenario, seed) in runs {
        let case = format!("run {scenario} seed {seed}");
        let out = scratch.path().join(&case);
        let file = format!("scenarios/{scenario}.ron");
        ubf(&["run", &file, "--seed", seed, "--out", out.to_str().unwrap()]);
        for name in ["trajectory.csv", "run.mcap", "plot.png"] {
            prints.insert(format!("{case}/{name}"), fingerprint(&std::fs::read(out.join(name)).unwrap()));
        }
        prints.insert(format!("{case}/report.json"), fingerprint(&report_without_wall_time(&out.join("report.json"))));
    }
    let case = "frames rendered-corridor";
    let out = scratch.path().join(case);
    ubf(&["frames", "scenarios/rendered-corridor.ron", "--out", out.to_str().unwrap(), "--max-frames", "3"]);
    for name in ["frames.csv", "camera.ron", "left/000003.png", "right/000003.png"] {
        prints.insert(format!("{case}/{name}"), fingerprint(&std::fs::read(out.join(name)).unwrap()));
    }
    prints
}

#[test]
fn runs_and_recordings_write_the_recorded_bytes() {
    let recorded_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/recorded/outputs.txt");
    let now = outputs();
    if std::env::var_os("UBF_RECORD_OUTPUTS").is_some() {
        let text: String = now.iter().map(|(what, print)| format!("{print}  {what}\n")).collect();
        std::fs::write(&recorded_path, text).unwrap();
        return;
    }
    let text = std::fs::read_to_string(&recorded_path).unwrap();
    let recorded: BTreeMap<String, String> = text
        .lines()
        .map(|line| {
            let (print, what) = line.split_once("  ").expect("a line is `fingerprint  case/file`");
            (what.to_owned(), print.to_owned())
        })
        .collect();
    let differing: std::collections::BTreeSet<&String> =
        recorded.keys().chain(now.keys()).filter(|k| recorded.get(*k) != now.get(*k)).collect();
    assert!(differing.is_empty(), "outputs differ from the recorded ones: {differing:?}");
}
