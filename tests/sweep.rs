//! `ubf sweep`: the summary does not depend on the number of jobs, every run
//! leaves a report, and bad arguments are refused.

mod common;

use std::path::Path;
use std::process::{Command, Output};

fn ubf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ubf")).args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap()
}

/// The test sweep (two scenarios, seeds 3..=14) into `out`, with `extra`
/// arguments.
fn sweep_with(out: &Path, extra: &[&str]) -> Output {
    ubf(&common::sweep_args(out, extra))
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

/// Every file under `dir` by its path in `dir`, with each report's
/// `wall_time_s` line (the one thing two runs of a seed differ in) blanked.
fn tree(dir: &Path) -> std::collections::BTreeMap<std::path::PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, files: &mut std::collections::BTreeMap<std::path::PathBuf, Vec<u8>>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(root, &path, files);
                continue;
            }
            let mut bytes = std::fs::read(&path).unwrap();
            if path.file_name().unwrap() == "report.json" {
                let text = String::from_utf8(bytes).unwrap();
                let kept: Vec<&str> = text.lines().filter(|l| !l.trim_start().starts_with("\"wall_time_s\"")).collect();
                assert!(kept.len() + 1 == text.lines().count(), "{}: one wall time", path.display());
                bytes = kept.join("\n").into_bytes();
            }
            files.insert(path.strip_prefix(root).unwrap().to_owned(), bytes);
        }
    }
    let mut files = std::collections::BTreeMap::new();
    walk(dir, dir, &mut files);
    files
}

/// Asserts `a` and `b` hold the same files with the same bytes (reports'
/// wall times aside).
fn assert_same_tree(a: &Path, b: &Path) {
    let (x, y) = (tree(a), tree(b));
    assert_eq!(x.keys().collect::<Vec<_>>(), y.keys().collect::<Vec<_>>(), "the same files");
    for (path, bytes) in &x {
        assert!(*bytes == y[path], "{} differs", path.display());
    }
}

/// The finished runs' folders (`LABEL/seed-N`) under `out`.
fn seed_folders(out: &Path) -> Vec<std::path::PathBuf> {
    let Ok(labels) = std::fs::read_dir(out) else { return Vec::new() };
    let mut found = Vec::new();
    for label in labels.flatten().filter(|e| e.path().is_dir()) {
        for seed in std::fs::read_dir(label.path()).into_iter().flatten().flatten() {
            if seed.file_name().to_string_lossy().starts_with("seed-") {
                found.push(seed.path());
            }
        }
    }
    found
}

