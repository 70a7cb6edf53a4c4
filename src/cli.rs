//! The `ubf` command line.
//!
//! A user's crate gets the same command line, with its own behaviours usable
//! from scenario files, by handing its registry to [`main_with`]:
//!
//! ```no_run
//! fn main() -> std::process::ExitCode {
//!     let registry = ubf::registry();
//!     // registry.register("Wander", |c: &WanderConfig, ctx| Wander::new(c, ctx));
//!     ubf::cli::main_with(registry)
//! }
//! ```

use crate::run::{run, EndReason, RunReport};
use crate::scenario::Scenario;
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use ubf_core::{Pose2, Registry};

/// Exit code for bad input: a malformed file, a bad argument.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code for a run that failed after its input was accepted.
pub const EXIT_FAILURE: u8 = 1;

#[derive(Debug, Parser)]
#[command(
    name = "ubf",
    version,
    about = "Unified Behavior Framework: run behaviour trees on simulated and real robots"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a scenario headless on the simulator and print a summary.
    Run {
        /// The scenario file (RON).
        file: PathBuf,
        /// Use this seed instead of the scenario's.
        #[arg(long)]
        seed: Option<u64>,
        /// Write report.json, trajectory.csv and plot.png into this directory.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print the report as JSON on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Run every scenario with every seed in parallel and summarise.
    Sweep {
        /// The scenario files (RON).
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Seeds: `A..B` (B excluded), `A..=B`, or one seed.
        #[arg(long, value_parser = parse_seeds)]
        seeds: std::ops::Range<u64>,
        /// Runs at once; by default one per core.
        #[arg(long)]
        jobs: Option<usize>,
        /// Where the reports and the summary go.
        #[arg(long)]
        out: PathBuf,
        /// Also write every run's trajectory.csv and plot.png.
        #[arg(long)]
        trajectories: bool,
    },
    /// Check scenario files without running them; exit code 2 on the first
    /// bad one.
    Check {
        /// The scenario files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// List the behaviours this build can read from scenario files.
    Behaviors,
}

/// Runs the command line with `registry` resolving behaviour names.
pub fn main_with(registry: Registry) -> ExitCode {
    init_tracing();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // clap prints help and version to stdout with success, usage errors
            // to stderr with code 2.
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { EXIT_BAD_INPUT } else { 0 });
        }
    };
    match cli.command {
        Command::Run { file, seed, out, json } => run_command(&registry, file, seed, out, json),
        Command::Check { files } => check_command(&registry, &files),
        Command::Sweep { files, seeds, jobs, out, trajectories } => {
            sweep_command(&registry, &files, seeds, jobs, &out, trajectories)
        }
        Command::Behaviors => {
            for name in registry.names() {
                println!("{name}");
            }
            ExitCode::SUCCESS
        }
    }
}

fn init_tracing() {
    use tracing_subscriber::EnvFilter;
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("warn"));
    let _ = tracing_subscriber::fmt().with_env_filter(filter).with_writer(std::io::stderr).try_init();
}

fn run_command(registry: &Registry, file: PathBuf, seed: Option<u64>, out: Option<PathBuf>, json: bool) -> ExitCode {
    let scenario = match Scenario::load(registry, &file) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let seed = seed.unwrap_or(scenario.seed);
    match run(&scenario, seed, out.as_deref()) {
        Ok(summary) if json => match serde_json::to_string_pretty(&summary) {
            Ok(text) => {
                println!("{text}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: writing the summary: {e}");
                ExitCode::from(EXIT_FAILURE)
            }
        },
        Ok(summary) => {
            print_summary(&summary);
            if let Some(dir) = &out {
                println!("outputs         {}/{{report.json, trajectory.csv, plot.png}}", dir.display());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {}: {e}", file.display());
            ExitCode::from(EXIT_FAILURE)
        }
    }
}

/// Parses `A..B`, `A..=B` or `N` into a range of seeds.
fn parse_seeds(text: &str) -> Result<std::ops::Range<u64>, String> {
    let number = |s: &str| s.trim().parse::<u64>().map_err(|_| format!("`{s}` is not a seed (a whole number ≥ 0)"));
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
    Ok(range)
}

fn sweep_command(
    registry: &Registry,
    files: &[PathBuf],
    seeds: std::ops::Range<u64>,
    jobs: Option<usize>,
    out: &std::path::Path,
    trajectories: bool,
) -> ExitCode {
    let mut items: Vec<crate::sweep::SweepItem> = Vec::new();
    for file in files {
        let scenario = match Scenario::load(registry, file) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(EXIT_BAD_INPUT);
            }
        };
        let stem = file.file_stem().map_or("scenario".into(), |s| s.to_string_lossy().into_owned());
        let mut label = stem.clone();
        let mut n = 2;
        while items.iter().any(|i| i.label == label) {
            label = format!("{stem}_{n}");
            n += 1;
        }
        items.push(crate::sweep::SweepItem { scenario, label });
    }
    let jobs = jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let stopwatch = ubf_core::Stopwatch::start();
    match crate::sweep::sweep(&items, seeds.clone(), jobs, out, trajectories) {
        Ok(summary) => {
            let runs: usize = summary.scenarios.values().map(|s| s.runs).sum();
            let failed: usize = summary.scenarios.values().map(|s| s.failed.len()).sum();
            println!(
                "{runs} runs of {} scenario(s) × seeds {}..{} in {:.2} s on {jobs} job(s); {failed} failed",
                items.len(),
                seeds.start,
                seeds.end,
                stopwatch.elapsed_s()
            );
            println!("summary: {}/summary.csv, {}/summary.json", out.display(), out.display());
            for (label, s) in &summary.scenarios {
                for (seed, error) in &s.failed {
                    eprintln!("error: {label} seed {seed}: {error}");
                }
            }
            if failed > 0 {
                ExitCode::from(EXIT_FAILURE)
            } else {
                ExitCode::SUCCESS
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_FAILURE)
        }
    }
}

fn check_command(registry: &Registry, files: &[PathBuf]) -> ExitCode {
    let mut code = ExitCode::SUCCESS;
    for file in files {
        match Scenario::load(registry, file) {
            Ok(scenario) => println!("{}: ok ({})", file.display(), scenario.name),
            Err(e) => {
                eprintln!("error: {e}");
                code = ExitCode::from(EXIT_BAD_INPUT);
            }
        }
    }
    code
}

fn pose_text(p: &Pose2) -> String {
    format!("({:.3}, {:.3}) m, {:.1}°", p.x, p.y, p.theta.to_degrees())
}

fn print_summary(s: &RunReport) {
    let ending = match s.end {
        EndReason::GoalReached => "robot believes it reached the goal",
        EndReason::TimeLimit => "time limit",
    };
    println!("scenario        {} (seed {})", s.scenario, s.seed);
    println!("ended           {ending} after {:.1} s simulated, {} ticks", s.sim_time_s, s.ticks);
    println!("goal reached    {}", if s.reached_goal { "yes" } else { "no" });
    println!("distance        {:.2} m", s.distance_m);
    println!("collisions      {}", s.collisions);
    println!("true pose       {}", pose_text(&s.final_true_pose));
    println!("estimated pose  {}", pose_text(&s.final_estimated_pose));
    println!("wall time       {:.3} s", s.wall_time_s);
}
