//! `ubf sweep`: the summary does not depend on the number of jobs, every run
//! leaves a report, and bad arguments are refused.

use std::path::Path;
use std::process::{Command, Output};

fn ubf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ubf")).args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap()
}

/// The test sweep (two scenarios, seeds 3..=14) into `out`, with `extra`
/// arguments.
fn sweep_with(out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "sweep",
        "scenarios/corridor-box.ron",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "3..=14",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    ubf(&args)
}

fn sweep(out: &Path, jobs: &str) -> Output {
    sweep_with(out, &["--jobs", jobs])
}

#[test]
fn the_summary_is_byte_identical_whatever_the_number_of_jobs() {
    let dir = tempfile::tempdir().unwrap();
    let one = dir.path().join("one");
    let three = dir.path().join("three");
    let a = sweep(&one, "1");
    let b = sweep(&three, "3");
    assert!(a.status.success() && b.status.success(), "{}", String::from_utf8_lossy(&a.stderr));
    // Not a terminal: no progress bar, nothing on stderr.
    assert!(a.stderr.is_empty(), "{}", String::from_utf8_lossy(&a.stderr));
    for file in ["summary.csv", "summary.json"] {
        let x = std::fs::read(one.join(file)).unwrap();
        let y = std::fs::read(three.join(file)).unwrap();
        assert!(x == y, "{file} differs between 1 and 3 jobs");
    }
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(one.join("summary.json")).unwrap()).unwrap();
    let boxes = &summary["scenarios"]["corridor-box"];
    assert_eq!(boxes["runs"], 12);
    assert_eq!(boxes["fields"]["collisions"]["mean"], 0.0);
    assert_eq!(boxes["fields"]["reached_goal"]["mean"], 1.0);
    let distance = &boxes["fields"]["distance_m"];
    let (lo, mean, hi) = (
        distance["ci95"][0].as_f64().unwrap(),
        distance["mean"].as_f64().unwrap(),
        distance["ci95"][1].as_f64().unwrap(),
    );
    assert!(lo < mean && mean < hi);
    for seed in 3..=14 {
        assert!(one.join(format!("corridor-box/seed-{seed}/report.json")).exists());
    }
    assert!(!one.join("corridor-box/seed-15").exists());
}

#[test]
fn bad_seed_ranges_are_refused() {
    for seeds in ["5..5", "x..3", "3..-1", "9..2"] {
        let out = ubf(&["sweep", "scenarios/goto-open-floor.ron", "--seeds", seeds, "--out", "unused"]);
        assert_eq!(out.status.code(), Some(2), "{seeds}");
    }
    assert!(!Path::new(env!("CARGO_MANIFEST_DIR")).join("unused").exists());
}

#[test]
fn a_sweep_never_leaves_old_runs_beside_a_new_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out_arg = out.to_str().unwrap();
    let first = ubf(&["sweep", "scenarios/corridor-box.ron", "--seeds", "0..2", "--out", out_arg]);
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    assert!(out.join("corridor-box").is_dir());
    // Into the same directory: refused, nothing touched.
    let again = ubf(&["sweep", "scenarios/goto-open-floor.ron", "--seeds", "0..2", "--out", out_arg]);
    assert_eq!(again.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&again.stderr).contains("--overwrite"),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    assert!(out.join("corridor-box").is_dir());
    // With --overwrite the earlier sweep's output is replaced, not mixed in.
    let replaced = ubf(&["sweep", "scenarios/goto-open-floor.ron", "--seeds", "0..2", "--out", out_arg, "--overwrite"]);
    assert!(replaced.status.success(), "{}", String::from_utf8_lossy(&replaced.stderr));
    assert!(!out.join("corridor-box").exists());
    assert!(out.join("goto-open-floor").is_dir());
    // A directory that is not a sweep's output is never deleted.
    let other = dir.path().join("photos");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("holiday.jpg"), b"not a sweep").unwrap();
    let refused = ubf(&[
        "sweep",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "0..2",
        "--out",
        other.to_str().unwrap(),
        "--overwrite",
    ]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(other.join("holiday.jpg").is_file());
}

fn shard(out: &Path, shard: &str) -> Output {
    sweep_with(out, &["--shard", shard])
}

