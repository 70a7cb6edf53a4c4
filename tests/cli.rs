//! The `ubf` binary end to end: runs, checks, and every kind of bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn ubf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ubf")).args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A scenario file with `body` in a fresh temporary directory.
fn scenario_file(dir: &tempfile::TempDir, body: &str) -> PathBuf {
    let path = dir.path().join("bad.ron");
    std::fs::write(&path, body).unwrap();
    path
}

const GOOD: &str = r#"Scenario(
    name: "t",
    max_time_s: 30.0,
    goal: (x: 3.0, y: 0.0),
    root: Composite(
        arbiter: HighestPriority,
        children: [
            (behavior: Stop(), weight: 2.0),
            (behavior: GoTo(cruise_speed: 0.5)),
        ],
    ),
)"#;

/// Runs `ubf check` on `body` and returns (exit code, stderr).
fn check(body: &str) -> (i32, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = scenario_file(&dir, body);
    let out = ubf(&["check", path.to_str().unwrap()]);
    (out.status.code().unwrap(), text(&out.stderr).replace(path.to_str().unwrap(), "FILE"))
}

#[test]
fn every_shipped_scenario_checks() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<String> = Vec::new();
    for dir in [root.join("scenarios"), root.join("lab/scenarios/thesis")] {
        files.extend(
            std::fs::read_dir(dir)
                .unwrap()
                .map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|e| e == "ron"))
                .map(|p| p.to_string_lossy().into_owned()),
        );
    }
    assert!(files.iter().any(|f| f.contains("thesis/table4.ron")));
    assert!(!files.is_empty());
    let args: Vec<&str> = std::iter::once("check").chain(files.iter().map(String::as_str)).collect();
    let out = ubf(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

#[test]
fn the_good_scenario_checks() {
    assert_eq!(check(GOOD), (0, String::new()));
}

#[test]
fn malformed_file_gives_file_line_column_and_exit_2() {
    let (code, err) = check("Scenario(\n    name: \"t\",\n    max_time_s 30.0,\n)");
    assert_eq!(code, 2);
    assert!(err.starts_with("error: FILE:3:15: Expected colon"), "{err}");
}

#[test]
fn a_missing_file_says_where_it_was_looked_for() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["run", "scenarios/goto-open-floor.ron"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let cwd = dir.path().canonicalize().unwrap();
    let expected = format!("scenarios/goto-open-floor.ron: not found in the working directory {}", cwd.display());
    assert!(text(&out.stderr).contains(&expected), "{}", text(&out.stderr));
}

#[test]
fn a_file_that_is_no_regular_file_is_refused_not_read() {
    // A FIFO would block the reader until a writer came; /dev/zero would
    // never end.
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("scenario.ron");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    for file in [fifo.to_str().unwrap(), "/dev/zero"] {
        for command in ["check", "run"] {
            let out = ubf(&[command, file]);
            assert_eq!(out.status.code(), Some(2), "{command} {file}");
            assert!(text(&out.stderr).contains(&format!("{file}: not a regular file")), "{}", text(&out.stderr));
        }
    }
}

#[test]
fn a_bad_ros_domain_id_is_bad_input_before_anything_runs() {
    for args in
        [&["run", "scenarios/corridor-box.ron", "--ros2"][..], &["simulate", "scenarios/corridor-box.ron", "--ros2"]]
    {
        let out = Command::new(env!("CARGO_BIN_EXE_ubf"))
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env("ROS_DOMAIN_ID", "abc")
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", text(&out.stderr));
        assert!(text(&out.stderr).contains("ROS_DOMAIN_ID is `abc`"), "{}", text(&out.stderr));
    }
}

#[test]
fn a_plot_that_is_no_png_is_refused_before_any_work() {
    for args in [&["replay", "out.mcap", "--plot", "plot.txt"][..], &["pipeline", "frames", "--plot", "plot"]] {
        let out = ubf(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(text(&out.stderr).contains("is not a FILE.png"), "{}", text(&out.stderr));
    }
}

#[test]
fn unknown_field_is_named_with_its_position() {
    let (code, err) = check(&GOOD.replace("cruise_speed: 0.5", "cruise_sped: 0.5"));
    assert_eq!(code, 2);
    assert!(err.starts_with("error: FILE:9:29: "), "{err}");
    assert!(err.contains("cruise_sped"), "{err}");
}

#[test]
fn unknown_scenario_field_is_refused() {
    let (code, err) = check(&GOOD.replace("max_time_s: 30.0,", "max_time_s: 30.0, speed_up: 2,"));
    assert_eq!(code, 2);
    assert!(err.contains("FILE:3:") && err.contains("speed_up"), "{err}");
}

#[test]
fn an_unknown_odometry_fusion_names_the_ones_there_are() {
    let body = r#"Scenario(name: "t", max_time_s: 1.0,
    robot: (camera: (), egomotion: (odometry_fusion: Half)),
    root: Stop())"#;
    let (code, err) = check(body);
    assert_eq!(code, 2);
    assert!(err.contains("FILE:2:") && err.contains("`Sideways`") && err.contains("`Full`"), "{err}");
    let (code, err) = check(&body.replace("Half", "Sideways"));
    assert_eq!(code, 0, "{err}");
}

#[test]
fn unknown_behaviour_is_named() {
    let (code, err) = check(&GOOD.replace("GoTo(", "Wander("));
    assert_eq!(code, 2);
    assert!(err.contains("FILE:9:") && err.contains("unknown behaviour `Wander`"), "{err}");
}

#[test]
fn nan_and_negative_values_are_refused_where_they_make_no_sense() {
    for (from, to, says) in [
        ("max_time_s: 30.0", "max_time_s: NaN", "NaN is out of range"),
        ("max_time_s: 30.0", "max_time_s: -5.0", "-5 is out of range"),
        ("goal: (x: 3.0, y: 0.0)", "goal: (x: 3.0, y: 0.0, tolerance: -0.1)", "-0.1 is out of range"),
        ("weight: 2.0", "weight: -2.0", "-2 is out of range"),
        ("cruise_speed: 0.5", "cruise_speed: inf", "inf is out of range"),
        // Half a percent written as a percentage, not a fraction.
        (
            "max_time_s: 30.0,",
            "max_time_s: 30.0, robot: (egomotion: (odometry_gate: (noise: (scale_sigma: 0.5)))),",
            "0.5 is out of range: must be a fraction from 0 to 0.2",
        ),
    ] {
        let (code, err) = check(&GOOD.replace(from, to));
        assert_eq!(code, 2, "{to}");
        assert!(err.starts_with("error: FILE:") && err.contains(says), "{to}: {err}");
    }
}

#[test]
fn missing_file_and_bad_arguments_exit_2_without_panicking() {
    let out = ubf(&["check", "no/such/file.ron"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("no/such/file.ron"));
    for args in [&["run", "scenarios/goto-open-floor.ron", "--seed", "minus-one"][..], &["fly"], &["run"]] {
        let out = ubf(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(!text(&out.stderr).contains("panicked"), "{args:?}");
    }
}

#[test]
fn every_error_a_user_can_cause_reads_as_one_sentence_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let at = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let unwritable = "/proc/ubf-cannot-write-here";
    std::fs::write(at("not-ron.ron"), "Scenario(").unwrap();
    std::fs::write(at("empty.mcap"), "").unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["run".into(), at("nope.ron")], "nope.ron"),
        (vec!["check".into(), dir.path().to_str().unwrap().into()], dir.path().to_str().unwrap()),
        (vec!["check".into(), at("not-ron.ron")], "not-ron.ron:"),
        (vec!["replay".into(), at("nope.mcap")], "nope.mcap"),
        (vec!["replay".into(), at("empty.mcap")], "empty.mcap"),
        (vec!["tree".into(), at("nope.ron")], "nope.ron"),
        (vec!["drive".into(), at("nope.ron")], "nope.ron"),
        (vec!["pipeline".into(), at("nowhere")], "nowhere"),
        (vec!["sweep".into(), "merge".into(), at("nowhere")], "nowhere"),
        (vec!["run".into(), "scenarios/goto-open-floor.ron".into(), "--out".into(), unwritable.into()], unwritable),
        (vec!["model".into(), "heatmap".into(), "--out".into(), format!("{unwritable}/m.png")], unwritable),
        (
            vec!["frames".into(), "scenarios/rendered-corridor.ron".into(), "--out".into(), unwritable.into()],
            unwritable,
        ),
    ];
    for (args, names) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = ubf(&args);
        let said = text(&out.stderr);
        assert!(matches!(out.status.code(), Some(1 | 2)), "{args:?}: {:?}\n{said}", out.status);
        assert!(said.starts_with("error: ") && said.contains(names), "{args:?}:\n{said}");
        // Rust's debug text and panics are for developers, not for users.
        for debug in ["Os {", "kind:", "Error(", "Error {", "panicked", "RUST_BACKTRACE", "\\n"] {
            assert!(!said.contains(debug), "{args:?} says `{debug}`:\n{said}");
        }
    }
}

