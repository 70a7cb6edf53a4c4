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
