//! Sweeps on a cluster: `--shard auto` takes the shard from a Slurm job
//! array's variables and `--shard auto/N` from a Kubernetes Indexed Job's,
//! the shards they run merge to the bytes one sweep writes, and what names
//! no shard is refused with a sentence. The job files in `deploy/cluster/`
//! run their sweep and its merge here, the scheduler stood in for, and
//! docs/cluster.md shows each as it is.

mod common;

use common::sweep_args;
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

// The job files in deploy/cluster/, run here without a cluster: the
// scheduler's part (its variables, sbatch, the Job controller's `$(VAR)`)
// stood in for, the rest run as it is.

/// A folder for the stand-ins of the commands a job finds on its `PATH`:
/// `ubf` is the binary under test.
fn bin_dir(dir: &Path) -> std::path::PathBuf {
    let bin = dir.join("bin");
    std::fs::create_dir(&bin).unwrap();
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_ubf"), bin.join("ubf")).unwrap();
    bin
}

/// Writes an executable shell script `name` into `bin`.
fn stand_in(bin: &Path, name: &str, script: &str) {
    use std::os::unix::fs::PermissionsExt;
    let path = bin.join(name);
    std::fs::write(&path, format!("#!/bin/sh\n{script}")).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// `PATH` with `bin` first.
fn path_with(bin: &Path) -> String {
    format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default())
}

fn read(path: &str) -> String {
    std::fs::read_to_string(root().join(path)).unwrap()
}

/// The value of the script's `#SBATCH --NAME=` line.
fn sbatch_option(script: &str, name: &str) -> String {
    let prefix = format!("#SBATCH --{name}=");
    let found = script.lines().find_map(|l| l.strip_prefix(&prefix));
    found.unwrap_or_else(|| panic!("no `{prefix}` line")).trim().to_owned()
}

/// The value the script gives a shell variable (`name="..."` on a line of
/// its own), its quotes removed.
fn shell_value(script: &str, name: &str) -> String {
    let prefix = format!("{name}=");
    let found = script.lines().find_map(|l| l.strip_prefix(&prefix));
    found.unwrap_or_else(|| panic!("no `{prefix}` line")).trim_matches('"').to_owned()
}

