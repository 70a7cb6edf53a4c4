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

use crate::run::{run, write_report, RunError, RunReport};
use crate::scenario::Scenario;
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// One scenario to sweep and the directory name its runs go under.
pub struct SweepItem {
    /// The scenario.
    pub scenario: Scenario,
    /// Directory name under the sweep's output directory.
    pub label: String,
}

/// Mean, spread and 95 % confidence interval of one report field.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FieldStats {
    /// Runs that reported the field.
    pub n: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one run).
    pub sd: f64,
    /// 95 % confidence interval of the mean; `None` below two runs, where
    /// it means nothing.
    pub ci95: Option<[f64; 2]>,
    /// How the interval was found: `t` (Student's t), or `bootstrap` (the
    /// percentile bootstrap of the mean) for a field with no negative value
    /// whose t interval would reach below zero.
    pub ci95_method: Option<&'static str>,
}

/// Resamples of the bootstrap interval.
const BOOTSTRAP_RESAMPLES: usize = 4000;

/// The percentile bootstrap 95 % interval of the mean of `values`, with a
/// fixed seed so that a summary is reproducible.
fn bootstrap_ci95(values: &[f64]) -> [f64; 2] {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let n = values.len();
    let mut means: Vec<f64> = (0..BOOTSTRAP_RESAMPLES)
        .map(|_| (0..n).map(|_| values[rng.random_range(0..n)]).sum::<f64>() / n as f64)
        .collect();
    means.sort_by(f64::total_cmp);
    let at = |q: f64| means[((q * (BOOTSTRAP_RESAMPLES - 1) as f64).round() as usize).min(BOOTSTRAP_RESAMPLES - 1)];
    [at(0.025), at(0.975)]
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

/// Why a sweep could not write its results.
#[derive(Debug, thiserror::Error)]
#[error("writing {}: {source}", path.display())]
pub struct SweepError {
    path: PathBuf,
    source: std::io::Error,
}

/// The two-sided 95 % quantile of Student's t with `dof` degrees of freedom.
pub fn t95(dof: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145, 2.131,
        2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042,
    ];
    match dof {
        0 => f64::NAN,
        1..=30 => TABLE[dof - 1],
        _ => {
            // Cornish–Fisher expansion around the normal quantile; within
            // 1e-4 of the exact value from 30 degrees of freedom up.
            let z: f64 = 1.959_964;
            let v = dof as f64;
            z + (z.powi(3) + z) / (4.0 * v) + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * v * v)
        }
    }
}

