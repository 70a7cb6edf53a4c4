//! Many runs: every scenario × every seed, in parallel, summarised.
//!
//! The summary depends only on the scenarios and seeds, never on how many
//! jobs ran them or in which order they finished: results are gathered by
//! job number, and wall time (the one thing that varies) stays out of it.
//!
//! A sweep too big for one machine is split into shards ([`Shard`]): each
//! runs a fixed share of the runs and leaves their reports and a record of
//! what it did; [`merge`] reads them back and writes the summary a single
//! sweep would have written, byte for byte.
//!
//! A sweep can be stopped and finished later. Every file it writes lands
//! whole ([`crate::atomic`]); a run writes into `LABEL/.seed-N.partial/` and
//! that folder is renamed to `LABEL/seed-N/` once its `report.json` is in,
//! so a `seed-N/report.json` is a finished run. Once its stop flag is set
//! ([`SweepSettings::stop`]) a sweep starts no run, discards the runs it
//! stopped, and writes no summary; with [`SweepSettings::resume`] it runs
//! only the runs without a `seed-N/report.json`, and its outputs are the
//! same bytes an uninterrupted sweep writes (each report's `wall_time_s`
//! aside).

use crate::run::{run_until, write_report, EndReason, Outputs, RunError};
use crate::scenario::Scenario;
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

mod merge;
mod stats;

pub use merge::{merge, MergeError};
use stats::{numeric_fields, numeric_leaves};
pub use stats::{stats, t95, FieldStats};

/// One scenario to sweep and the directory name its runs go under.
pub struct SweepItem {
    /// The scenario.
    pub scenario: Scenario,
    /// Directory name under the sweep's output directory.
    pub label: String,
}

/// The summary of one scenario's runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScenarioSummary {
    /// Runs that finished.
    pub runs: usize,
    /// Runs that failed, with their seeds and errors.
    pub failed: Vec<(u64, String)>,
    /// Every numeric report field (booleans as 0/1, poses as `pose.x`…);
    /// `seed` and `wall_time_s` are left out.
    pub fields: BTreeMap<String, FieldStats>,
}

/// What a sweep found: `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepSummary {
    /// The seeds swept, `start..end`.
    pub seeds: [u64; 2],
    /// One summary per scenario label.
    pub scenarios: BTreeMap<String, ScenarioSummary>,
}

/// A share of a sweep's runs: of the runs in order (scenario by scenario,
/// seed by seed), those whose position modulo `count` is `index`. Written
/// `K/N`, 0-based, as a Slurm array task or a Kubernetes indexed job
/// numbers its workers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// Which share, from 0.
    pub index: u64,
    /// How many shares.
    pub count: u64,
}

impl Shard {
    /// Reads `K/N` with `0 ≤ K < N`.
    pub fn parse(text: &str) -> Result<Shard, String> {
        let parsed = text.split_once('/').and_then(|(k, n)| Some((k.trim().parse().ok()?, n.trim().parse().ok()?)));
        match parsed {
            Some((index, count)) if index < count => Ok(Shard { index, count }),
            _ => Err(format!("expected K/N with 0 ≤ K < N (shards are numbered from 0), e.g. 0/8; got {text:?}")),
        }
    }

    /// Whether the run at `position` (in sweep order) is this shard's.
    pub fn takes(&self, position: usize) -> bool {
        position as u64 % self.count == self.index
    }

    /// The name of the record this shard leaves beside its runs.
    pub fn record_name(&self) -> String {
        format!("shard-{}-of-{}.json", self.index, self.count)
    }
}

/// What a shard did, `shard-K-of-N.json` beside its runs: enough for
/// [`merge`] to find every run's report and to know the sweep is whole.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardRecord {
    /// Which share of the runs.
    pub shard: Shard,
    /// The seeds swept, `start..end`.
    pub seeds: [u64; 2],
    /// The scenario labels, in sweep order.
    pub labels: Vec<String>,
    /// This shard's runs that failed: label, seed and error.
    pub failed: Vec<(String, u64, String)>,
}