/// One sweep of `scenario` over `seeds` into `dir/whole`.
fn whole_sweep_of(dir: &Path, scenario: &str, seeds: &str) -> std::path::PathBuf {
    let whole = dir.join("whole");
    let out = ubf(&[], &["sweep", scenario, "--seeds", seeds, "--out", whole.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    whole
}

/// The seeds the job files' sweep is run with here, in place of their
/// hundred thousand.
const FEW_SEEDS: &str = "0..12";

#[test]
fn the_slurm_scripts_submit_run_and_merge_a_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let bin = bin_dir(dir.path());
    let path = path_with(&bin);
    // sbatch as `--parsable` answers, each call recorded.
    let log = dir.path().join("sbatch.log");
    stand_in(&bin, "sbatch", "echo \"$*\" >> \"$SBATCH_LOG\"\necho '4242;cluster'\n");
    let mut submit = Command::new("bash");
    submit.arg("deploy/cluster/submit.sh");
    let vars = [("PATH", path.clone()), ("SBATCH_LOG", log.display().to_string())];
    let out = output(submit, &vars);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let submitted = std::fs::read_to_string(&log).unwrap();
    assert_eq!(
        submitted,
        "--parsable deploy/cluster/sweep.slurm\n--dependency=afterany:4242 deploy/cluster/merge.slurm\n"
    );

    // Every task of the array as Slurm starts it, then the merge.
    let sweep = read("deploy/cluster/sweep.slurm");
    let merge = read("deploy/cluster/merge.slurm");
    assert_eq!(shell_value(&sweep, "out"), shell_value(&merge, "out"), "both scripts default to one folder");
    let array = sbatch_option(&sweep, "array");
    let range = array.split('%').next().unwrap();
    let (min, max) = range.split_once('-').expect("a contiguous range of ids, as --shard auto needs");
    let (min, max): (u64, u64) = (min.parse().unwrap(), max.parse().unwrap());
    let count = max - min + 1;
    let cpus = sbatch_option(&sweep, "cpus-per-task");
    let shared = dir.path().join("shared");
    let job = |script: &str, task: &[(&'static str, String)]| {
        let mut command = Command::new("bash");
        command.arg(script);
        let mut vars = vec![
            ("PATH", path.clone()),
            ("HOME", dir.path().display().to_string()),
            ("SEEDS", FEW_SEEDS.to_owned()),
            ("SWEEP_OUT", shared.display().to_string()),
        ];
        vars.extend(task.iter().cloned());
        output(command, &vars)
    };
    for id in min..=max {
        let task = [
            ("SLURM_ARRAY_TASK_ID", id.to_string()),
            ("SLURM_ARRAY_TASK_MIN", min.to_string()),
            ("SLURM_ARRAY_TASK_MAX", max.to_string()),
            ("SLURM_ARRAY_TASK_COUNT", count.to_string()),
            ("SLURM_ARRAY_TASK_STEP", "1".to_owned()),
            ("SLURM_CPUS_PER_TASK", cpus.clone()),
        ];
        let out = job("deploy/cluster/sweep.slurm", &task);
        assert!(out.status.success(), "task {id}: {}", text(&out.stderr));
        let said = format!("--shard auto: shard {}/{count}, from SLURM_ARRAY_TASK_ID={id}", id - min);
        assert!(text(&out.stderr).starts_with(&said), "task {id}: {}", text(&out.stderr));
    }
    let out = job("deploy/cluster/merge.slurm", &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let whole = whole_sweep_of(dir.path(), &shell_value(&sweep, "scenarios"), FEW_SEEDS);
    assert_same_summary(&shared, &whole);
}

/// A Kubernetes manifest as JSON.
fn manifest(path: &str) -> serde_json::Value {
    serde_norway::from_str(&read(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The Job's one container.
fn container(job: &serde_json::Value) -> &serde_json::Value {
    let containers = job["spec"]["template"]["spec"]["containers"].as_array().expect("containers");
    assert_eq!(containers.len(), 1);
    &containers[0]
}

/// The container's environment, as its `env` sets it.
fn container_env(container: &serde_json::Value) -> Vec<(String, String)> {
    let env = container["env"].as_array().expect("env");
    env.iter().map(|v| (v["name"].as_str().unwrap().to_owned(), v["value"].as_str().unwrap().to_owned())).collect()
}

/// `text` with each `$(NAME)` of `env` replaced by its value, as
/// Kubernetes does in a container's command and arguments.
fn kubernetes_expanded(text: &str, env: &[(String, String)]) -> String {
    env.iter().fold(text.to_owned(), |text, (name, value)| text.replace(&format!("$({name})"), value))
}

/// `env` with `SEEDS` and `SWEEP_OUT` replaced: the sweep run here.
fn here(env: &[(String, String)], shared: &Path) -> Vec<(String, String)> {
    let mut here: Vec<(String, String)> =
        env.iter().filter(|(name, _)| name != "SEEDS" && name != "SWEEP_OUT").cloned().collect();
    here.push(("SEEDS".into(), FEW_SEEDS.into()));
    here.push(("SWEEP_OUT".into(), shared.display().to_string()));
    here
}

#[test]
fn the_indexed_job_runs_its_shards_and_the_merge_job_merges_them() {
    let job = manifest("deploy/cluster/sweep-job.yaml");
    assert_eq!((job["apiVersion"].as_str(), job["kind"].as_str()), (Some("batch/v1"), Some("Job")));
    let spec = &job["spec"];
    assert_eq!(spec["completionMode"], "Indexed");
    let completions = spec["completions"].as_u64().expect("completions");
    assert!(spec["parallelism"].as_u64().expect("parallelism") <= completions);
    assert_eq!(spec["template"]["spec"]["restartPolicy"], "Never", "podFailurePolicy needs it");
    let ubf_container = container(&job);
    let rule = &spec["podFailurePolicy"]["rules"][0];
    assert_eq!((rule["action"].as_str(), rule["onExitCodes"]["values"][0].as_u64()), (Some("FailJob"), Some(2)));
    assert_eq!(rule["onExitCodes"]["containerName"], ubf_container["name"]);
    assert_eq!(ubf_container["workingDir"], "/ubf", "the repository, where the scenario's path starts");
    assert_eq!(ubf_container["command"], serde_json::json!(["sh", "-c"]));
    let env = container_env(ubf_container);
    let script = kubernetes_expanded(ubf_container["args"][0].as_str().expect("one argument"), &env);
    assert!(script.contains(&format!("--shard auto/{completions} ")), "N is the Job's completions: {script}");

    // Every pod, in the repository (its working folder), then the merge.
    let dir = tempfile::tempdir().unwrap();
    let bin = bin_dir(dir.path());
    let shared = dir.path().join("shared");
    let env = here(&env, &shared);
    for index in 0..completions {
        let mut pod = Command::new("sh");
        pod.arg("-c").arg(&script).env("PATH", path_with(&bin)).envs(env.iter().map(|(k, v)| (k, v)));
        let out = output(pod, &[("JOB_COMPLETION_INDEX", index.to_string())]);
        assert!(out.status.success(), "index {index}: {}", text(&out.stderr));
    }
    let merge_job = manifest("deploy/cluster/merge-job.yaml");
    let merge_container = container(&merge_job);
    assert_eq!(merge_container["volumeMounts"], ubf_container["volumeMounts"]);
    assert_eq!(merge_job["spec"]["template"]["spec"]["volumes"], job["spec"]["template"]["spec"]["volumes"]);
    let merge_env = container_env(merge_container);
    let sweep_out = |env: &[(String, String)]| env.iter().find(|(k, _)| k == "SWEEP_OUT").cloned();
    assert_eq!(sweep_out(&merge_env), sweep_out(&container_env(ubf_container)), "both Jobs use one folder");
    let words: Vec<String> = merge_container["command"]
        .as_array()
        .expect("command")
        .iter()
        .map(|w| kubernetes_expanded(w.as_str().unwrap(), &here(&merge_env, &shared)))
        .collect();
    let mut merge = Command::new(&words[0]);
    merge.args(&words[1..]).env("PATH", path_with(&bin));
    let out = output(merge, &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let scenario = script.split_whitespace().nth(2).expect("ubf sweep SCENARIO");
    let whole = whole_sweep_of(dir.path(), scenario, FEW_SEEDS);
    assert_same_summary(&shared, &whole);

    // The shell around `ubf`: a shard whose runs failed (1) is done; bad
    // input (2, which fails the Job) and a stop (130) are passed on.
    let fake = dir.path().join("fake");
    std::fs::create_dir(&fake).unwrap();
    stand_in(&fake, "ubf", "exit \"$UBF_STATUS\"\n");
    for (status, expected) in [(0, 0), (1, 0), (2, 2), (130, 130)] {
        let mut pod = Command::new("sh");
        pod.arg("-c").arg(&script).env("PATH", path_with(&fake)).env("UBF_STATUS", status.to_string());
        assert_eq!(output(pod, &[]).status.code(), Some(expected), "ubf exiting {status}");
    }
}

/// The fenced blocks of a Markdown page, their bodies as they are.
fn fenced_blocks(page: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut open: Option<String> = None;
    for line in page.lines() {
        match (line.trim_start().starts_with("```"), open.take()) {
            (true, Some(body)) => blocks.push(body),
            (true, None) => open = Some(String::new()),
            (false, Some(mut body)) => {
                body.push_str(line);
                body.push('\n');
                open = Some(body);
            }
            (false, None) => {}
        }
    }
    blocks
}

#[test]
fn the_cluster_page_shows_every_job_file_as_it_is() {
    let blocks = fenced_blocks(&read("docs/cluster.md"));
    let mut files: Vec<_> =
        std::fs::read_dir(root().join("deploy/cluster")).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    assert!(files.len() >= 5, "{files:?}");
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(blocks.contains(&text), "docs/cluster.md does not show {} as it is", file.display());
    }
}