/// Mean, standard deviation and confidence interval of `values`.
pub fn stats(values: &[f64]) -> FieldStats {
    let n = values.len();
    let mean = values.iter().sum::<f64>() / n as f64;
    let sd = if n > 1 { (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt() } else { 0.0 };
    if n < 2 {
        return FieldStats { n, mean, sd, ci95: None, ci95_method: None };
    }
    let half = t95(n - 1) * sd / (n as f64).sqrt();
    let (ci95, method) = if mean - half < 0.0 && values.iter().all(|v| *v >= 0.0) {
        (bootstrap_ci95(values), "bootstrap")
    } else {
        ([mean - half, mean + half], "t")
    };
    FieldStats { n, mean, sd, ci95: Some(ci95), ci95_method: Some(method) }
}

/// Every numeric leaf of a report, with dotted names.
fn numeric_fields(report: &RunReport) -> Vec<(String, f64)> {
    numeric_leaves(&serde_json::to_value(report).expect("a report always serialises"))
}

/// Every numeric leaf of a report read as JSON, with dotted names (booleans
/// as 0 and 1), leaving out `seed` and `wall_time_s`.
fn numeric_leaves(report: &serde_json::Value) -> Vec<(String, f64)> {
    fn walk(prefix: &str, value: &serde_json::Value, out: &mut Vec<(String, f64)>) {
        match value {
            serde_json::Value::Number(n) => out.extend(n.as_f64().map(|v| (prefix.to_owned(), v))),
            serde_json::Value::Bool(b) => out.push((prefix.to_owned(), f64::from(u8::from(*b)))),
            serde_json::Value::Object(map) => {
                for (key, v) in map {
                    let name = if prefix.is_empty() { key.clone() } else { format!("{prefix}.{key}") };
                    walk(&name, v, out);
                }
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk("", report, &mut out);
    out.retain(|(name, _)| name != "seed" && name != "wall_time_s");
    out
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
    let results = run_tasks(items, seeds.clone(), jobs, out, full_outputs, |_| true);
    let labels: Vec<String> = items.iter().map(|i| i.label.clone()).collect();
    let summary = summarise(&labels, seeds, |task| match &results[task] {
        Some(Ok(report)) => Ok(numeric_fields(report)),
        Some(Err(e)) => Err(e.clone()),
        None => unreachable!("an unsharded sweep runs every task"),
    });
    write_summary(&summary, out)?;
    Ok(summary)
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
    let results = run_tasks(items, seeds.clone(), jobs, out, full_outputs, |task| shard.takes(task));
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
    let record = ShardRecord {
        shard,
        seeds: [seeds.start, seeds.end],
        labels: items.iter().map(|i| i.label.clone()).collect(),
        failed,
    };
    let path = out.join(shard.record_name());
    let fail = |path: PathBuf| move |source| SweepError { path, source };
    std::fs::create_dir_all(out).map_err(fail(out.to_owned()))?;
    let json = serde_json::to_string_pretty(&record).expect("a record always serialises") + "\n";
    std::fs::write(&path, json).map_err(fail(path.clone()))?;
    Ok(record)
}

/// Runs the tasks (item × seed, item by item) that `chosen` picks, on
/// `jobs` threads; `None` for the others.
fn run_tasks(
    items: &[SweepItem],
    seeds: Range<u64>,
    jobs: usize,
    out: &Path,
    full_outputs: bool,
    chosen: impl Fn(usize) -> bool,
) -> Vec<Option<Result<RunReport, String>>> {
    let tasks: Vec<(usize, usize, u64)> = (0..items.len())
        .flat_map(|i| seeds.clone().map(move |s| (i, s)))
        .enumerate()
        .filter(|(task, _)| chosen(*task))
        .map(|(task, (i, s))| (task, i, s))
        .collect();
    let results = run_parallel(&tasks, jobs, |&(_, item, seed)| {
        let dir = out.join(&items[item].label).join(format!("seed-{seed}"));
        run_one(&items[item].scenario, seed, &dir, full_outputs).map_err(|e| e.to_string())
    });
    let mut all: Vec<Option<Result<RunReport, String>>> =
        (0..items.len() * (seeds.end - seeds.start) as usize).map(|_| None).collect();
    for ((task, _, _), result) in tasks.into_iter().zip(results) {
        all[task] = Some(result);
    }
    all
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

/// Why shards could not be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A file could not be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A record or report is not what a shard writes.
    #[error("{}: {message}", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the line and column where JSON knows them.
        message: String,
    },
    /// The shards do not make one whole sweep.
    #[error("{0}")]
    Incomplete(String),
    /// The summary could not be written.
    #[error(transparent)]
    Write(#[from] SweepError),
}

/// Merges the shards recorded in `dirs` (each holding one or more
/// `shard-K-of-N.json` and those shards' runs) into the summary one sweep
/// would have written, and writes `summary.csv` and `summary.json` into
/// `out`. Refuses shards of different sweeps, a shard twice, and a
/// missing one.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<SweepSummary, MergeError> {
    let mut records: Vec<(PathBuf, ShardRecord)> = Vec::new();
    for dir in dirs {
        let entries = std::fs::read_dir(dir).map_err(|source| MergeError::Read { path: dir.clone(), source })?;
        let mut names: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("shard-") && n.ends_with(".json"))
            })
            .collect();
        names.sort();
        for path in names {
            let text =
                std::fs::read_to_string(&path).map_err(|source| MergeError::Read { path: path.clone(), source })?;
            let record: ShardRecord = serde_json::from_str(&text)
                .map_err(|e| MergeError::Malformed { path: path.clone(), message: e.to_string() })?;
            records.push((dir.clone(), record));
        }
    }
    let Some((_, first)) = records.first() else {
        let shown: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
        return Err(MergeError::Incomplete(format!("no shard records (shard-K-of-N.json) in {}", shown.join(", "))));
    };
    let (seeds, labels, count) = (first.seeds, first.labels.clone(), first.shard.count);
    let mut owner: Vec<Option<usize>> = vec![None; count as usize];
    for (n, (dir, record)) in records.iter().enumerate() {
        if record.seeds != seeds || record.labels != labels || record.shard.count != count {
            return Err(MergeError::Incomplete(format!(
                "{}: {} belongs to another sweep (seeds {:?}, scenarios {:?}, {} shards; expected {:?}, {:?}, {count})",
                dir.display(),
                record.shard.record_name(),
                record.seeds,
                record.labels,
                record.shard.count,
                seeds,
                labels
            )));
        }
        let slot = &mut owner[record.shard.index as usize];
        if slot.is_some() {
            return Err(MergeError::Incomplete(format!("shard {}/{count} is recorded twice", record.shard.index)));
        }
        *slot = Some(n);
    }
    let missing: Vec<String> =
        owner.iter().enumerate().filter(|(_, o)| o.is_none()).map(|(k, _)| format!("{k}/{count}")).collect();
    if !missing.is_empty() {
        return Err(MergeError::Incomplete(format!("missing shards: {}", missing.join(", "))));
    }
    let range = seeds[0]..seeds[1];
    let per_item = (seeds[1] - seeds[0]) as usize;
    // Read every run's report first, so that a broken one is an error, not
    // a failed run.
    let mut outcomes: Vec<Result<Vec<(String, f64)>, String>> = Vec::with_capacity(labels.len() * per_item);
    for task in 0..labels.len() * per_item {
        let (label, seed) = (&labels[task / per_item], seeds[0] + (task % per_item) as u64);
        let (dir, record) = &records[owner[(task as u64 % count) as usize].expect("every shard is present")];
        if let Some((_, _, error)) = record.failed.iter().find(|(l, s, _)| l == label && *s == seed) {
            outcomes.push(Err(error.clone()));
            continue;
        }
        let path = dir.join(label).join(format!("seed-{seed}")).join("report.json");
        let text = std::fs::read_to_string(&path).map_err(|source| MergeError::Read { path: path.clone(), source })?;
        let report: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| MergeError::Malformed { path: path.clone(), message: e.to_string() })?;
        outcomes.push(Ok(numeric_leaves(&report)));
    }
    let summary = summarise(&labels, range, |task| outcomes[task].clone());
    write_summary(&summary, out)?;
    Ok(summary)
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