/// The test sweep with trajectories (eight runs of about a second each
/// unoptimised) into `out`, started and sent `signal` once two runs have
/// finished; its output once it has ended.
fn interrupted_sweep(out: &Path, signal: &str, extra: &[&str]) -> Output {
    let mut args = vec![
        "sweep",
        "scenarios/corridor-box.ron",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "0..4",
        "--jobs",
        "1",
        "--trajectories",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    let child = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(&args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while seed_folders(out).len() < 2 && started.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let sent = Command::new("kill").args([signal, &child.id().to_string()]).status().unwrap();
    assert!(sent.success());
    child.wait_with_output().unwrap()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn an_interrupted_sweep_resumes_to_the_bytes_of_an_uninterrupted_one() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("interrupted");
    let stopped = interrupted_sweep(&out, "-INT", &[]);
    assert_eq!(stopped.status.code(), Some(130), "{}", text(&stopped.stderr));
    assert!(text(&stopped.stderr).contains("--resume"), "{}", text(&stopped.stderr));
    // Stopped midway, with nothing half-done: no summary, and every run's
    // folder whole.
    let finished = seed_folders(&out);
    assert!((2..8).contains(&finished.len()), "{finished:?}");
    assert!(!out.join("summary.json").exists() && !out.join("summary.csv").exists());
    for folder in &finished {
        for file in ["report.json", "trajectory.csv", "run.mcap", "plot.png"] {
            assert!(folder.join(file).is_file(), "{}: no {file}", folder.display());
        }
    }
    // Resuming with other seeds is another sweep: refused, nothing touched.
    let other = ubf(&[
        "sweep",
        "scenarios/corridor-box.ron",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "0..5",
        "--trajectories",
        "--out",
        out.to_str().unwrap(),
        "--resume",
    ]);
    assert_eq!(other.status.code(), Some(2), "{}", text(&other.stderr));
    assert_eq!(seed_folders(&out).len(), finished.len());
    let resumed = ubf(&[
        "sweep",
        "scenarios/corridor-box.ron",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "0..4",
        "--jobs",
        "2",
        "--trajectories",
        "--out",
        out.to_str().unwrap(),
        "--resume",
    ]);
    assert!(resumed.status.success(), "{}", text(&resumed.stderr));
    let fresh = dir.path().join("fresh");
    let whole = ubf(&[
        "sweep",
        "scenarios/corridor-box.ron",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "0..4",
        "--trajectories",
        "--out",
        fresh.to_str().unwrap(),
    ]);
    assert!(whole.status.success(), "{}", text(&whole.stderr));
    assert_same_tree(&out, &fresh);
    // A finished sweep resumed again runs nothing and changes nothing.
    let again = ubf(&[
        "sweep",
        "scenarios/corridor-box.ron",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "0..4",
        "--trajectories",
        "--out",
        out.to_str().unwrap(),
        "--resume",
    ]);
    assert!(again.status.success(), "{}", text(&again.stderr));
    assert_same_tree(&out, &fresh);
}

#[test]
fn a_sweep_stopped_by_sigterm_can_be_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let stopped = interrupted_sweep(&out, "-TERM", &[]);
    assert_eq!(stopped.status.code(), Some(130), "{}", text(&stopped.stderr));
    let replaced = ubf(&[
        "sweep",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "0..2",
        "--out",
        out.to_str().unwrap(),
        "--overwrite",
    ]);
    assert!(replaced.status.success(), "{}", text(&replaced.stderr));
    assert!(!out.join("corridor-box").exists() && out.join("summary.json").is_file());
}

#[test]
fn a_killed_sweep_leaves_only_whole_runs_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("killed");
    let killed = interrupted_sweep(&out, "-KILL", &[]);
    assert_eq!(killed.status.code(), None, "killed by a signal");
    // A run's folder appears only whole, with its report.
    let finished = seed_folders(&out);
    assert!(!finished.is_empty());
    for folder in &finished {
        for file in ["report.json", "trajectory.csv", "run.mcap", "plot.png"] {
            assert!(folder.join(file).is_file(), "{}: no {file}", folder.display());
        }
    }
    let resumed = ubf(&[
        "sweep",
        "scenarios/corridor-box.ron",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "0..4",
        "--trajectories",
        "--out",
        out.to_str().unwrap(),
        "--resume",
    ]);
    assert!(resumed.status.success(), "{}", text(&resumed.stderr));
    let fresh = dir.path().join("fresh");
    let whole = ubf(&[
        "sweep",
        "scenarios/corridor-box.ron",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "0..4",
        "--trajectories",
        "--out",
        fresh.to_str().unwrap(),
    ]);
    assert!(whole.status.success(), "{}", text(&whole.stderr));
    assert_same_tree(&out, &fresh);
}