#[test]
fn shards_merged_give_the_same_summary_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    assert!(sweep(&whole, "2").status.success());
    // Shards in their own directories (machines without a shared disk)…
    let parts: Vec<_> = (0..5).map(|k| dir.path().join(format!("part-{k}"))).collect();
    for (k, part) in parts.iter().enumerate() {
        let out = shard(part, &format!("{k}/5"));
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        assert!(part.join(format!("shard-{k}-of-5.json")).is_file() && !part.join("summary.json").exists());
    }
    let merged = dir.path().join("merged");
    let mut args = vec!["sweep", "merge"];
    args.extend(parts.iter().map(|p| p.to_str().unwrap()));
    args.extend(["--out", merged.to_str().unwrap()]);
    let out = ubf(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // …or all in one, merged in place.
    let shared = dir.path().join("shared");
    for k in 0..3 {
        assert!(shard(&shared, &format!("{k}/3")).status.success());
    }
    let rerun = shard(&shared, "1/3");
    assert_eq!(rerun.status.code(), Some(2), "a shard run twice is refused without --overwrite");
    assert!(ubf(&["sweep", "merge", shared.to_str().unwrap()]).status.success());
    for file in ["summary.csv", "summary.json"] {
        let expected = std::fs::read(whole.join(file)).unwrap();
        assert!(std::fs::read(merged.join(file)).unwrap() == expected, "{file}: 5 shards differ from one sweep");
        assert!(std::fs::read(shared.join(file)).unwrap() == expected, "{file}: 3 shards differ from one sweep");
    }
    // A missing shard, or one from another sweep, is named, not guessed.
    let out = ubf(&["sweep", "merge", parts[0].to_str().unwrap(), parts[2].to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing shards: 1/5, 3/5, 4/5"));
    let out = ubf(&["sweep", "merge", parts[0].to_str().unwrap(), shared.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("belongs to another sweep"));
    let out = ubf(&["sweep", "scenarios/goto-open-floor.ron", "--seeds", "0..3", "--out", "unused", "--shard", "3/3"]);
    assert_eq!(out.status.code(), Some(2));
}

/// A report without its wall-clock time, the one field that differs
/// between two runs of the same scenario and seed.
fn report_without_wall_time(path: &Path) -> serde_json::Value {
    let mut report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    report.as_object_mut().unwrap().remove("wall_time_s");
    report
}

#[test]
fn layout_seeds_redraw_the_landmarks_as_the_scenario_file_would() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("layouts");
    let route = "lab/scenarios/thesis/route-1-2.ron";
    let sweep = ubf(&["sweep", route, "--seeds", "0", "--layout-seeds", "2121,2222", "--out", out.to_str().unwrap()]);
    assert!(sweep.status.success(), "{}", String::from_utf8_lossy(&sweep.stderr));
    // The same run with the layout's seed written into the file.
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(route)).unwrap();
    let edited = dir.path().join("route-1-2.ron");
    std::fs::write(&edited, text.replace("seed: 12)", "seed: 2222)")).unwrap();
    let by_file = dir.path().join("by-file");
    let sweep = ubf(&["sweep", edited.to_str().unwrap(), "--seeds", "0", "--out", by_file.to_str().unwrap()]);
    assert!(sweep.status.success(), "{}", String::from_utf8_lossy(&sweep.stderr));

    let report = |dir: &Path, label: &str| report_without_wall_time(&dir.join(label).join("seed-0/report.json"));
    assert_eq!(report(&out, "route-1-2@2222"), report(&by_file, "route-1-2"));
    assert_ne!(report(&out, "route-1-2@2121"), report(&out, "route-1-2@2222"));
}

#[test]
fn layout_seeds_are_refused_where_nothing_can_be_redrawn() {
    let cases = [
        ("scenarios/goto-open-floor.ron", "5", "scenarios/goto-open-floor.ron: --layout-seeds redraws"),
        ("lab/scenarios/thesis/route-1-2.ron", "5,3..7", "layout seed 5 is listed twice"),
        ("lab/scenarios/thesis/route-1-2.ron", "5,x", "`x` is not a seed"),
    ];
    for (file, layouts, message) in cases {
        let out = ubf(&["sweep", file, "--seeds", "0", "--layout-seeds", layouts, "--out", "unused"]);
        assert_eq!(out.status.code(), Some(2), "{layouts}");
        assert!(String::from_utf8_lossy(&out.stderr).contains(message), "{}", String::from_utf8_lossy(&out.stderr));
    }
    assert!(!Path::new(env!("CARGO_MANIFEST_DIR")).join("unused").exists());
}