fn run_one(scenario: &Scenario, seed: u64, dir: &Path, full_outputs: bool) -> Result<RunReport, RunError> {
    if full_outputs {
        return run(scenario, seed, Some(dir));
    }
    let report = run(scenario, seed, None)?;
    std::fs::create_dir_all(dir).map_err(|source| RunError::Output { path: dir.to_owned(), source })?;
    write_report(&report, &dir.join("report.json"))?;
    Ok(report)
}

fn write_summary(summary: &SweepSummary, out: &Path) -> Result<(), SweepError> {
    let fail = |path: PathBuf| move |source| SweepError { path, source };
    std::fs::create_dir_all(out).map_err(fail(out.to_owned()))?;
    let mut csv = String::from("scenario,field,n,mean,sd,ci95_low,ci95_high\n");
    for (label, s) in &summary.scenarios {
        for (field, f) in &s.fields {
            let (low, high) = f.ci95.map_or((String::new(), String::new()), |[l, h]| (l.to_string(), h.to_string()));
            csv.push_str(&format!("{label},{field},{},{},{},{low},{high}\n", f.n, f.mean, f.sd));
        }
    }
    let csv_path = out.join("summary.csv");
    std::fs::write(&csv_path, csv).map_err(fail(csv_path.clone()))?;
    let json = serde_json::to_string_pretty(summary).expect("a summary always serialises") + "\n";
    let json_path = out.join("summary.json");
    std::fs::write(&json_path, json).map_err(fail(json_path.clone()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_quantiles() {
        assert_eq!(t95(1), 12.706);
        assert_eq!(t95(29), 2.045);
        // Exact values: 2.0211 at 40, 1.9840 at 100.
        assert!((t95(40) - 2.0211).abs() < 2e-4);
        assert!((t95(100) - 1.9840).abs() < 2e-4);
    }

    #[test]
    fn stats_of_a_known_sample() {
        let s = stats(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(s.mean, 2.5);
        assert!((s.sd - 1.290_994).abs() < 1e-6);
        let half = 3.182 * s.sd / 2.0;
        assert!((s.ci95.unwrap()[1] - (2.5 + half)).abs() < 1e-12);
        assert_eq!(s.ci95_method, Some("t"));
        // One run: no interval at all, not a zero-width one.
        assert_eq!(stats(&[5.0]).ci95, None);
        // Errors cannot be negative, nor can their interval: three skewed
        // end-point errors whose t interval reaches −6.7 m.
        let skewed = stats(&[0.3, 0.5, 24.0]);
        let [low, high] = skewed.ci95.unwrap();
        assert_eq!(skewed.ci95_method, Some("bootstrap"));
        assert!((0.3..=24.0).contains(&low) && low < skewed.mean && skewed.mean < high && high <= 24.0, "{skewed:?}");
        // A field that can be negative keeps its t interval.
        assert_eq!(stats(&[-1.0, 0.5, 2.0]).ci95_method, Some("t"));
    }
}
