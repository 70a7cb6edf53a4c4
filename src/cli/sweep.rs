//! `ubf sweep` and `ubf sweep merge`.

use super::shard::ShardSpec;
use super::{CliError, Exit, Outcome};
use crate::scenario::Scenario;
use crate::sweep::{Ended, Shard, SweepError, SweepItem, SweepSettings};
use std::path::{Path, PathBuf};
use ubf_core::Registry;

/// The most runs a sweep starts without `--huge`.
const MOST_SWEEP_RUNS: u64 = 100_000;

/// What one `ubf sweep` was asked to do.
pub(super) struct SweepRequest<'a> {
    pub files: &'a [PathBuf],
    pub seeds: std::ops::Range<u64>,
    pub layout_seeds: Option<&'a [u64]>,
    pub shard: Option<ShardSpec>,
    pub jobs: Option<usize>,
    pub out: &'a Path,
    pub trajectories: bool,
    pub overwrite: bool,
    pub resume: bool,
    pub huge: bool,
}

/// Runs every scenario with every seed (or a shard's share of them) and
/// summarises; exit code 1 if any run failed, 130 if Ctrl-C or SIGTERM
/// stopped it (`--resume` finishes it).
pub(super) fn command(registry: &Registry, request: SweepRequest) -> Outcome {
    let SweepRequest { files, seeds, layout_seeds, shard, jobs, out, trajectories, overwrite, resume, huge } = request;
    let shard = shard.map(super::shard::resolve_here).transpose()?;
    let share = shard.map_or(1, |s| s.count);
    let layouts = layout_seeds.map_or(1, <[u64]>::len) as u64;
    let runs = (seeds.end - seeds.start).saturating_mul(files.len() as u64).saturating_mul(layouts).div_ceil(share);
    if runs > MOST_SWEEP_RUNS && !huge {
        return Err(CliError::bad_input(format!(
            "{runs} runs ({} seeds × {} files × {layouts} layouts), more than {MOST_SWEEP_RUNS}: each \
             leaves a directory and a report; narrow --seeds, or pass --huge to run them anyway",
            seeds.end - seeds.start,
            files.len()
        )));
    }
    // Every input is read and checked before anything in --out changes.
    let mut items: Vec<SweepItem> = Vec::new();
    let mut identity = format!("ubf {}", env!("CARGO_PKG_VERSION"));
    for file in files {
        let loaded = if huge { Scenario::load_unbounded(registry, file) } else { Scenario::load(registry, file) };
        let scenario = loaded.map_err(CliError::bad_input)?;
        if trajectories && !huge {
            scenario.check_logs().map_err(|e| CliError::bad_input(format!("{}: {e}", file.display())))?;
        }
        let stem = label_of(file).map_err(CliError::bad_input)?;
        let bytes = ubf_core::config::read_bounded(file, ubf_core::config::MOST_SETTINGS_BYTES)
            .map_err(|e| CliError::bad_input(format!("{}: {e}", file.display())))?;
        identity.push_str(&format!("; {stem}: {:016x}", fnv1a(&bytes)));
        for (scenario, stem) in in_layouts(scenario, &stem, layout_seeds)
            .map_err(|e| CliError::bad_input(format!("{}: {e}", file.display())))?
        {
            let mut label = stem.clone();
            let mut n = 2;
            while items.iter().any(|i| i.label == label) {
                label = format!("{stem}_{n}");
                n += 1;
            }
            crate::sweep::check_label(&label).map_err(|e| CliError::bad_input(format!("{}: {e}", file.display())))?;
            items.push(SweepItem { scenario, label });
        }
    }
    if !resume {
        match shard {
            None => super::out_dir::prepare(out, &super::out_dir::SWEEP, overwrite)?,
            Some(shard) => clear_shard_output(out, shard, overwrite)?,
        }
    }
    let jobs = jobs.unwrap_or_else(super::cores);
    let stop = crate::drive::install_stop_flag();
    let _once = super::repeated_warnings::say_once();
    let settings = SweepSettings { jobs, full_outputs: trajectories, stop: &stop, resume, identity: &identity };
    let stopwatch = ubf_core::Stopwatch::start();
    let refused = |e: SweepError| match e {
        SweepError::Refused(_) => CliError::bad_input(e),
        _ => CliError::failed(e),
    };
    let failed: Vec<(String, u64, String)> = match shard {
        Some(shard) => {
            let record =
                match crate::sweep::sweep_shard_with(&items, seeds.clone(), shard, &settings, out).map_err(refused)? {
                    Ended::Done(record) => record,
                    Ended::Interrupted { done, total } => return Ok(interrupted(done, total)),
                };
            let total = items.len() * (seeds.end - seeds.start) as usize;
            let runs = (0..total).filter(|&t| shard.takes(t)).count();
            println!(
                "shard {}/{}: {} in {:.2} s on {}; {} failed",
                shard.index,
                shard.count,
                counted(runs, "run"),
                stopwatch.elapsed_s(),
                counted(jobs, "job"),
                record.failed.len()
            );
            println!(
                "record: {}; once every shard has run: ubf sweep merge DIR...",
                out.join(shard.record_name()).display()
            );
            record.failed
        }
        None => {
            let summary = match crate::sweep::sweep_with(&items, seeds.clone(), &settings, out).map_err(refused)? {
                Ended::Done(summary) => summary,
                Ended::Interrupted { done, total } => return Ok(interrupted(done, total)),
            };
            let runs: usize = summary.scenarios.values().map(|s| s.runs).sum();
            let failed: usize = summary.scenarios.values().map(|s| s.failed.len()).sum();
            println!(
                "{} of {} × seeds {}..{} in {:.2} s on {}; {failed} failed",
                counted(runs, "run"),
                counted(items.len(), "scenario"),
                seeds.start,
                seeds.end,
                stopwatch.elapsed_s(),
                counted(jobs, "job")
            );
            println!("summary: {}/summary.csv, {}/summary.json", out.display(), out.display());
            let by_scenario = summary.scenarios.iter();
            by_scenario
                .flat_map(|(label, s)| s.failed.iter().map(move |(seed, error)| (label.clone(), *seed, error.clone())))
                .collect()
        }
    };
    for (label, seed, error) in &failed {
        eprintln!("error: {label} seed {seed}: {error}");
    }
    Ok(if failed.is_empty() { Exit::Success } else { Exit::Failure })
}