/// `ubf` with `args` under a file size limit of `blocks` (of 512 or 1024
/// bytes, as the shell counts them), its SIGXFSZ ignored so that a write
/// over the limit fails as a full disk's does. Root ignores a read-only
/// folder; nobody ignores this limit.
fn ubf_with_file_limit(blocks: u32, args: &[&str]) -> Output {
    let script = format!("trap '' XFSZ; ulimit -f {blocks}; exec \"$0\" \"$@\"");
    Command::new("sh")
        .arg("-c")
        .arg(script)
        .arg(env!("CARGO_BIN_EXE_ubf"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

/// Every file under `dir`, with its length.
fn files_and_lengths(dir: &Path) -> Vec<(std::path::PathBuf, u64)> {
    fn walk(dir: &Path, found: &mut Vec<(std::path::PathBuf, u64)>) {
        for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
            let path = entry.path();
            match path.is_dir() {
                true => walk(&path, found),
                false => found.push((path.clone(), std::fs::metadata(&path).unwrap().len())),
            }
        }
    }
    let mut found = Vec::new();
    walk(dir, &mut found);
    found
}

#[test]
fn a_failing_write_ends_the_sweep_naming_the_file_and_leaves_nothing_half_written() {
    let dir = tempfile::tempdir().unwrap();
    // Nothing can be written at all: the first file is named, no empty
    // file is left behind.
    let out = dir.path().join("nothing");
    let args = ["sweep", "scenarios/corridor-box.ron", "--seeds", "0..3", "--out", out.to_str().unwrap()];
    let result = ubf_with_file_limit(0, &args);
    assert_eq!(result.status.code(), Some(1), "{}", text(&result.stderr));
    assert!(text(&result.stderr).contains(&out.display().to_string()), "{}", text(&result.stderr));
    assert!(text(&result.stderr).contains("File too large"), "{}", text(&result.stderr));
    for (path, length) in files_and_lengths(&out) {
        assert!(length > 0, "{} is empty", path.display());
    }
    // Reports fit, the summary does not: no summary, and none cut short;
    // the sweep finishes once there is room.
    let out = dir.path().join("no-room-for-the-summary");
    let args = [
        "sweep",
        "scenarios/corridor-box.ron",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "0..3",
        "--out",
        out.to_str().unwrap(),
    ];
    let result = ubf_with_file_limit(2, &args);
    assert_eq!(result.status.code(), Some(1), "{}", text(&result.stderr));
    assert!(text(&result.stderr).contains("summary.csv: File too large"), "{}", text(&result.stderr));
    assert!(!out.join("summary.csv").exists() && !out.join("summary.json").exists());
    let mut resumed = args.to_vec();
    resumed.push("--resume");
    let result = ubf(&resumed);
    assert!(result.status.success(), "{}", text(&result.stderr));
    assert!(out.join("summary.json").is_file());
    // A run's log over the limit: the sweep stops at it, named, and leaves
    // no run's folder without its report.
    let out = dir.path().join("no-room-for-a-log");
    let args =
        ["sweep", "scenarios/corridor-box.ron", "--seeds", "0..3", "--trajectories", "--out", out.to_str().unwrap()];
    let result = ubf_with_file_limit(200, &args);
    assert_eq!(result.status.code(), Some(1), "{}", text(&result.stderr));
    assert!(text(&result.stderr).contains("File too large"), "{}", text(&result.stderr));
    assert!(!out.join("summary.json").exists());
    for folder in seed_folders(&out) {
        assert!(folder.join("report.json").is_file(), "{} has no report", folder.display());
    }
    for (path, length) in files_and_lengths(&out) {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        assert!(length > 0 && !name.ends_with(".partial"), "{} ({length} bytes) left", path.display());
    }
    // A file where the sweep's folder must go.
    let blocked = dir.path().join("blocked");
    std::fs::write(&blocked, b"a file").unwrap();
    let out = blocked.join("out");
    let result = ubf(&["sweep", "scenarios/corridor-box.ron", "--seeds", "0..2", "--out", out.to_str().unwrap()]);
    assert_eq!(result.status.code(), Some(1), "{}", text(&result.stderr));
    assert!(text(&result.stderr).contains(&out.display().to_string()), "{}", text(&result.stderr));
}

#[test]
fn crafted_shard_records_are_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let shards = dir.path().join("shards");
    let outside = dir.path().join("escape/seed-0");
    std::fs::create_dir_all(&shards).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    // A report outside the shard folder that a label `../escape` reaches.
    let report = r#"{"scenario": "x", "seed": 0, "distance_m": 1.0}"#;
    std::fs::write(outside.join("report.json"), report).unwrap();
    let cases = [
        (r#"{"shard": {"index": 0, "count": 0}, "seeds": [0, 1], "labels": ["a"], "failed": []}"#, "0 ≤ K < N"),
        (r#"{"shard": {"index": 7, "count": 2}, "seeds": [0, 1], "labels": ["a"], "failed": []}"#, "0 ≤ K < N"),
        (
            r#"{"shard": {"index": 0, "count": 4611686018427387904}, "seeds": [0, 1], "labels": ["a"], "failed": []}"#,
            "missing shards: 1/4611686018427387904",
        ),
        (
            r#"{"shard": {"index": 0, "count": 1}, "seeds": [0, 4611686018427387904], "labels": ["a", "b", "c", "d", "e"], "failed": []}"#,
            "too many runs",
        ),
        (
            r#"{"shard": {"index": 0, "count": 1}, "seeds": [0, 1099511627776], "labels": ["a"], "failed": []}"#,
            "a/seed-0/report.json",
        ),
        (r#"{"shard": {"index": 0, "count": 1}, "seeds": [5, 2], "labels": ["a"], "failed": []}"#, "hold no seed"),
        (
            r#"{"shard": {"index": 0, "count": 1}, "seeds": [0, 1], "labels": ["../escape"], "failed": []}"#,
            "cannot name a folder",
        ),
        (r#"{"shard": {"index": 0, "count": 1}, "seeds": [0, 1], "labels": ["a", "a"], "failed": []}"#, "listed twice"),
        (
            r#"{"shard": {"index": 0, "count": 2}, "seeds": [0, 2], "labels": ["a"], "failed": [["a", 1, "no"]]}"#,
            "not one of this shard's runs",
        ),
    ];
    for (record, says) in cases {
        let path = shards.join("shard-0-of-1.json");
        std::fs::write(&path, record).unwrap();
        let out = dir.path().join("merged");
        let result = ubf(&["sweep", "merge", shards.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        let stderr = text(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{record}: {stderr}");
        assert!(stderr.contains(says), "{record}: {stderr}");
        assert!(!stderr.contains("panicked"), "{record}: {stderr}");
        if !says.starts_with("missing") {
            assert!(stderr.contains(&shards.display().to_string()), "{record}: names the file: {stderr}");
        }
        assert!(!out.exists(), "{record}: nothing written");
        std::fs::remove_file(&path).unwrap();
    }
    assert!(!dir.path().join("summary.json").exists());
}

#[test]
fn a_scenario_whose_name_is_no_folder_name_is_refused_and_nothing_is_written_outside_out() {
    let dir = tempfile::tempdir().unwrap();
    let deep = dir.path().join("a/b");
    std::fs::create_dir_all(&deep).unwrap();
    let scenario = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/goto-open-floor.ron")).unwrap();
    for name in ["...ron", "..ron", ".ron", "summary.json.ron"] {
        let file = deep.join(name);
        std::fs::write(&file, &scenario).unwrap();
        let out = deep.join("out");
        let result = ubf(&["sweep", file.to_str().unwrap(), "--seeds", "1", "--out", out.to_str().unwrap()]);
        let stderr = text(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{name}: {stderr}");
        assert!(stderr.contains("rename the file") && stderr.contains(name), "{name}: {stderr}");
        assert!(!out.exists(), "{name}: nothing written");
        std::fs::remove_file(&file).unwrap();
    }
    let left: Vec<_> = files_and_lengths(dir.path());
    assert!(left.is_empty(), "{left:?}");
    assert!(!dir.path().join("a/seed-1").exists() && !deep.join("seed-1").exists());
}

#[test]
fn a_warning_every_run_gives_is_said_once_a_sweep() {
    // The steered camera's scenario without its camera: every run's aid
    // warns that it has nothing to aid with.
    let original =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/steered-camera.ron")).unwrap();
    let (from, to) = (original.find("        camera: (").unwrap(), original.find("        egomotion:").unwrap());
    let blind = format!(
        "{}{}",
        &original[..from],
        &original[to..].replacen("        egomotion: (estimator: Rigid()),\n", "", 1)
    );
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("blind.ron");
    std::fs::write(&file, blind).unwrap();
    let out = dir.path().join("sweep");
    let run = ubf(&["sweep", file.to_str().unwrap(), "--seeds", "1..6", "--out", out.to_str().unwrap()]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let said = text(&run.stderr);
    assert_eq!(said.matches("no stereo frame").count(), 1, "{said}");
    assert!(said.contains("held back 4 warnings said already"), "{said}");
    // Asked for more, every one.
    let verbose =
        ubf(&["-v", "sweep", file.to_str().unwrap(), "--seeds", "1..6", "--out", out.to_str().unwrap(), "--overwrite"]);
    assert!(verbose.status.success(), "{}", text(&verbose.stderr));
    assert_eq!(text(&verbose.stderr).matches("no stereo frame").count(), 5);
}
