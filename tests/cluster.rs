//! Sweeps on a cluster: `--shard auto` takes the shard from a Slurm job
//! array's variables and `--shard auto/N` from a Kubernetes Indexed Job's,
//! the shards they run merge to the bytes one sweep writes, and what names
//! no shard is refused with a sentence.

use std::path::Path;
use std::process::{Command, Output};

/// The variables a scheduler sets that `--shard auto` reads: removed from
/// every command here, so that a suite run inside a Slurm job or a pod
/// sees only the ones a test sets.
const SCHEDULER_VARIABLES: [&str; 6] = [
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_COUNT",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_MAX",
    "SLURM_ARRAY_TASK_STEP",
    "JOB_COMPLETION_INDEX",
];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `command` in the repository, with only `vars` of the scheduler's
/// variables set.
fn output(mut command: Command, vars: &[(&str, String)]) -> Output {
    for name in SCHEDULER_VARIABLES {
        command.env_remove(name);
    }
    command.envs(vars.iter().map(|(k, v)| (k, v))).current_dir(root()).output().unwrap()
}

/// `ubf args` with `vars` set.
fn ubf(vars: &[(&str, String)], args: &[&str]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_ubf"));
    command.args(args);
    output(command, vars)
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The test sweep's arguments (two scenarios, seeds 3..=14) into `out`,
/// with `extra`.
fn sweep_args<'a>(out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
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
    args
}

/// Asserts `merged` holds the summary `whole` does, byte for byte (what
/// tests/sweep.rs compares of a merged sweep).
fn assert_same_summary(merged: &Path, whole: &Path) {
    for file in ["summary.csv", "summary.json"] {
        let expected = std::fs::read(whole.join(file)).unwrap();
        assert!(std::fs::read(merged.join(file)).unwrap() == expected, "{file}: the shards differ from one sweep");
    }
}

/// One sweep of the test sweep into `dir/whole`.
fn whole_sweep(dir: &Path) -> std::path::PathBuf {
    let whole = dir.join("whole");
    let out = ubf(&[], &sweep_args(&whole, &[]));
    assert!(out.status.success(), "{}", text(&out.stderr));
    whole
}

#[test]
fn a_slurm_array_numbered_from_one_merges_to_the_bytes_of_one_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let whole = whole_sweep(dir.path());
    // The tasks of `--array=1-4`, into one shared folder.
    let shared = dir.path().join("shared");
    for id in 1..=4 {
        let vars = [
            ("SLURM_ARRAY_TASK_ID", id.to_string()),
            ("SLURM_ARRAY_TASK_MIN", "1".into()),
            ("SLURM_ARRAY_TASK_MAX", "4".into()),
            ("SLURM_ARRAY_TASK_COUNT", "4".into()),
            ("SLURM_ARRAY_TASK_STEP", "1".into()),
        ];
        let out = ubf(&vars, &sweep_args(&shared, &["--shard", "auto"]));
        assert!(out.status.success(), "task {id}: {}", text(&out.stderr));
        let said = format!(
            "--shard auto: shard {}/4, from SLURM_ARRAY_TASK_ID={id} less SLURM_ARRAY_TASK_MIN=1, of \
             SLURM_ARRAY_TASK_COUNT=4\n",
            id - 1
        );
        assert_eq!(text(&out.stderr), said);
        assert!(shared.join(format!("shard-{}-of-4.json", id - 1)).is_file());
    }
    let merged = ubf(&[], &["sweep", "merge", shared.to_str().unwrap()]);
    assert!(merged.status.success(), "{}", text(&merged.stderr));
    assert_same_summary(&shared, &whole);
}

#[test]
fn an_indexed_job_merges_to_the_bytes_of_one_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let whole = whole_sweep(dir.path());
    // Each pod of a Job of 3 completions into its own folder.
    let parts: Vec<_> = (0..3).map(|k| dir.path().join(format!("pod-{k}"))).collect();
    for (index, part) in parts.iter().enumerate() {
        let out = ubf(&[("JOB_COMPLETION_INDEX", index.to_string())], &sweep_args(part, &["--shard", "auto/3"]));
        assert!(out.status.success(), "index {index}: {}", text(&out.stderr));
        assert_eq!(text(&out.stderr), format!("--shard auto/3: shard {index}/3, from JOB_COMPLETION_INDEX={index}\n"));
    }
    let merged = dir.path().join("merged");
    let mut args = vec!["sweep", "merge"];
    args.extend(parts.iter().map(|p| p.to_str().unwrap()));
    args.extend(["--out", merged.to_str().unwrap()]);
    let out = ubf(&[], &args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_same_summary(&merged, &whole);
}