/// Says how far an interrupted sweep got and how to finish it.
fn interrupted(done: usize, total: usize) -> Exit {
    eprintln!(
        "interrupted: {done} of {total} runs finished and kept, none half-written, no summary yet; \
         the same command with --resume runs the other {}",
        total - done
    );
    Exit::Interrupted
}

/// The label of a scenario file's runs: its name without `.ron`, refused
/// when it cannot name a folder under `--out` (`...ron` would be `..`).
fn label_of(file: &Path) -> Result<String, String> {
    let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    crate::sweep::check_label(&stem).map_err(|e| {
        format!("{}: its runs are labelled by the file's name without `.ron`, and {e}; rename the file", file.display())
    })?;
    Ok(stem)
}

/// The 64-bit FNV-1a hash of `bytes`: what a resumed sweep checks the
/// scenario files against (a changed file is another sweep).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |hash, &b| (hash ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

/// `scenario` once per layout seed, its random landmarks redrawn from each
/// and its label `stem@seed`; or as it is, labelled `stem`, without
/// layout seeds.
fn in_layouts(scenario: Scenario, stem: &str, layout_seeds: Option<&[u64]>) -> Result<Vec<(Scenario, String)>, String> {
    let Some(layout_seeds) = layout_seeds else { return Ok(vec![(scenario, stem.to_owned())]) };
    if scenario.world.random_landmarks.is_none() {
        return Err("--layout-seeds redraws a scenario's `random_landmarks`, and this one has none".into());
    }
    Ok(layout_seeds
        .iter()
        .map(|&seed| {
            let mut redrawn = scenario.clone();
            if let Some(landmarks) = redrawn.world.random_landmarks.as_mut() {
                landmarks.seed = Some(seed);
            }
            (redrawn, format!("{stem}@{seed}"))
        })
        .collect())
}

/// Combines shards into the summary one sweep writes.
pub(super) fn merge(dirs: &[PathBuf], out: Option<&Path>) -> Outcome {
    let Some(out) = out.or(dirs.first().map(PathBuf::as_path)) else {
        return Err(CliError::bad_input("no shard directories given"));
    };
    let summary = crate::sweep::merge(dirs, out).map_err(|e| match e {
        crate::sweep::MergeError::Write(_) => CliError::failed(e),
        _ => CliError::bad_input(e),
    })?;
    let runs: usize = summary.scenarios.values().map(|s| s.runs).sum();
    let failed: usize = summary.scenarios.values().map(|s| s.failed.len()).sum();
    println!("merged {} of {}; {failed} failed", counted(runs, "run"), counted(summary.scenarios.len(), "scenario"));
    println!("summary: {}/summary.csv, {}/summary.json", out.display(), out.display());
    Ok(Exit::Success)
}