/// Why a sweep stopped short of its results.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A file or folder could not be written (a full disk, a read-only
    /// folder): the sweep stops there.
    #[error("writing {}: {source}", path.display())]
    Write {
        /// The file or folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A run's outputs could not be written: the sweep stops there.
    #[error("{label} seed {seed}: {error}")]
    RunOutput {
        /// The scenario's label.
        label: String,
        /// The seed.
        seed: u64,
        /// What could not be written.
        error: String,
    },
    /// What the sweep was asked to do cannot be done safely: a label that
    /// is no safe folder name, or `--resume` into a folder that holds no
    /// interrupted sweep of the same runs. Nothing was written.
    #[error("{0}")]
    Refused(String),
}

impl SweepError {
    fn write(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
        move |source| SweepError::Write { path: path.to_owned(), source }
    }
}

/// Whether `label` is safe as the name of a sweep's folder for one
/// scenario: one path component under `--out`, neither hidden nor a name
/// the sweep itself writes there. `Err` says why not.
pub fn check_label(label: &str) -> Result<(), String> {
    let why = if label.is_empty() {
        "it is empty"
    } else if label.starts_with('.') {
        "it starts with `.` (`.` and `..` are not folders of their own, and a sweep keeps its unfinished files under names starting with `.`)"
    } else if label.contains(['/', '\\']) {
        "it holds a path separator"
    } else if label.chars().any(char::is_control) {
        "it holds a control character"
    } else if label.len() > MOST_LABEL_BYTES {
        "it is longer than 200 bytes"
    } else if label == "summary.csv"
        || label == "summary.json"
        || (label.starts_with("shard-") && label.ends_with(".json"))
    {
        "a sweep writes a file of that name beside the scenarios' folders"
    } else {
        return Ok(());
    };
    Err(format!("`{label}` cannot name a folder under --out: {why}"))
}

/// The longest label, in bytes: with `@layout` and room to spare, under the
/// 255 most file systems take.
const MOST_LABEL_BYTES: usize = 200;

/// How a sweep runs, besides what it runs and where it writes.
#[derive(Clone, Copy, Debug)]
pub struct SweepSettings<'a> {
    /// Runs at once (at least one is used).
    pub jobs: usize,
    /// Whether every run also writes its trajectory, log and plot.
    pub full_outputs: bool,
    /// Once set (Ctrl-C, SIGTERM), no further run starts, the runs under
    /// way are stopped and their outputs discarded, and no summary or
    /// record is written: the sweep ends [`Ended::Interrupted`].
    pub stop: &'a AtomicBool,
    /// Finish an interrupted sweep in the output folder: run only the runs
    /// whose `seed-N/report.json` is not there. Refused unless the folder
    /// holds an interrupted (or finished) sweep of the same runs, or is
    /// empty or absent.
    pub resume: bool,
    /// What else a resumed sweep must share with the interrupted one
    /// (digests of the scenario files, say), recorded in its plan.
    pub identity: &'a str,
}

impl SweepSettings<'static> {
    /// `jobs` threads, no interruption, no resumption.
    pub fn new(jobs: usize, full_outputs: bool) -> Self {
        static NEVER: AtomicBool = AtomicBool::new(false);
        SweepSettings { jobs, full_outputs, stop: &NEVER, resume: false, identity: "" }
    }
}

/// How a sweep that wrote everything it could ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Ended<T> {
    /// Every run ran; the summary (or shard record) is written.
    Done(T),
    /// Stopped by its stop flag: `done` of `total` runs are finished and
    /// kept, nothing half-written is left, and no summary was written.
    Interrupted {
        /// Runs finished (failed ones included).
        done: usize,
        /// Runs in the sweep (or shard).
        total: usize,
    },
}