#[test]
fn run_reaches_the_goal_and_prints_json() {
    let out = ubf(&["run", "scenarios/goto-open-floor.ron", "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["reached_goal"], true);
    assert_eq!(report["end"], "goal_reached");
    let distance = report["distance_m"].as_f64().unwrap();
    // The straight line is √(8² + 3²) = 8.54 m less the 0.2 m tolerance.
    assert!(distance > 8.3 && distance < 9.5, "{distance}");
}

#[test]
fn same_scenario_and_seed_give_identical_reports() {
    let strip = |out: Output| {
        let mut v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        v.as_object_mut().unwrap().remove("wall_time_s");
        v.to_string()
    };
    let a = strip(ubf(&["run", "scenarios/goto-open-floor.ron", "--json", "--seed", "5"]));
    let b = strip(ubf(&["run", "scenarios/goto-open-floor.ron", "--json", "--seed", "5"]));
    assert_eq!(a, b);
}

#[test]
fn every_command_that_writes_a_folder_refuses_a_full_one_unless_told_to_overwrite() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out_arg = out.to_str().unwrap();
    let run = |extra: &[&str]| ubf(&[&["run", "scenarios/goto-open-floor.ron", "--out", out_arg], extra].concat());
    assert!(run(&[]).status.success());
    let report = std::fs::read(out.join("report.json")).unwrap();
    // Again into the same folder: refused, with what to do, nothing touched.
    let again = run(&["--seed", "9"]);
    assert_eq!(again.status.code(), Some(2));
    let said = text(&again.stderr);
    assert!(said.contains("is not empty") && said.contains("--overwrite"), "{said}");
    assert_eq!(std::fs::read(out.join("report.json")).unwrap(), report);
    // Nor with --overwrite while the folder holds anything a run does not
    // write: here, the scenario the run reads.
    let scenario = out.join("mine.ron");
    std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/goto-open-floor.ron"), &scenario).unwrap();
    let mine = ubf(&["run", scenario.to_str().unwrap(), "--out", out_arg, "--overwrite"]);
    assert_eq!(mine.status.code(), Some(2));
    assert!(text(&mine.stderr).contains("mine.ron, which `ubf run` does not write"), "{}", text(&mine.stderr));
    assert!(scenario.is_file() && out.join("report.json").is_file());
    std::fs::remove_file(&scenario).unwrap();
    // With --overwrite the earlier run is replaced.
    assert!(run(&["--seed", "9", "--overwrite"]).status.success());
    assert_ne!(std::fs::read(out.join("report.json")).unwrap(), report);
    // A run never takes a recording's folder, nor a recording a run's.
    let frames = |extra: &[&str]| {
        ubf(&[&["frames", "scenarios/rendered-corridor.ron", "--out", out_arg, "--max-frames", "1"], extra].concat())
    };
    let refused = frames(&["--overwrite"]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(text(&refused.stderr).contains("not deleting it"), "{}", text(&refused.stderr));
    assert!(out.join("report.json").is_file());
    std::fs::remove_dir_all(&out).unwrap();
    assert!(frames(&[]).status.success());
    assert_eq!(frames(&[]).status.code(), Some(2));
    assert!(frames(&["--overwrite"]).status.success());
    assert_eq!(run(&["--overwrite"]).status.code(), Some(2));
}

#[test]
fn ubf_new_writes_the_crate_the_workspace_builds_and_tests() {
    // examples/my-behaviours is what `ubf new` writes, built and tested by
    // this suite as a workspace member; here `ubf new` must write the same
    // sources, and a Cargo.toml that Cargo resolves against this checkout
    // with the versions in its Cargo.lock, offline.
    let dir = tempfile::tempdir().unwrap();
    let crate_dir = dir.path().join("my-behaviours");
    let out = ubf(&["new", crate_dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/my-behaviours");
    for file in ["src/main.rs", "tests/scenario.rs", "my-behaviours.ron", ".gitignore"] {
        assert_eq!(
            std::fs::read_to_string(crate_dir.join(file)).unwrap(),
            std::fs::read_to_string(example.join(file)).unwrap(),
            "{file}: `ubf new` and examples/my-behaviours differ"
        );
    }
    let manifest = std::fs::read_to_string(crate_dir.join("Cargo.toml")).unwrap();
    assert!(manifest.contains("[profile.dev.package.\"*\"]\nopt-level = 3"), "{manifest}");
    let tree = Command::new(env!("CARGO"))
        .args(["tree", "--offline", "--depth", "1", "--prefix", "none", "-e", "normal", "--manifest-path"])
        .arg(crate_dir.join("Cargo.toml"))
        .output()
        .unwrap();
    assert!(tree.status.success(), "{}", text(&tree.stderr));
    let checkout = std::fs::canonicalize(env!("CARGO_MANIFEST_DIR")).unwrap();
    let core = format!("ubf-core v0.1.0 ({})", checkout.join("ubf-core").display());
    assert!(text(&tree.stdout).lines().any(|line| line == core), "{}", text(&tree.stdout));
    // Never into a folder that holds anything, nor under a name Cargo refuses.
    let again = ubf(&["new", crate_dir.to_str().unwrap()]);
    assert_eq!(again.status.code(), Some(2));
    assert!(text(&again.stderr).contains("is not empty"), "{}", text(&again.stderr));
    let badly_named = ubf(&["new", dir.path().join("My Behaviours").to_str().unwrap()]);
    assert_eq!(badly_named.status.code(), Some(2));
    assert!(text(&badly_named.stderr).contains("lower-case"), "{}", text(&badly_named.stderr));
}

#[test]
fn the_figures_in_the_docs_are_the_ones_the_code_draws_now() {
    // A change to how figures are drawn shows in review as a changed PNG
    // in docs/figures/: `UBF_RECORD_FIGURES=1` draws them again.
    let dir = tempfile::tempdir().unwrap();
    let run = ubf(&["run", "scenarios/corridor-box.ron", "--out", dir.path().join("run").to_str().unwrap()]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let model = dir.path().join("model.png");
    assert!(ubf(&["model", "heatmap", "--out", model.to_str().unwrap()]).status.success());
    let figures = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/figures");
    for (drawn, shown) in [(dir.path().join("run/plot.png"), "corridor-box.png"), (model, "error-model.png")] {
        let drawn = std::fs::read(drawn).unwrap();
        if std::env::var_os("UBF_RECORD_FIGURES").is_some() {
            std::fs::write(figures.join(shown), &drawn).unwrap();
        }
        assert!(drawn == std::fs::read(figures.join(shown)).unwrap(), "docs/figures/{shown} is not what is drawn now");
    }
}

#[test]
fn the_stock_binary_does_not_know_a_users_behaviour() {
    // Wander is registered by the example crate's own binary, not by ubf.
    let out = ubf(&["check", "examples/wander/wander.ron"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("unknown behaviour `Wander`"));
}

#[test]
fn thesis_table4_prints_the_promised_json() {
    let out = ubf(&["experiment", "thesis-table4", "--seeds", "0..2", "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let runs = v["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 8);
    for technique in ["none", "zigzag", "scan", "tracking"] {
        assert!(v["mean"][technique].as_f64().unwrap() > 0.0, "{technique}");
        assert!(v["improvement_pct"][technique].is_number(), "{technique}");
        assert_eq!(runs.iter().filter(|r| r["technique"] == technique).count(), 2);
    }
    assert_eq!(v["improvement_pct"]["none"], 0.0);
    assert!(runs.iter().all(|r| r["corridor"].is_u64() && r["journey_cv"].is_f64()));
}

#[test]
fn rendered_frames_are_recorded_identically_and_replayed() {
    // Two recordings of the same scenario and seed are byte-identical, and
    // the pipeline finds the corridor's landmarks in them.
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    for out in [&a, &b] {
        let run =
            ubf(&["frames", "scenarios/rendered-corridor.ron", "--out", out.to_str().unwrap(), "--max-frames", "3"]);
        assert!(run.status.success(), "{}", text(&run.stderr));
        assert!(text(&run.stdout).starts_with("3 stereo pairs"), "{}", text(&run.stdout));
    }
    for file in ["frames.csv", "camera.ron", "left/000003.png", "right/000003.png"] {
        assert_eq!(std::fs::read(a.join(file)).unwrap(), std::fs::read(b.join(file)).unwrap(), "{file}");
    }
    let replay = ubf(&["pipeline", a.to_str().unwrap(), "--json"]);
    assert!(replay.status.success(), "{}", text(&replay.stderr));
    let report: serde_json::Value = serde_json::from_slice(&replay.stdout).unwrap();
    assert_eq!(report["frames"], 3);
    assert!(report["landmarks_mean"].as_f64().unwrap() > 10.0, "{report}");
    // A directory that is not one is a clean error.
    let missing = ubf(&["pipeline", dir.path().to_str().unwrap()]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(text(&missing.stderr).contains("frames.csv"), "{}", text(&missing.stderr));
}

#[test]
fn thesis_table2_names_the_outlier_share_that_matches() {
    let out = ubf(&["experiment", "thesis-table2", "--trials", "50", "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["thesis"]["landmarks"], 13);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 21);
    // More gross mismatches, a heavier tail.
    let tail = |k: usize| rows[k]["stats"]["beyond_2_m"].as_f64().unwrap();
    assert!(tail(0) < tail(10) && tail(10) < tail(20), "{} {} {}", tail(0), tail(10), tail(20));
    let best = v["best_outlier_share"].as_f64().unwrap();
    assert!(rows.iter().any(|r| r["outlier_share"].as_f64() == Some(best)));
    // Nonsense is refused, not run.
    let bad = ubf(&["experiment", "thesis-table2", "--step", "-1"]);
    assert_eq!(bad.status.code(), Some(2), "{}", text(&bad.stderr));
}

#[test]
fn where_aiding_pays_maps_every_environment_and_draws_it() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("map.png");
    let png_arg = png.to_str().unwrap();
    let args = ["experiment", "where-aiding-pays", "--seeds", "0..2", "--held-out-seeds", "5..7", "--plot", png_arg];
    let out = ubf(&[&args[..], &["--json"]].concat());
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let cells = v["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 24);
    for c in cells {
        let (ratio, ci) = (c["ratio"].as_f64().unwrap(), c["ratio_ci95"].as_array().unwrap());
        assert!(ratio > 0.0 && ci[0].as_f64().unwrap() <= ratio && ratio <= ci[1].as_f64().unwrap(), "{c}");
        assert!(["zigzag", "scan", "tracking", "camera"].contains(&c["best"].as_str().unwrap()), "{c}");
    }
    // One base cell per factor, all the same environment.
    let base: Vec<_> = cells.iter().filter(|c| c["base"] == true).collect();
    assert_eq!(base.len(), 6);
    assert!(base.iter().all(|c| c["ratio"] == base[0]["ratio"]));
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
}

#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_a_command_quietly() {
    // `ubf run S --json | head -0`: the reader is gone before the report is
    // written. The command ends as Unix filters do (killed by SIGPIPE, no
    // message), not with a panic and exit 101.
    use std::os::unix::process::ExitStatusExt;
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/goto-open-floor.ron");
    // The reading end is closed before the command starts, so its first
    // write finds no reader, however fast it runs.
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["run", scenario.to_str().unwrap(), "--json"])
        .stdout(writer)
        .stderr(std::process::Stdio::piped())
        .output()
        .unwrap();
    assert_eq!(out.status.signal(), Some(13), "{:?}: {}", out.status, text(&out.stderr));
    assert!(out.stderr.is_empty(), "{}", text(&out.stderr));
}

#[test]
fn zero_jobs_and_zero_frames_are_refused() {
    let out = ubf(&["sweep", "scenarios/goto-open-floor.ron", "--seeds", "0..2", "--out", "x", "--jobs", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("at least one job"), "{}", text(&out.stderr));
    // It wrote one pair.
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("frames");
    let out =
        ubf(&["frames", "scenarios/goto-open-floor.ron", "--out", out_dir.to_str().unwrap(), "--max-frames", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("at least 1"), "{}", text(&out.stderr));
    assert!(!out_dir.exists());
}

#[test]
fn a_start_inside_a_wall_is_refused_by_check_and_run() {
    // A corridor runs from x = 0: the default start (0, 0) puts the robot in
    // its end wall, where a run once went 0.36 m with 129 collisions.
    let dir = tempfile::tempdir().unwrap();
    let body = r#"Scenario(name: "wall", max_time_s: 10.0,
        world: (corridor: (width: 4.0, length: 20.0)),
        goal: (x: 10.0, y: 0.0, tolerance: 0.3),
        root: GoTo())"#;
    let path = scenario_file(&dir, body);
    for command in ["check", "run"] {
        let out = ubf(&[command, path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "{command}: {}", text(&out.stderr));
        assert!(text(&out.stderr).contains("robot.start"), "{command}: {}", text(&out.stderr));
    }
    // Where the start is written, the error points at it.
    let written = scenario_file(
        &dir,
        &body.replace("max_time_s: 10.0,", "max_time_s: 10.0,\n    robot: (start: (x: 0.1, y: 0.0)),"),
    );
    let out = ubf(&["check", written.to_str().unwrap()]);
    assert!(text(&out.stderr).contains("bad.ron:2:13: robot.start: at (0.1, 0)"), "{}", text(&out.stderr));
    let moved =
        scenario_file(&dir, &body.replace("max_time_s: 10.0,", "max_time_s: 10.0, robot: (start: (x: 1.0, y: 0.0)),"));
    assert!(ubf(&["check", moved.to_str().unwrap()]).status.success());
}

#[test]
fn a_panicking_behaviour_ends_the_run_with_its_report_or_is_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let body = |policy: &str| {
        format!(
            r#"Scenario(name: "fault", max_time_s: 10.0, goal: (x: 3.0, y: 0.0), {policy}
            root: Composite(arbiter: CommandFusion, children: [
                (behavior: Stop()), (behavior: InjectFault(after_s: 1.0, message: "sensor table empty")),
                (behavior: GoTo(cruise_speed: 0.5))]))"#
        )
    };
    let file = scenario_file(&dir, &body(""));
    let out_dir = dir.path().join("out");
    let out = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["run", file.to_str().unwrap(), "--out", out_dir.to_str().unwrap()])
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("failure         behaviour root/InjectFault panicked: sensor table empty"));
    // Said once, in the run's words, not in Rust's panic message as well.
    assert!(!text(&out.stderr).contains("panicked at"), "{}", text(&out.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["end"], "behavior_failed");
    assert!((report["sim_time_s"].as_f64().unwrap() - 1.0).abs() < 1e-9, "{report}");
    // Skipped, the run carries on without it and reaches the goal.
    let file = scenario_file(&dir, &body("on_behavior_panic: SkipBehavior,"));
    let out = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["run", file.to_str().unwrap(), "--json"])
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap();
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!((report["end"].as_str(), report["reached_goal"].as_bool()), (Some("goal_reached"), Some(true)));
}

#[test]
fn logging_follows_rust_log_and_the_verbosity_flags() {
    let run = |args: &[&str], rust_log: Option<&str>| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_ubf"));
        command.args(args).current_dir(env!("CARGO_MANIFEST_DIR")).env_remove("RUST_LOG");
        if let Some(filter) = rust_log {
            command.env("RUST_LOG", filter);
        }
        let out = command.output().unwrap();
        assert!(out.status.success(), "{}", text(&out.stderr));
        text(&out.stderr).lines().filter(|l| l.contains(" tick tick=")).count()
    };
    let scenario = "scenarios/goto-open-floor.ron";
    let ticks = run(&["run", scenario, "-vvv"], None);
    assert!(ticks > 50, "-vvv prints every tick: {ticks}");
    assert_eq!(run(&["run", scenario, "--json"], Some("ubf_core=trace")), ticks, "as the docs say");
    assert_eq!(run(&["run", scenario, "-v"], None), 0);
    assert_eq!(run(&["-q", "run", scenario], None), 0);
    assert_eq!(run(&["run", scenario], None), 0);
}

#[test]
fn an_interrupted_run_still_writes_its_report_marked_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("out");
    let child = Command::new(env!("CARGO_BIN_EXE_ubf"))
        .args(["run", "scenarios/rendered-corridor.ron", "--out", out_dir.to_str().unwrap()])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(130), "{}", text(&out.stdout));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["end"], "interrupted");
    assert!(out_dir.join("trajectory.csv").exists() && out_dir.join("plot.png").exists());
}

#[test]
fn work_beyond_the_bounds_is_refused_before_it_starts() {
    // Each of these passed `check` once and then hung, filled the disk,
    // aborted or panicked.
    for (body, says) in [
        (
            r#"Scenario(name: "t", period_s: 1e-300, max_time_s: 10.0, root: Stop())"#,
            "1:31: period_s: 1e-300 is out of range",
        ),
        (r#"Scenario(name: "t", max_time_s: 1e300, root: Stop())"#, "1e300 is out of range"),
        (r#"Scenario(name: "t", period_s: 0.001, max_time_s: 1e7, root: Stop())"#, "pass --huge"),
        (
            r#"Scenario(name: "t", max_time_s: 10.0, world: (corridor: (width: 5e-324, length: 9.0)), root: Stop())"#,
            "5e-324 is out of range",
        ),
        (
            r#"Scenario(name: "t", max_time_s: 10.0, world: (corridor: (width: 4.0, length: 9.0),
                random_landmarks: (count: 4000000000)), root: Stop())"#,
            "at most 10000 landmarks",
        ),
        // A frame's matching is pair by pair: people's features count too.
        (
            r#"Scenario(name: "t", max_time_s: 10.0, world: (people: [
                (start: (x: 1.0, y: 0.0), velocity: (x: 0.0, y: 0.0), features: 9000),
                (start: (x: 2.0, y: 0.0), velocity: (x: 0.0, y: 0.0), features: 9000)]), root: Stop())"#,
            "18000 landmarks and people's features in all: at most 10000",
        ),
        // A name a terminal would obey: retitled and cleared.
        (r#"Scenario(name: "\u{1b}]0;pwned\u{7}\u{1b}[2J", max_time_s: 5.0, root: Stop())"#, "control character"),
        // The plot's axes spun forever on a landmark 1e308 m away.
        (r#"Scenario(name: "t", max_time_s: 5.0, world: (landmarks: [(x: 5.0, y: 1e308)]), root: Stop())"#, "1e308"),
        // A number quoted back as written, not as three hundred digits.
        (r#"Scenario(name: "t", max_time_s: 5.0, robot: (camera: (rate_hz: 1e300)), root: Stop())"#, "rate_hz 1e300:"),
        // A person's velocity is a speed, not a place.
        (
            r#"Scenario(name: "t", max_time_s: 5.0, world: (people: [(start: (x: 1.0, y: 0.0),
                velocity: (x: 400.0, y: 0.0))]), root: Stop())"#,
            "from -10 to 10 m/s",
        ),
        // Headings every 1e-9° (2^31 of them), an error-model table 1e15 m
        // deep, a model of NaN.
        (r#"Scenario(name: "t", max_time_s: 5.0, root: ActionAiding(angle_step_deg: 1e-9))"#, "from 0.1 to 180°"),
        (r#"Scenario(name: "t", max_time_s: 5.0, root: ActionAiding(max_range_m: 1e15))"#, "at most 1000 m"),
        (
            r#"Scenario(name: "t", max_time_s: 5.0, root: ActionAiding(model: Exponential(alpha: NaN, beta: 1.0,
                gamma: 1.0)))"#,
            "NaN is out of range",
        ),
        (
            r#"Scenario(name: "t", max_time_s: 10.0, robot: (camera: (stereo: (focal_px: 1e-300))), root: Stop())"#,
            "focal_px",
        ),
        (
            r#"Scenario(name: "t", max_time_s: 10.0, robot: (camera: (min_depth_m: 100.0)), root: Stop())"#,
            "it would see nothing",
        ),
        (
            r#"Scenario(name: "t", max_time_s: 10.0, robot: (start: (x: 1.0, y: 0.0)), goal: (x: 30.0, y: 0.0),
                world: (corridor: (width: 4.0, length: 20.0)), root: Stop())"#,
            "FILE:1:73: goal: (30, 0) lies outside the corridor",
        ),
        (
            r#"Scenario(name: "t", max_time_s: 5e5, robot: (camera: (images: (), rate_hz: 100.0)), root: Stop())"#,
            "rendered pairs",
        ),
    ] {
        let (code, stderr) = check(body);
        assert_eq!(code, 2, "{body}: {stderr}");
        assert!(stderr.contains(says), "{body}: {stderr}");
    }
    // 20 000 votes a tick, for 100 000 ticks, within the tick bound: tens
    // of gigabytes of logs.
    let children = vec!["(behavior: Stop())"; 20_000].join(", ");
    let wide = format!(
        r#"Scenario(name: "t", max_time_s: 10000.0, root: Composite(arbiter: HighestPriority, children: [{children}]))"#
    );
    let dir = tempfile::tempdir().unwrap();
    let wide_file = scenario_file(&dir, &wide);
    let out = dir.path().join("wide");
    let refused = ubf(&["run", wide_file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(refused.status.code(), Some(2), "{}", text(&refused.stderr));
    let said = text(&refused.stderr);
    assert!(said.contains("100000 ticks × 20001 nodes of the tree, logs of about 48.1 GB"), "{said}");
    assert!(!out.exists(), "nothing was written");
    // Without logs to write, the same run is not refused.
    assert_eq!(check(&wide).0, 0);
    let file = scenario_file(&dir, GOOD);
    let out = dir.path().join("sweep");
    for (seeds, says) in [("0..4000000000", "at most 10 000 000"), ("0..400000", "pass --huge")] {
        let result = ubf(&["sweep", file.to_str().unwrap(), "--seeds", seeds, "--out", out.to_str().unwrap()]);
        assert_eq!(result.status.code(), Some(2));
        assert!(text(&result.stderr).contains(says), "{}", text(&result.stderr));
        assert!(!out.exists(), "nothing was written");
    }
    let result = ubf(&["model", "fit", "--depths", "1e-300..1e-299"]);
    assert_eq!(result.status.code(), Some(2), "{}", text(&result.stderr));
    for (heights, says) in [("1.5..-1", "LOW ≤ HIGH"), ("-1..tall", "`tall` is not a height"), ("-1e9..0", "−100")]
    {
        let result = ubf(&["model", "fit", "--heights", heights]);
        assert_eq!(result.status.code(), Some(2), "{heights}");
        assert!(text(&result.stderr).contains(says), "{heights}: {}", text(&result.stderr));
    }
    let result = ubf(&["experiment", "thesis-endpoint", "--model", "cubic"]);
    assert_eq!(result.status.code(), Some(2));
    assert!(text(&result.stderr).contains("geometric-3d"), "{}", text(&result.stderr));
    let result = ubf(&["experiment", "thesis-endpoint", "--odometry-fusion", "half"]);
    assert_eq!(result.status.code(), Some(2));
    assert!(text(&result.stderr).contains("`sideways`"), "{}", text(&result.stderr));
    // A recording of a day at 2 pairs a second: about 106 GB of images.
    let day = scenario_file(&dir, r#"Scenario(name: "t", max_time_s: 86400.0, robot: (camera: ()), root: Stop())"#);
    let frames = dir.path().join("frames");
    let result = ubf(&["frames", day.to_str().unwrap(), "--out", frames.to_str().unwrap()]);
    assert_eq!(result.status.code(), Some(2));
    assert!(text(&result.stderr).contains("lower --max-frames, or pass --huge"), "{}", text(&result.stderr));
    assert!(!frames.exists(), "nothing was written");
}

#[test]
fn deep_trees_and_non_utf8_files_get_a_position_and_plain_words() {
    let tree = |depth: usize| {
        let mut inner = "Stop()".to_owned();
        for _ in 0..depth {
            inner = format!("Composite(arbiter: CommandFusion, children: [(behavior: {inner})])");
        }
        format!(r#"Scenario(name: "t", max_time_s: 10.0, root: {inner})"#)
    };
    assert_eq!(check(&tree(15)).0, 0);
    let (code, stderr) = check(&tree(16));
    assert_eq!(code, 2);
    assert!(stderr.contains("FILE:1:") && stderr.contains("at most 15 composites deep"), "{stderr}");
    assert!(!stderr.contains("serde_stacker"), "{stderr}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("latin1.ron");
    std::fs::write(&path, b"Scenario(\n  name: \"caf\xe9\", max_time_s: 10.0, root: Stop())").unwrap();
    let out = ubf(&["check", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("latin1.ron:2:13: not UTF-8"), "{}", text(&out.stderr));
}

/// KITTI odometry 06, frames 0–50, beside the checkout (or `UBF_DATA`).
fn kitti_sample() -> Option<PathBuf> {
    let found = ubf_perception::kitti::shared_sample(std::path::Path::new(env!("CARGO_MANIFEST_DIR")));
    if found.is_none() {
        eprintln!("SKIPPED: no KITTI sample (set UBF_DATA, or put it at ../shared/data)");
    }
    found
}

#[test]
fn a_kitti_sequence_replays_with_its_calibration_and_is_measured_against_its_poses() {
    let Some(dir) = kitti_sample() else { return };
    let out = tempfile::tempdir().unwrap().keep();
    let (plot, listed) = (out.join("kitti.png"), out.join("landmarks.csv"));
    let args = ["--json", "--plot", plot.to_str().unwrap(), "--landmarks", listed.to_str().unwrap()];
    let result = ubf(&[&["pipeline", dir.to_str().unwrap()], &args[..]].concat());
    assert_eq!(result.status.code(), Some(0), "{}", text(&result.stderr));
    let report: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
    assert_eq!(report["layout"], "kitti");
    assert_eq!(report["frames"], 51);
    // No failed step. The sequence's calibration leaves a disparity offset
    // of about 0.13 px (docs/perception.md, scripts/kitti-scale.py), which
    // inflates every step by about 1 %; by default egomotion reads it from
    // the frames and corrects the landmarks by it once it has settled.
    assert_eq!(report["failures"], 0, "{report}");
    assert_eq!(report["disparity_offset_corrected"], true, "{report}");
    let read = report["disparity_offset_px"].as_f64().unwrap();
    assert!((0.05..0.3).contains(&read), "{report}");
    let drift = report["endpoint_drift_pct"].as_f64().unwrap();
    assert!(drift <= 2.0, "end-point drift {drift} %");
    let segments = report["translation_error_pct"].as_f64().unwrap();
    assert!(segments < 2.0, "{report}");
    // Frame by frame: no far anchor's wrong consensus puts frames metres
    // off (the median step was 42 % wrong before the near-far check).
    assert!(report["step_translation_error_pct_median"].as_f64().unwrap() < 5.0, "{report}");
    // As the calibration has it, every step is too long, and the
    // over-estimate moves with the disparity offset, as the explanation
    // says it must.
    let pipeline = |extra: &[&str]| -> serde_json::Value {
        let args = [&["pipeline", dir.to_str().unwrap(), "--json", "--keep-disparity-offset"], extra].concat();
        serde_json::from_slice(&ubf(&args).stdout).unwrap()
    };
    let kept_listed = out.join("kept.csv");
    let kept = pipeline(&["--landmarks", kept_listed.to_str().unwrap()]);
    assert_eq!(kept["disparity_offset_corrected"], false, "{kept}");
    // Every step's offset fit converges and is read, kept or corrected.
    assert_eq!(kept["disparity_offset_steps"], 50, "{kept}");
    assert_eq!(report["disparity_offset_steps"], 50, "{report}");
    // The landmarks file holds the points the path was estimated from:
    // each row's depth is f·B over its disparity plus the offset in its
    // last column, which is the calibration's (0) while the offset is
    // kept, and the correction once it has settled when it is not.
    let calib = std::fs::read_to_string(dir.join("calib.txt")).unwrap();
    let p1 = calib.lines().find_map(|l| l.strip_prefix("P1:")).unwrap();
    let focal_baseline = -p1.split_whitespace().nth(3).unwrap().parse::<f64>().unwrap();
    let offsets = |path: &Path| -> Vec<f64> {
        let rows = std::fs::read_to_string(path).unwrap();
        assert_eq!(rows.lines().next(), Some(ubf::frames::LANDMARKS_HEADER));
        let rows: Vec<Vec<f64>> =
            rows.lines().skip(1).map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
        assert!(rows.len() > 20_000, "{} rows", rows.len());
        for row in &rows {
            let (disparity, depth, offset) = (row[4], row[6], row[8]);
            assert!((depth * (disparity + offset) / focal_baseline - 1.0).abs() < 1e-3, "{row:?}");
        }
        rows.iter().map(|row| row[8]).collect()
    };
    assert!(offsets(&kept_listed).iter().all(|&o| o == 0.0));
    let corrected_offsets = offsets(&listed);
    assert_eq!(corrected_offsets[0], 0.0, "not corrected before it settles");
    assert!((0.05..0.3).contains(corrected_offsets.last().unwrap()), "{:?}", corrected_offsets.last());
    let scale = kept["step_scale_median"].as_f64().unwrap();
    assert!((1.0..1.03).contains(&scale), "{kept}");
    let corrected = pipeline(&["--disparity-offset", "0.13"]);
    assert!(corrected["step_scale_median"].as_f64().unwrap() < scale - 0.005, "{corrected}");
    let kept_segments = kept["translation_error_pct"].as_f64().unwrap();
    assert!(corrected["translation_error_pct"].as_f64().unwrap() < kept_segments - 0.3, "{corrected}");
    // The offset read from the frames moves it the same way.
    assert!(report["step_scale_median"].as_f64().unwrap() < scale - 0.002, "{report}");
    assert!(segments < kept_segments, "{report}");
    assert_eq!(report["limits"], serde_json::json!([40.0, 90.0]));
    assert!(std::fs::metadata(&plot).unwrap().len() > 10_000);
    // The robot's limits reject every step of a car at 12 m/s.
    let slow = ubf(&["pipeline", dir.to_str().unwrap(), "--json", "--max-speed", "0.6"]);
    let slow: serde_json::Value = serde_json::from_slice(&slow.stdout).unwrap();
    assert!(slow["failures"].as_u64().unwrap() >= 45, "{slow}");
}

#[test]
fn a_broken_kitti_calibration_is_named_with_its_line() {
    let Some(sample) = kitti_sample() else { return };
    let dir = tempfile::tempdir().unwrap();
    for name in ["image_0", "image_1", "times.txt"] {
        std::os::unix::fs::symlink(sample.join(name), dir.path().join(name)).unwrap();
    }
    let calib = std::fs::read_to_string(sample.join("calib.txt")).unwrap();
    std::fs::write(dir.path().join("calib.txt"), calib.replacen("P1: 7.07", "P1: x7.07", 1)).unwrap();
    let result = ubf(&["pipeline", dir.path().to_str().unwrap()]);
    assert_eq!(result.status.code(), Some(2));
    assert!(text(&result.stderr).contains("calib.txt:2: `P1:` needs 12 finite numbers"), "{}", text(&result.stderr));
    std::fs::write(dir.path().join("calib.txt"), calib).unwrap();
    std::fs::write(dir.path().join("poses.txt"), "1 0 0 0 0 1 0 0 0 0 1 0\n").unwrap();
    let result = ubf(&["pipeline", dir.path().to_str().unwrap()]);
    assert_eq!(result.status.code(), Some(2));
    assert!(text(&result.stderr).contains("1 poses for 51 frames"), "{}", text(&result.stderr));
}

/// A `camera_info` file for a camera that needs no rectification: the
/// rendered camera's intrinsics (its principal point the image centre, at
/// 319.5, 239.5 where pixel centres are integers), no distortion, `R` the
/// identity, and the camera `shift` metres right of the left one.
fn identity_camera_info(focal: f64, shift: f64) -> String {
    let k = format!("[{focal}, 0, 319.5, 0, {focal}, 239.5, 0, 0, 1]");
    let p = format!("[{focal}, 0, 319.5, {}, 0, {focal}, 239.5, 0, 0, 0, 1, 0]", -focal * shift);
    format!(
        "image_width: 640\nimage_height: 480\ncamera_name: c\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: {k}\n\
         distortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0, 0, 0, 0, 0]\n\
         rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n\
         projection_matrix:\n  rows: 3\n  cols: 4\n  data: {p}\n"
    )
}

#[test]
fn a_raw_recording_with_camera_info_files_is_rectified_on_replay() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    let scenario = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("lab/scenarios/thesis/route-1-2.ron");
    let recorded = ubf(&["frames", scenario.to_str().unwrap(), "--out", frames.to_str().unwrap(), "--max-frames", "6"]);
    assert!(recorded.status.success(), "{}", text(&recorded.stderr));
    let replay = |dir: &std::path::Path| {
        let result = ubf(&["pipeline", dir.to_str().unwrap(), "--json"]);
        assert!(result.status.success(), "{}", text(&result.stderr));
        let report: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
        (report["landmarks_mean"].clone(), report["final_pose"].clone())
    };
    let rectified = replay(&frames);
    let listed = dir.path().join("landmarks.csv");
    let result = ubf(&["pipeline", frames.to_str().unwrap(), "--landmarks", listed.to_str().unwrap()]);
    assert!(result.status.success(), "{}", text(&result.stderr));
    let rows = std::fs::read_to_string(&listed).unwrap();
    assert_eq!(rows.lines().next(), Some(ubf::frames::LANDMARKS_HEADER));
    let mean = rectified.0.as_f64().unwrap();
    assert_eq!(rows.lines().count() - 1, (mean * 6.0).round() as usize, "one row per landmark of 6 pairs");
    // The same images as "raw" ones with an identity rectification give the
    // same landmarks and the same path.
    let camera: String = std::fs::read_to_string(frames.join("camera.ron")).unwrap();
    let number = |key: &str| -> f64 {
        let line = camera.lines().find(|l| l.trim_start().starts_with(key)).unwrap();
        line.split(':').nth(1).unwrap().trim().trim_end_matches(',').parse().unwrap()
    };
    std::fs::remove_file(frames.join("camera.ron")).unwrap();
    let (focal, baseline) = (number("focal_px"), number("baseline_m"));
    std::fs::write(frames.join("left.yaml"), identity_camera_info(focal, 0.0)).unwrap();
    std::fs::write(frames.join("right.yaml"), identity_camera_info(focal, baseline)).unwrap();
    assert_eq!(replay(&frames), rectified);
    // And so does the same identity as OpenCV's unrectified stereo
    // calibration (K, D, R, T).
    std::fs::remove_file(frames.join("left.yaml")).unwrap();
    std::fs::remove_file(frames.join("right.yaml")).unwrap();
    let matrix = |rows: usize, cols: usize, data: &str| {
        format!(" !!opencv-matrix\n   rows: {rows}\n   cols: {cols}\n   dt: d\n   data: [ {data} ]\n")
    };
    let k = matrix(3, 3, &format!("{focal}, 0., 319.5, 0., {focal}, 239.5, 0., 0., 1."));
    let d = matrix(1, 5, "0., 0., 0., 0., 0.");
    let stereo = format!(
        "%YAML 1.2\n---\nimage_width: 640\nimage_height: 480\nK1:{k}D1:{d}K2:{k}D2:{d}R:{}T:{}",
        matrix(3, 3, "1., 0., 0., 0., 1., 0., 0., 0., 1."),
        matrix(3, 1, &format!("{}, 0., 0.", -baseline))
    );
    std::fs::write(frames.join("stereo.yaml"), stereo).unwrap();
    assert_eq!(replay(&frames), rectified);
    // Two kinds of calibration in one directory: refused, not guessed.
    std::fs::write(frames.join("camera.ron"), camera).unwrap();
    let both = ubf(&["pipeline", frames.to_str().unwrap()]);
    assert_eq!(both.status.code(), Some(2));
    assert!(text(&both.stderr).contains("keep the one that describes its images"), "{}", text(&both.stderr));
}

#[test]
fn the_tree_is_drawn_with_its_arbiters_weights_and_votes() {
    let dir = tempfile::tempdir().unwrap();
    let file = scenario_file(
        &dir,
        r#"Scenario(name: "t", max_time_s: 1.0, root: Composite(arbiter: HighestPriority, children: [
            (behavior: Stop(), weight: 3.0),
            (behavior: Composite(arbiter: CommandFusion, vote: 0.5, children: [
                (behavior: AvoidCollision()), (behavior: GoTo())])),
        ]))"#,
    );
    let dot = ubf(&["tree", file.to_str().unwrap()]);
    assert!(dot.status.success(), "{}", text(&dot.stderr));
    let dot = text(&dot.stdout);
    assert!(dot.starts_with("digraph tree {") && dot.trim_end().ends_with('}'), "{dot}");
    assert_eq!(dot.matches(" -> ").count(), 4, "five nodes, four edges: {dot}");
    assert!(dot.contains("HighestPriority") && dot.contains("CommandFusion\\nvote 0.5"), "{dot}");
    assert!(dot.contains("[label=\"0.75\"]") && dot.contains("[label=\"0.50\"]"), "weights 3:1 and 1:1: {dot}");
    let mermaid = text(&ubf(&["tree", file.to_str().unwrap(), "--mermaid"]).stdout);
    assert!(mermaid.starts_with("flowchart TD") && mermaid.matches(" --> ").count() == 4, "{mermaid}");
    let missing = ubf(&["tree", "no-such.ron"]);
    assert_eq!(missing.status.code(), Some(2));
}

#[test]
fn the_model_fit_reports_the_planar_and_the_3d_form_side_by_side() {
    let result = ubf(&["model", "fit", "--json", "--heights", "-0.5..0.5"]);
    assert!(result.status.success(), "{}", text(&result.stderr));
    let fit: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
    // The planar fit has no height term; the 3D one a positive one, over
    // the heights asked for.
    assert!(fit["planar"]["model"].get("delta").is_none(), "{fit}");
    assert!(fit["planar"].get("height_range_m").is_none(), "{fit}");
    assert!(fit["with_height"]["model"]["delta"].as_f64().unwrap() > 0.0, "{fit}");
    assert_eq!(fit["with_height"]["height_range_m"], serde_json::json!([-0.5, 0.5]));
    let text = text(&ubf(&["model", "fit"]).stdout);
    assert!(text.contains("planar (eq. 24)") && text.contains("3D (§5.3.1)"), "{text}");
}

#[test]
fn the_error_model_heat_map_is_drawn_with_its_colour_bar() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("model.png");
    let result = ubf(&["model", "heatmap", "--out", png.to_str().unwrap()]);
    assert!(result.status.success(), "{}", text(&result.stderr));
    let image = image::open(&png).unwrap().into_rgb8();
    assert_eq!(image.dimensions(), (1000, 900));
    // The bar, right of the map: red at its top, blue at its bottom.
    let (top, bottom) = (image.get_pixel(965, 60), image.get_pixel(965, 840));
    assert!(top[0] > 200 && top[2] < 100, "top of the bar {top:?}");
    assert!(bottom[2] > 200 && bottom[0] < 100, "bottom of the bar {bottom:?}");
}