/// Makes `out` ready for one shard of a sweep: other shards' output may be
/// there (shards often share a directory), but this shard's record only
/// with `overwrite`.
fn clear_shard_output(out: &Path, shard: Shard, overwrite: bool) -> Result<(), CliError> {
    let record = out.join(shard.record_name());
    if !record.exists() {
        return Ok(());
    }
    if !overwrite {
        return Err(CliError::bad_input(format!(
            "{} exists: this shard has run before. Pass --overwrite to run it again",
            record.display()
        )));
    }
    std::fs::remove_file(&record)
        .map_err(|e| CliError::failed(format!("cannot remove {} to run the shard again: {e}", record.display())))
}

/// Parses `A..B`, `A..=B` or `N` into a range of seeds.
pub(super) fn parse_seeds(text: &str) -> Result<std::ops::Range<u64>, String> {
    let number = |s: &str| {
        s.trim().parse::<u64>().map_err(|_| {
            format!("`{s}` is not a seed (a whole number ≥ 0): write one seed, A..B (B left out) or A..=B")
        })
    };
    let range = if let Some((a, b)) = text.split_once("..=") {
        let end = number(b)?.checked_add(1).ok_or("the last seed is too large")?;
        number(a)?..end
    } else if let Some((a, b)) = text.split_once("..") {
        number(a)?..number(b)?
    } else {
        let n = number(text)?;
        n..n.checked_add(1).ok_or("the seed is too large")?
    };
    if range.is_empty() {
        return Err(format!("`{text}` holds no seed"));
    }
    if range.end - range.start > 10_000_000 {
        return Err(format!("`{text}` holds {} seeds; at most 10 000 000", range.end - range.start));
    }
    Ok(range)
}

/// Landmark layout seeds: a comma-separated list of seeds and ranges as
/// [`parse_seeds`] reads them (`2121,2222,3000..3003`), each at most once.
pub(super) fn parse_layout_seeds(text: &str) -> Result<LayoutSeeds, String> {
    let mut seeds = Vec::new();
    for part in text.split(',') {
        for seed in parse_seeds(part)? {
            if seeds.contains(&seed) {
                return Err(format!("layout seed {seed} is listed twice"));
            }
            if seeds.len() == MOST_LAYOUTS {
                return Err(format!("`{text}` holds more than {MOST_LAYOUTS} layout seeds"));
            }
            seeds.push(seed);
        }
    }
    Ok(LayoutSeeds(seeds))
}

/// The most layout seeds one sweep takes.
const MOST_LAYOUTS: usize = 10_000;

/// Seeds of landmark layouts, as `--layout-seeds` takes them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LayoutSeeds(pub Vec<u64>);

/// The most jobs a sweep runs at once: more threads than any machine has
/// cores only costs memory.
const MOST_JOBS: usize = 1024;

/// `n` and `noun`, plural unless one: "1 run", "12 runs".
fn counted(n: usize, noun: &str) -> String {
    format!("{n} {noun}{}", if n == 1 { "" } else { "s" })
}

/// Parses a number of jobs, 1 to [`MOST_JOBS`].
pub(super) fn parse_jobs(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(0) => Err("at least one job is needed".into()),
        Ok(n) if n > MOST_JOBS => Err(format!("{n} jobs is more than the {MOST_JOBS} a machine can use")),
        Ok(n) => Ok(n),
        Err(_) => Err(format!("`{text}` is not a number of jobs")),
    }
}

#[cfg(test)]
mod tests {
    use super::parse_seeds;

    #[test]
    fn seeds_are_one_or_a_range_and_a_mistake_says_how_to_write_them() {
        assert_eq!(parse_seeds("7"), Ok(7..8));
        assert_eq!(parse_seeds("3..6"), Ok(3..6));
        assert_eq!(parse_seeds("3..=6"), Ok(3..7));
        for wrong in ["1,2,3", "1-5", "x..3"] {
            let said = parse_seeds(wrong).unwrap_err();
            assert!(said.ends_with("write one seed, A..B (B left out) or A..=B"), "{wrong}: {said}");
        }
        assert_eq!(parse_seeds("5..5").unwrap_err(), "`5..5` holds no seed");
    }
}