/// What an unfinished sweep leaves in its output folder, so that
/// `--resume` knows it is finishing the same sweep: `.sweep-plan.json`, or
/// `.shard-K-of-N-plan.json`. Removed once the summary (or record) lands.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Plan {
    seeds: [u64; 2],
    labels: Vec<String>,
    shard: Option<Shard>,
    full_outputs: bool,
    identity: String,
}

impl Plan {
    fn file_name(&self) -> String {
        match self.shard {
            None => ".sweep-plan.json".into(),
            Some(shard) => format!(".shard-{}-of-{}-plan.json", shard.index, shard.count),
        }
    }

    /// The file a finished sweep (or shard) ends with.
    fn final_name(&self) -> String {
        self.shard.map_or_else(|| "summary.json".into(), |shard| shard.record_name())
    }

    /// Checks `out` against this plan (with `resume`) and records the plan
    /// there before any run starts.
    fn start(&self, out: &Path, resume: bool) -> Result<(), SweepError> {
        for label in &self.labels {
            check_label(label).map_err(SweepError::Refused)?;
        }
        if let Some(label) = self.labels.iter().enumerate().find_map(|(i, l)| self.labels[..i].contains(l).then_some(l))
        {
            return Err(SweepError::Refused(format!("the label `{label}` is given to two scenarios")));
        }
        let path = out.join(self.file_name());
        if resume {
            self.check_resumable(out, &path)?;
        }
        std::fs::create_dir_all(out).map_err(SweepError::write(out))?;
        let json = serde_json::to_string_pretty(self).expect("a plan always serialises") + "\n";
        crate::atomic::write(&path, json.as_bytes()).map_err(SweepError::write(&path))
    }

