//! Many runs: every scenario × every seed, in parallel, summarised.
//!
//! The summary depends only on the scenarios and seeds, never on how many
//! jobs ran them or in which order they finished: results are gathered by
//! job number, and wall time (the one thing that varies) stays out of it.

use crate::run::{run, write_report, RunError, RunReport};
use crate::scenario::Scenario;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
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
    walk("", &serde_json::to_value(report).expect("a report always serialises"), &mut out);
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
    let tasks: Vec<(usize, u64)> = (0..items.len()).flat_map(|i| seeds.clone().map(move |s| (i, s))).collect();
    let results = run_parallel(&tasks, jobs, |&(item, seed)| {
        let dir = out.join(&items[item].label).join(format!("seed-{seed}"));
        run_one(&items[item].scenario, seed, &dir, full_outputs).map_err(|e| e.to_string())
    });
    let mut scenarios = BTreeMap::new();
    for (i, item) in items.iter().enumerate() {
        let mut values: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        let mut failed = Vec::new();
        let mut runs = 0;
        for (task, result) in tasks.iter().zip(&results).filter(|(t, _)| t.0 == i) {
            match result {
                Ok(report) => {
                    runs += 1;
                    for (name, v) in numeric_fields(report) {
                        values.entry(name).or_default().push(v);
                    }
                }
                Err(e) => failed.push((task.1, e.clone())),
            }
        }
        let fields = values.into_iter().map(|(k, v)| (k, stats(&v))).collect();
        scenarios.insert(item.label.clone(), ScenarioSummary { runs, failed, fields });
    }
    let summary = SweepSummary { seeds: [seeds.start, seeds.end], scenarios };
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