#[test]
fn behaviours_describe_their_fields() {
    let out = ubf(&["behaviors", "--describe", "GoTo"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let described = text(&out.stdout);
    assert!(described.starts_with("### `GoTo`"), "{described}");
    assert!(described.contains("| `cruise_speed` | number | m/s | `0.5` | > 0 |"), "{described}");
    let names = text(&ubf(&["behaviors"]).stdout);
    assert!(names.lines().any(|l| l == "ActionAiding") && names.lines().any(|l| l == "Composite"), "{names}");
    let unknown = ubf(&["behaviors", "--describe", "Teleport"]);
    assert_eq!(unknown.status.code(), Some(2));
    assert!(text(&unknown.stderr).contains("unknown behaviour `Teleport`"), "{}", text(&unknown.stderr));
}

#[test]
fn a_log_that_is_not_there_is_said_to_be_unreadable_not_unwritable() {
    let missing = ubf(&["replay", "no-such-log.mcap"]);
    assert_eq!(missing.status.code(), Some(2));
    let said = text(&missing.stderr);
    assert!(said.starts_with("error: reading no-such-log.mcap: "), "{said}");
    assert!(!said.contains("writing"), "{said}");
}

#[test]
fn aiding_on_a_robot_without_a_camera_says_so() {
    // It drives straight at the goal, as it would with no aid at all.
    let dir = tempfile::tempdir().unwrap();
    let body = r#"Scenario(name: "blind", max_time_s: 8.0, robot: (start: (x: 1.0, y: 0.0)), goal: (x: 8.0, y: 0.0),
        world: (corridor: (width: 4.0, length: 20.0)), root: ActionAiding(technique: Scan))"#;
    let out = ubf(&["run", scenario_file(&dir, body).to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let said = text(&out.stderr).matches("no stereo frame with its calibration in 5 s").count();
    assert_eq!(said, 1, "{}", text(&out.stderr));
    let with_camera = body.replace("start: (x: 1.0, y: 0.0))", "start: (x: 1.0, y: 0.0), camera: ())");
    let out = ubf(&["run", scenario_file(&dir, &with_camera).to_str().unwrap()]);
    assert!(!text(&out.stderr).contains("no stereo frame"), "{}", text(&out.stderr));
}

#[test]
fn a_run_without_a_goal_says_so_rather_than_that_it_missed_it() {
    let dir = tempfile::tempdir().unwrap();
    let aimless = GOOD.replace("goal: (x: 3.0, y: 0.0),", "").replace("max_time_s: 30.0", "max_time_s: 2.0");
    let file = scenario_file(&dir, &aimless);
    let out = ubf(&["run", file.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("goal reached    no goal set"), "{}", text(&out.stdout));
    let with_goal = ubf(&["run", scenario_file(&dir, GOOD).to_str().unwrap()]);
    assert!(text(&with_goal.stdout).contains("goal reached    yes"), "{}", text(&with_goal.stdout));
}