    /// Whether `out` holds this sweep unfinished (its plan at `path`), or
    /// finished, or nothing at all.
    fn check_resumable(&self, out: &Path, path: &Path) -> Result<(), SweepError> {
        let refuse = |why: String| Err(SweepError::Refused(format!("--resume: {why}")));
        match ubf_core::config::read_bounded(path, ubf_core::config::MOST_SETTINGS_BYTES) {
            Ok(bytes) => {
                return match serde_json::from_slice::<Plan>(&bytes) {
                    Ok(plan) if plan == *self => Ok(()),
                    Ok(_) => refuse(format!(
                        "{} records a sweep of other scenarios, seeds or options; finish it with the command \
                         that started it, or choose another --out",
                        path.display()
                    )),
                    Err(e) => refuse(format!("{}: {e}", path.display())),
                };
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(source) => return Err(SweepError::Write { path: path.to_owned(), source }),
        }
        // No plan: a finished sweep of the same seeds and scenarios, or a
        // folder with nothing of this sweep's in it.
        let finished = out.join(self.final_name());
        // A shard's record is read with the bound its merge reads it with.
        if let Ok(bytes) = ubf_core::config::read_bounded(&finished, merge::MOST_RECORD_BYTES) {
            let value: serde_json::Value = serde_json::from_slice(&bytes).unwrap_or_default();
            let labels: Option<Vec<&str>> = match self.shard {
                None => value["scenarios"].as_object().map(|s| s.keys().map(String::as_str).collect()),
                Some(_) => value["labels"].as_array().map(|l| l.iter().filter_map(|l| l.as_str()).collect()),
            };
            let mut ours: Vec<&str> = self.labels.iter().map(String::as_str).collect();
            if self.shard.is_none() {
                ours.sort_unstable();
            }
            let seeds = value["seeds"].as_array().map(|s| s.iter().filter_map(serde_json::Value::as_u64).collect());
            if labels != Some(ours) || seeds != Some(self.seeds.to_vec()) {
                return refuse(format!(
                    "{} is the end of a sweep of other scenarios or seeds; choose another --out",
                    finished.display()
                ));
            }
            return Ok(());
        }
        let empty = match std::fs::read_dir(out) {
            Ok(mut entries) => entries.next().is_none(),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => true,
            Err(source) => return Err(SweepError::Write { path: out.to_owned(), source }),
        };
        if empty || self.shard.is_some() {
            return Ok(());
        }
        refuse(format!(
            "{} holds neither an interrupted sweep ({}) nor a finished one ({})",
            out.display(),
            self.file_name(),
            self.final_name()
        ))
    }

    /// Removes the plan once the sweep's last file has landed.
    fn finish(&self, out: &Path) -> Result<(), SweepError> {
        let path = out.join(self.file_name());
        std::fs::remove_file(&path).map_err(SweepError::write(&path))
    }
}

/// Runs every item × seed on `jobs` threads, writing each run's
/// `report.json` (and, with `full_outputs`, its trajectory and plot) under
/// `out/<label>/seed-<n>/`, then `summary.csv` and `summary.json` in `out`.
pub fn sweep(
    items: &[SweepItem],
    seeds: Range<u64>,
    jobs: usize,
    out: &Path,
    full_outputs: bool,
) -> Result<SweepSummary, SweepError> {
    match sweep_with(items, seeds, &SweepSettings::new(jobs, full_outputs), out)? {
        Ended::Done(summary) => Ok(summary),
        Ended::Interrupted { .. } => unreachable!("nothing stops a sweep without a stop flag"),
    }
}

/// [`sweep`], stopped by `settings.stop` and resumed with
/// `settings.resume`: the summary is written only once every run is.
pub fn sweep_with(
    items: &[SweepItem],
    seeds: Range<u64>,
    settings: &SweepSettings,
    out: &Path,
) -> Result<Ended<SweepSummary>, SweepError> {
    let plan = plan(items, &seeds, None, settings);
    plan.start(out, settings.resume)?;
    let results = run_tasks(items, seeds.clone(), settings, out, |_| true)?;
    if settings.stop.load(Ordering::SeqCst) {
        return Ok(interrupted(&results));
    }
    let summary = summarise(&plan.labels, seeds, |task| match &results[task] {
        Some(outcome) => outcome.clone(),
        None => unreachable!("an unsharded sweep runs every task"),
    });
    write_summary(&summary, out)?;
    plan.finish(out)?;
    Ok(Ended::Done(summary))
}

fn plan(items: &[SweepItem], seeds: &Range<u64>, shard: Option<Shard>, settings: &SweepSettings) -> Plan {
    Plan {
        seeds: [seeds.start, seeds.end],
        labels: items.iter().map(|i| i.label.clone()).collect(),
        shard,
        full_outputs: settings.full_outputs,
        identity: settings.identity.to_owned(),
    }
}

/// How far an interrupted sweep got.
fn interrupted<T>(results: &[Option<Result<Fields, String>>]) -> Ended<T> {
    Ended::Interrupted { done: results.iter().flatten().count(), total: results.len() }
}

/// Runs `shard`'s share of every item × seed, as [`sweep`] does, and
/// writes its record (`shard-K-of-N.json`) in `out` instead of a summary.
pub fn sweep_shard(
    items: &[SweepItem],
    seeds: Range<u64>,
    shard: Shard,
    jobs: usize,
    out: &Path,
    full_outputs: bool,
) -> Result<ShardRecord, SweepError> {
    match sweep_shard_with(items, seeds, shard, &SweepSettings::new(jobs, full_outputs), out)? {
        Ended::Done(record) => Ok(record),
        Ended::Interrupted { .. } => unreachable!("nothing stops a shard without a stop flag"),
    }
}

/// [`sweep_shard`], stopped and resumed as [`sweep_with`] is: the record
/// is written only once every run of the shard is.
pub fn sweep_shard_with(
    items: &[SweepItem],
    seeds: Range<u64>,
    shard: Shard,
    settings: &SweepSettings,
    out: &Path,
) -> Result<Ended<ShardRecord>, SweepError> {
    let plan = plan(items, &seeds, Some(shard), settings);
    plan.start(out, settings.resume)?;
    let results = run_tasks(items, seeds.clone(), settings, out, |task| shard.takes(task))?;
    if settings.stop.load(Ordering::SeqCst) {
        let mine: Vec<_> = results.into_iter().enumerate().filter(|(t, _)| shard.takes(*t)).map(|(_, r)| r).collect();
        return Ok(interrupted(&mine));
    }
    let per_item = (seeds.end - seeds.start) as usize;
    let failed = results
        .iter()
        .enumerate()
        .filter_map(|(task, r)| match r {
            Some(Err(e)) => {
                Some((items[task / per_item].label.clone(), seeds.start + (task % per_item) as u64, e.clone()))
            }
            _ => None,
        })
        .collect();
    let record = ShardRecord { shard, seeds: plan.seeds, labels: plan.labels.clone(), failed };
    let path = out.join(shard.record_name());
    let json = serde_json::to_string_pretty(&record).expect("a record always serialises") + "\n";
    crate::atomic::write(&path, json.as_bytes()).map_err(SweepError::write(&path))?;
    plan.finish(out)?;
    Ok(Ended::Done(record))
}

/// A finished run's numeric report fields, as [`numeric_leaves`] reads
/// them.
type Fields = Vec<(String, f64)>;

/// Runs the tasks (item × seed, item by item) that `chosen` picks, on
/// `settings.jobs` threads: each task's numeric fields or error, `None` for
/// the tasks not chosen and those the stop flag kept from finishing. The
/// first failed write stops the sweep and is the error.
fn run_tasks(
    items: &[SweepItem],
    seeds: Range<u64>,
    settings: &SweepSettings,
    out: &Path,
    chosen: impl Fn(usize) -> bool,
) -> Result<Vec<Option<Result<Fields, String>>>, SweepError> {
    let tasks: Vec<(usize, usize, u64)> = (0..items.len())
        .flat_map(|i| seeds.clone().map(move |s| (i, s)))
        .enumerate()
        .filter(|(task, _)| chosen(*task))
        .map(|(task, (i, s))| (task, i, s))
        .collect();
    // Set by the first failed write: no run starts after it.
    let halted = AtomicBool::new(false);
    let results = run_parallel(&tasks, settings.jobs, |&(_, item, seed)| {
        if settings.stop.load(Ordering::SeqCst) || halted.load(Ordering::SeqCst) {
            return None;
        }
        let item = &items[item];
        let folder = out.join(&item.label);
        if settings.resume {
            if let Some(fields) = finished_run(&folder, seed) {
                return Some(Ok(Ok(fields)));
            }
        }
        let result = run_one(&item.scenario, seed, &folder, settings.full_outputs, settings.stop);
        match result {
            RunOutcome::Finished(fields) => Some(Ok(Ok(fields))),
            RunOutcome::Failed(error) => Some(Ok(Err(error))),
            RunOutcome::Stopped => None,
            RunOutcome::WriteFailed(error) => {
                halted.store(true, Ordering::SeqCst);
                Some(Err(SweepError::RunOutput { label: item.label.clone(), seed, error }))
            }
        }
    });
    let mut all: Vec<Option<Result<Fields, String>>> =
        (0..items.len() * (seeds.end - seeds.start) as usize).map(|_| None).collect();
    for ((task, _, _), result) in tasks.into_iter().zip(results) {
        all[task] = result.transpose()?;
    }
    Ok(all)
}

/// The numeric fields of the finished run of `seed` in `folder` (one
/// scenario's), if it has finished: its `seed-N/report.json` is there and
/// reads.
fn finished_run(folder: &Path, seed: u64) -> Option<Fields> {
    let path = folder.join(seed_folder(seed)).join("report.json");
    let bytes = ubf_core::config::read_bounded(&path, MOST_REPORT_BYTES).ok()?;
    let report: serde_json::Value = serde_json::from_slice(&bytes).ok()?;
    Some(numeric_leaves(&report))
}

/// The largest run report a sweep reads back (resuming, merging): a
/// report is a few kilobytes.
const MOST_REPORT_BYTES: u64 = 1 << 20;

fn seed_folder(seed: u64) -> String {
    format!("seed-{seed}")
}

/// The summary of every label × seed, from each task's numeric fields or
/// error (tasks item by item, seed by seed). The one place summaries are
/// made, so that a merged sweep's is the same as a single one's.
fn summarise(
    labels: &[String],
    seeds: Range<u64>,
    outcome: impl Fn(usize) -> Result<Vec<(String, f64)>, String>,
) -> SweepSummary {
    let per_item = (seeds.end - seeds.start) as usize;
    let mut scenarios = BTreeMap::new();
    for (i, label) in labels.iter().enumerate() {
        let mut values: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        let mut failed = Vec::new();
        let mut runs = 0;
        for (k, seed) in seeds.clone().enumerate() {
            match outcome(i * per_item + k) {
                Ok(fields) => {
                    runs += 1;
                    for (name, v) in fields {
                        values.entry(name).or_default().push(v);
                    }
                }
                Err(e) => failed.push((seed, e)),
            }
        }
        let fields = values.into_iter().map(|(k, v)| (k, stats(&v))).collect();
        scenarios.insert(label.clone(), ScenarioSummary { runs, failed, fields });
    }
    SweepSummary { seeds: [seeds.start, seeds.end], scenarios }
}

/// A progress bar on stderr for `len` items called `unit` ("runs",
/// "pairs"); indicatif hides it when stderr is not a terminal.
pub fn progress_bar(len: u64, unit: &str) -> ProgressBar {
    let progress = ProgressBar::new(len);
    let template = format!("{{bar:40}} {{pos}}/{{len}} {unit}  {{elapsed_precise}} elapsed, {{eta}} to go");
    progress.set_style(ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar()));
    progress
}