#[test]
fn an_environment_that_names_no_shard_is_refused_with_a_sentence() {
    let slurm = |pairs: &[(&'static str, &str)]| -> Vec<(&'static str, String)> {
        pairs.iter().map(|(k, v)| (*k, (*v).to_owned())).collect()
    };
    let cases = [
        ("auto", slurm(&[]), "SLURM_ARRAY_TASK_ID is not set; submit the job as an array"),
        (
            "auto",
            slurm(&[("JOB_COMPLETION_INDEX", "2")]),
            "JOB_COMPLETION_INDEX is, so this looks like a Kubernetes Indexed Job",
        ),
        (
            "auto",
            slurm(&[("SLURM_ARRAY_TASK_ID", "2")]),
            "SLURM_ARRAY_TASK_ID=2 is set but SLURM_ARRAY_TASK_COUNT is not",
        ),
        (
            "auto",
            slurm(&[("SLURM_ARRAY_TASK_ID", "two"), ("SLURM_ARRAY_TASK_COUNT", "4")]),
            "SLURM_ARRAY_TASK_ID=\"two\" is not a whole number",
        ),
        (
            "auto",
            slurm(&[("SLURM_ARRAY_TASK_ID", "1"), ("SLURM_ARRAY_TASK_COUNT", "")]),
            "SLURM_ARRAY_TASK_COUNT=\"\" is not a whole number",
        ),
        (
            "auto",
            slurm(&[
                ("SLURM_ARRAY_TASK_ID", "4"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
                ("SLURM_ARRAY_TASK_MAX", "10"),
                ("SLURM_ARRAY_TASK_COUNT", "6"),
                ("SLURM_ARRAY_TASK_STEP", "2"),
            ]),
            "SLURM_ARRAY_TASK_STEP=2: the array's ids go in steps (--array=0-10:2), so they cannot number shards \
             without gaps; submit a contiguous range, such as --array=0-5",
        ),
        (
            "auto",
            slurm(&[
                ("SLURM_ARRAY_TASK_ID", "3"),
                ("SLURM_ARRAY_TASK_MIN", "1"),
                ("SLURM_ARRAY_TASK_MAX", "7"),
                ("SLURM_ARRAY_TASK_COUNT", "3"),
            ]),
            "SLURM_ARRAY_TASK_MIN=1, SLURM_ARRAY_TASK_MAX=7 and SLURM_ARRAY_TASK_COUNT=3 are not a contiguous range",
        ),
        (
            "auto",
            slurm(&[("SLURM_ARRAY_TASK_ID", "0"), ("SLURM_ARRAY_TASK_MIN", "1"), ("SLURM_ARRAY_TASK_COUNT", "3")]),
            "SLURM_ARRAY_TASK_ID=0 is below SLURM_ARRAY_TASK_MIN=1, so it names no shard",
        ),
        (
            "auto",
            slurm(&[("SLURM_ARRAY_TASK_ID", "3"), ("SLURM_ARRAY_TASK_COUNT", "3")]),
            "SLURM_ARRAY_TASK_ID=3 is not below SLURM_ARRAY_TASK_COUNT=3, so it names no shard",
        ),
        (
            "auto/4",
            slurm(&[]),
            "--shard auto/4 takes the shard from a Kubernetes Indexed Job, but JOB_COMPLETION_INDEX",
        ),
        ("auto/4", slurm(&[("JOB_COMPLETION_INDEX", "-1")]), "JOB_COMPLETION_INDEX=\"-1\" is not a whole number"),
        (
            "auto/4",
            slurm(&[("JOB_COMPLETION_INDEX", "4")]),
            "JOB_COMPLETION_INDEX=4 is not below the 4 shards of --shard auto/4",
        ),
        ("auto/0", slurm(&[("JOB_COMPLETION_INDEX", "0")]), "`auto/N` needs a number of shards N ≥ 1"),
    ];
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    for (spec, vars, says) in cases {
        let result = ubf(&vars, &sweep_args(&out, &["--shard", spec]));
        let stderr = text(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{spec} {vars:?}: {stderr}");
        assert!(stderr.starts_with("error: ") && stderr.contains(says), "{spec} {vars:?}: {stderr}");
        assert!(!out.exists(), "{spec} {vars:?}: nothing written");
    }
}