/// Runs `work` on every task on `jobs` threads, with a progress bar on
/// stderr (hidden when stderr is not a terminal), and returns the results in
/// the tasks' order whatever order they finished in.
pub fn run_parallel<T: Sync, R: Send>(tasks: &[T], jobs: usize, work: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let progress = progress_bar(tasks.len() as u64, "runs");
    let next = AtomicUsize::new(0);
    let (sender, receiver) = crossbeam_channel::unbounded();
    std::thread::scope(|scope| {
        for _ in 0..jobs.max(1) {
            let sender = sender.clone();
            let (next, progress, work) = (&next, &progress, &work);
            scope.spawn(move || loop {
                let index = next.fetch_add(1, Ordering::Relaxed);
                let Some(task) = tasks.get(index) else { break };
                let result = work(task);
                progress.inc(1);
                if sender.send((index, result)).is_err() {
                    break;
                }
            });
        }
    });
    drop(sender);
    progress.finish_and_clear();
    let mut results: Vec<(usize, R)> = receiver.into_iter().collect();
    results.sort_by_key(|(index, _)| *index);
    results.into_iter().map(|(_, r)| r).collect()
}

/// How one run of a sweep ended.
enum RunOutcome {
    /// Its report (and outputs) landed in `seed-N/`.
    Finished(Fields),
    /// It failed; what it wrote (with full outputs) is in `seed-N/`,
    /// without a report.
    Failed(String),
    /// The stop flag stopped it; nothing of it is left.
    Stopped,
    /// Its outputs could not be written; nothing of it is left.
    WriteFailed(String),
}

/// Runs `scenario` with `seed` into `.seed-N.partial/` in `folder`, and
/// renames that to `seed-N/` once its report is in: a `seed-N/` holding a
/// `report.json` is a finished run, whatever stopped the sweep when.
fn run_one(scenario: &Scenario, seed: u64, folder: &Path, full_outputs: bool, stop: &AtomicBool) -> RunOutcome {
    let done = folder.join(seed_folder(seed));
    let partial = folder.join(format!(".{}.partial", seed_folder(seed)));
    let written = |path: &Path, e: std::io::Error| RunOutcome::WriteFailed(format!("writing {}: {e}", path.display()));
    // What an earlier, stopped or failed, run of this seed left.
    for leftover in [&partial, &done] {
        if let Err(e) = remove_folder(leftover) {
            return written(leftover, e);
        }
    }
    if let Err(e) = std::fs::create_dir_all(folder) {
        return written(folder, e);
    }
    let outputs = full_outputs.then_some(Outputs { dir: &partial, images: false, rosbag: false });
    let result = run_until(scenario, seed, outputs, None, stop).and_then(|report| {
        if !full_outputs {
            std::fs::create_dir_all(&partial).map_err(|source| RunError::Output { path: partial.clone(), source })?;
            write_report(&report, &partial.join("report.json"))?;
        }
        Ok(report)
    });
    let stopped = stop.load(Ordering::SeqCst);
    match result {
        Ok(report) if report.end == EndReason::Interrupted => {
            let _ = remove_folder(&partial);
            RunOutcome::Stopped
        }
        Ok(report) => match std::fs::rename(&partial, &done) {
            Ok(()) => RunOutcome::Finished(numeric_fields(&report)),
            Err(e) => {
                let _ = remove_folder(&partial);
                written(&done, e)
            }
        },
        Err(_) if stopped => {
            let _ = remove_folder(&partial);
            RunOutcome::Stopped
        }
        Err(e) if is_write_failure(&e) => {
            let _ = remove_folder(&partial);
            RunOutcome::WriteFailed(e.to_string())
        }
        Err(e) => {
            // A failed run keeps what it logged, for a look at why.
            if partial.exists() {
                if let Err(rename) = std::fs::rename(&partial, &done) {
                    let _ = remove_folder(&partial);
                    return written(&done, rename);
                }
            }
            RunOutcome::Failed(e.to_string())
        }
    }
}

/// Removes a folder and what it holds, if it is there.
fn remove_folder(path: &Path) -> std::io::Result<()> {
    match std::fs::remove_dir_all(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

/// Whether a run failed writing its outputs (an I/O error anywhere in its
/// chain of causes), not in what it ran.
fn is_write_failure(error: &RunError) -> bool {
    let mut cause: Option<&(dyn std::error::Error + 'static)> = Some(error);
    while let Some(e) = cause {
        if e.is::<std::io::Error>() {
            return true;
        }
        cause = e.source();
    }
    matches!(error, RunError::Output { .. })
}

/// Writes `summary.csv` and `summary.json` into `out`, each atomically.
fn write_summary(summary: &SweepSummary, out: &Path) -> Result<(), SweepError> {
    std::fs::create_dir_all(out).map_err(SweepError::write(out))?;
    let mut csv = String::from("scenario,field,n,mean,sd,ci95_low,ci95_high\n");
    for (label, s) in &summary.scenarios {
        for (field, f) in &s.fields {
            let (low, high) = f.ci95.map_or((String::new(), String::new()), |[l, h]| (l.to_string(), h.to_string()));
            csv.push_str(&format!("{label},{field},{},{},{},{low},{high}\n", f.n, f.mean, f.sd));
        }
    }
    let csv_path = out.join("summary.csv");
    crate::atomic::write(&csv_path, csv.as_bytes()).map_err(SweepError::write(&csv_path))?;
    let json = serde_json::to_string_pretty(summary).expect("a summary always serialises") + "\n";
    let json_path = out.join("summary.json");
    crate::atomic::write(&json_path, json.as_bytes()).map_err(SweepError::write(&json_path))
}
