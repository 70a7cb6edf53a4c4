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

use crate::run::{run_until, EndReason, RunReport};
use crate::scenario::Scenario;
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use ubf_behaviors::DecisionObjective;
use ubf_core::{Pose2, Registry};

/// Exit code for bad input: a malformed file, a bad argument.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code for a run that failed after its input was accepted.
pub const EXIT_FAILURE: u8 = 1;
/// The most runs a sweep starts without `--huge`.
const MOST_SWEEP_RUNS: u64 = 100_000;

/// Exit code for a run stopped by Ctrl-C or SIGTERM (128 + SIGINT, as
/// shells report it).
pub const EXIT_INTERRUPTED: u8 = 130;

#[derive(Debug, Parser)]
#[command(
    name = "ubf",
    version,
    about = "Unified Behavior Framework: run behaviour trees on simulated and real robots"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// More log on stderr: -v info, -vv debug, -vvv every tick (trace).
    /// RUST_LOG, when set, decides instead.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    /// Errors only on stderr.
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
}

/// What `ubf sweep` does besides sweeping.
#[derive(Debug, Subcommand)]
enum SweepAction {
    /// Combine the shards of a sweep (`ubf sweep ... --shard K/N`) into the
    /// summary one sweep would have written: `summary.csv` and
    /// `summary.json`, byte for byte.
    Merge {
        /// Directories holding the shards' output (one may hold them all).
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Where the summary goes (default: the first directory).
        #[arg(long)]
        out: Option<PathBuf>,
    },
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
        /// Run it even beyond the bound on ticks (a deliberately huge run).
        #[arg(long)]
        huge: bool,
        /// Put the camera's rendered stereo pairs in run.mcap (PNG; needs
        /// `--out` and a camera that renders).
        #[arg(long, requires = "out")]
        log_images: bool,
    },
    /// Run every scenario with every seed in parallel and summarise; with
    /// `--shard K/N`, a share of the runs, for `ubf sweep merge` to combine.
    #[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
    Sweep {
        #[command(subcommand)]
        action: Option<SweepAction>,
        /// The scenario files (RON).
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Seeds: `A..B` (B excluded), `A..=B`, or one seed.
        #[arg(long, required = true, value_parser = parse_seeds)]
        seeds: Option<std::ops::Range<u64>>,
        /// Runs at once (at least 1); by default one per core.
        #[arg(long, value_parser = parse_jobs)]
        jobs: Option<usize>,
        /// Where the reports and the summary go.
        #[arg(long, required = true)]
        out: Option<PathBuf>,
        /// Run only share K of N (from 0) of the runs, leaving their
        /// reports and `shard-K-of-N.json` in `--out` (which may hold other
        /// shards' output) instead of a summary; `ubf sweep merge` then
        /// combines the shards. For a Slurm job array or a Kubernetes
        /// indexed job.
        #[arg(long, value_name = "K/N", value_parser = crate::sweep::Shard::parse)]
        shard: Option<crate::sweep::Shard>,
        /// Also write every run's trajectory.csv and plot.png.
        #[arg(long)]
        trajectories: bool,
        /// Replace an earlier sweep's output in `--out` (a directory holding
        /// its summary.json); without this a non-empty `--out` is refused,
        /// so old runs never sit beside a new summary.
        #[arg(long)]
        overwrite: bool,
        /// Run it even beyond the bounds on runs and on ticks per run.
        #[arg(long)]
        huge: bool,
    },
    /// Check scenario files without running them; exit code 2 on the first
    /// bad one.
    Check {
        /// The scenario files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// List the behaviours this build can read from scenario files; with
    /// `--describe`, their fields (kind, unit, default, range, meaning) as
    /// Markdown tables.
    Behaviors {
        /// Print each behaviour's fields, not only its name.
        #[arg(long)]
        describe: bool,
        /// Only these behaviours (with `--describe`).
        names: Vec<String>,
    },
    /// Read a run's log (`run.mcap`) back: print the run's summary and draw
    /// its plot again from the log alone.
    Replay {
        /// The log, as `ubf run --out DIR` writes it (`DIR/run.mcap`).
        file: PathBuf,
        /// Where to draw the plot (default: beside the log, as
        /// `<name>-replay.png`).
        #[arg(long, value_name = "FILE.png")]
        plot: Option<PathBuf>,
    },
    /// Print a scenario's (or robot file's) behaviour tree as Graphviz DOT
    /// (`| dot -Tpng > tree.png`), or as Mermaid for Markdown pages: each
    /// composite with its arbiter and vote override, each child with its
    /// share of the vote.
    Tree {
        /// The scenario or robot file (RON).
        file: PathBuf,
        /// Mermaid instead of DOT.
        #[arg(long)]
        mermaid: bool,
    },
    /// Run a scenario with rendered stereo images and write every pair into
    /// a directory (with `frames.csv` and `camera.ron`), for replay.
    Frames {
        /// The scenario file (RON); its robot needs a camera.
        file: PathBuf,
        /// Where the images go.
        #[arg(long)]
        out: PathBuf,
        /// Seed (default: the scenario's).
        #[arg(long)]
        seed: Option<u64>,
        /// Stop after this many pairs.
        #[arg(long, default_value_t = 100_000)]
        max_frames: usize,
        /// Record even beyond 10 GB of images (a deliberately huge
        /// recording).
        #[arg(long)]
        huge: bool,
    },
    /// Replay a directory of stereo pairs through the feature pipeline and
    /// the rigid egomotion estimator on one core, and time them; with
    /// ground truth, measure the estimate's accuracy (KITTI's metrics).
    Pipeline {
        /// A directory written by `ubf frames` (or laid out the same way),
        /// or a KITTI odometry sequence (`image_0/`, `image_1/`,
        /// `calib.txt`, `times.txt`).
        dir: PathBuf,
        /// Print the measurements as JSON.
        #[arg(long)]
        json: bool,
        /// Ground-truth poses for a KITTI sequence, in KITTI's format
        /// (default: the sequence's `poses.txt`, if it has one).
        #[arg(long, value_name = "FILE")]
        poses: Option<PathBuf>,
        /// The fastest motion egomotion accepts, m/s (default: 0.6, the
        /// robot's, for a recording; 40, a road vehicle's, for KITTI).
        #[arg(long, value_name = "M/S", value_parser = parse_limit)]
        max_speed: Option<f64>,
        /// The fastest turn egomotion accepts, °/s (default: 100 for a
        /// recording, 90 for KITTI).
        #[arg(long, value_name = "DEG/S", value_parser = parse_limit)]
        max_turn_rate: Option<f64>,
        /// How far from a keyframe a frame may still be matched to it, m
        /// (default 10); near 1 m the matching is almost frame to frame.
        #[arg(long, value_name = "M", value_parser = parse_limit)]
        keyframe_range: Option<f64>,
        /// Add this to every disparity before triangulating, px, in place
        /// of the calibration's offset (`disparity_offset_px` in
        /// `camera.ron`; KITTI's `calib.txt` has none): for a pair whose
        /// rectification leaves a disparity bias. Negative values allowed.
        #[arg(long, value_name = "PX", allow_negative_numbers = true, value_parser = parse_offset)]
        disparity_offset: Option<f64>,
        /// Draw the estimated path (over the true one, if known) here (PNG).
        #[arg(long, value_name = "FILE.png")]
        plot: Option<PathBuf>,
        /// Write every landmark of every pair here (CSV: pair, pixels with
        /// the first pixel's centre at (0, 0), disparity, camera-frame
        /// point).
        #[arg(long, value_name = "FILE.csv")]
        landmarks: Option<PathBuf>,
    },
    /// Drive a real robot (or an emulator) with a behaviour tree; Ctrl-C or
    /// SIGTERM stops it safely.
    Drive {
        /// The robot configuration file (RON).
        file: PathBuf,
        /// Connect and show the robot's identity, odometry and sonar without
        /// enabling the motors.
        #[arg(long)]
        dry_run: bool,
        /// Show the live state (link, pose, speeds, winning behaviour, hold)
        /// on stderr even when it is not a terminal (on a terminal it is
        /// always shown, on one updating line).
        #[arg(long)]
        status: bool,
        /// End the drive once the robot believes it is at the goal (the
        /// robot is stopped and the session closed); without it the tree
        /// holds the robot there until Ctrl-C.
        #[arg(long)]
        until_goal: bool,
    },
    /// Emulate a Powerbot's controller on a TCP port or a pseudo-terminal,
    /// for trying things out without a robot.
    EmulatePowerbot {
        /// Address to listen on.
        #[arg(long, default_value = "127.0.0.1:8101", conflicts_with = "pty")]
        listen: String,
        /// Serve on a new pseudo-terminal instead, as the robot's serial port
        /// would be; prints its device path for `connection`.
        #[arg(long)]
        pty: bool,
        /// Put the robot in the middle of a LENGTHxWIDTH metre room, facing
        /// along it, for the sonar to see (default: open space, no echoes).
        #[arg(long, value_name = "LENGTHxWIDTH", value_parser = parse_room)]
        room: Option<(f64, f64)>,
        /// Milliseconds between SIPs (ARCOS: 100); down to 0.1 to flood a
        /// client with 10 000 a second.
        #[arg(long, value_name = "MS", default_value_t = 100.0, value_parser = parse_sip_period)]
        sip_period_ms: f64,
        /// Freeze AFTER seconds into each session, for FOR seconds: no SIPs
        /// and no motion while commands are still read, as a paused
        /// simulator does; for rehearsing what the client does.
        #[arg(long, value_name = "AFTER:FOR", value_parser = parse_silence)]
        silence: Option<(f64, f64)>,
    },
    /// Reproduce one of the thesis's experiments.
    Experiment {
        #[command(subcommand)]
        which: ExperimentCommand,
    },
    /// The landmark egomotion error model of a camera (thesis §3.3.3).
    Model {
        #[command(subcommand)]
        action: ModelCommand,
    },
}

#[derive(Debug, Subcommand)]
enum ExperimentCommand {
    /// Where aiding pays: vary one factor of route 1→2 at a time (corridor
    /// width, landmark count, side-wall share, featureless stretch,
    /// detection range, pixel noise), choose the best aided technique on the
    /// development seeds, and measure its gain over straight driving on
    /// held-out seeds in a held-out layout; table, JSON and a PNG map.
    WhereAidingPays {
        /// Seeds the best technique is chosen on.
        #[arg(long, default_value = "0..30", value_parser = parse_seeds)]
        seeds: std::ops::Range<u64>,
        /// Seeds the gain is measured on.
        #[arg(long, default_value = "1000..1030", value_parser = parse_seeds)]
        held_out_seeds: std::ops::Range<u64>,
        /// The held-out landmark layout.
        #[arg(long, default_value_t = 101)]
        layout_seed: u64,
        /// Runs at once (at least 1); by default one per core.
        #[arg(long, value_parser = parse_jobs)]
        jobs: Option<usize>,
        /// Draw the map here (PNG).
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Print the results as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Table 2: single-landmark egomotion errors for one frame step, beside
    /// the thesis's, for a range of gross stereo mismatch shares; names the
    /// share that matches (the route scenarios use it).
    ThesisTable2 {
        /// The step between the two frames, m (the thesis's robot: 0.15 m).
        #[arg(long, default_value_t = 0.15)]
        step: f64,
        /// Frame pairs per outlier share.
        #[arg(long, default_value_t = 200)]
        trials: u64,
        /// Runs at once (at least 1); by default one per core.
        #[arg(long, value_parser = parse_jobs)]
        jobs: Option<usize>,
        /// Print the results as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Table 4: journey CV of every technique in 10 random 6 m × 60 m corridors.
    ThesisTable4 {
        /// Corridors (seeds of their layouts).
        #[arg(long, default_value = "0..10", value_parser = parse_seeds)]
        seeds: std::ops::Range<u64>,
        /// What the evaluative techniques minimise: `end-point` (the
        /// predicted end-point variance, turns included) or `cv` (the
        /// thesis's step CV, turns free).
        #[arg(long, default_value = "cv", value_parser = parse_objective)]
        objective: DecisionObjective,
        /// Runs at once (at least 1); by default one per core.
        #[arg(long, value_parser = parse_jobs)]
        jobs: Option<usize>,
        /// Print the results as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Tables 5–7 and 10: end-point egomotion error on the two 40.7 m routes
    /// and the feature-poor section, both estimators.
    ThesisEndpoint {
        /// Seeds per route, technique and estimator.
        #[arg(long, default_value = "0..30", value_parser = parse_seeds)]
        seeds: std::ops::Range<u64>,
        /// Runs at once (at least 1); by default one per core.
        #[arg(long, value_parser = parse_jobs)]
        jobs: Option<usize>,
        /// Print the results as JSON.
        #[arg(long)]
        json: bool,
        /// Render stereo images and find the landmarks in them with the
        /// feature pipeline, instead of the geometric camera model (about
        /// 30 ms a frame: a few seconds a run; use fewer seeds).
        #[arg(long)]
        rendered: bool,
        /// Replace each route's fixed landmark layout with one drawn from
        /// this seed (layouts nobody tuned on).
        #[arg(long)]
        layout_seed: Option<u64>,
        /// What the evaluative techniques minimise: `end-point` (the
        /// predicted end-point variance, turns included) or `cv` (the
        /// thesis's step CV, turns free).
        #[arg(long, default_value = "end-point", value_parser = parse_objective)]
        objective: DecisionObjective,
        /// Drive with the thesis's decoupled motion (turn on the spot, then
        /// translate) instead of the routes' continuous profile.
        #[arg(long)]
        rotate_then_translate: bool,
    },
}

#[derive(Debug, Subcommand)]
enum ModelCommand {
    /// Fit the exponential model (eq. 24) to the geometric one (eq. 16–23)
    /// and report the fit's quality.
    Fit {
        #[command(flatten)]
        camera: CameraArgs,
        /// Print the fit as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Fit the coefficients the end-point decision weighs (turn heading
    /// variance, step translation error per CV) from run logs with ground
    /// truth: `trajectory.csv` files, or directories searched for them (as
    /// `ubf sweep --trajectories` writes them).
    FitCosts {
        /// Logs or directories of logs.
        #[arg(required = true)]
        logs: Vec<PathBuf>,
        /// Print the fit as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Draw the model as a heat map over the field of view (thesis figure 16).
    Heatmap {
        #[command(flatten)]
        camera: CameraArgs,
        /// Draw the fitted exponential model instead of the geometric one.
        #[arg(long)]
        exponential: bool,
        /// The PNG to write.
        #[arg(long)]
        out: PathBuf,
    },
}

#[derive(Debug, clap::Args)]
struct CameraArgs {
    /// Take the camera from this scenario's robot (default: the default camera).
    #[arg(long)]
    scenario: Option<PathBuf>,
    /// The step the model assumes, m (the thesis: 1 m).
    #[arg(long, default_value_t = 1.0)]
    step: f64,
    /// Nearest and farthest depth of the fit, m, as `NEAR..FAR`.
    #[arg(long, default_value = "1.2..40", value_parser = parse_depths)]
    depths: [f64; 2],
}

/// Whether `ubf` accepts `args` (the words after the program's name) as a
/// command line, without running anything: the docs test checks every
/// command the docs show with it. The error is clap's message.
pub fn parses<I: IntoIterator<Item = T>, T: Into<std::ffi::OsString> + Clone>(args: I) -> Result<(), String> {
    let words = std::iter::once(std::ffi::OsString::from("ubf")).chain(args.into_iter().map(Into::into));
    Cli::try_parse_from(words).map(drop).map_err(|e| e.to_string())
}

/// Runs the command line with `registry` resolving behaviour names.
pub fn main_with(registry: Registry) -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // clap prints help and version to stdout with success, usage errors
            // to stderr with code 2.
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { EXIT_BAD_INPUT } else { 0 });
        }
    };
    init_tracing(cli.verbose, cli.quiet);
    // A closed pipe (`ubf run S | head -1`) ends a command quietly with the
    // conventional status, as it does any Unix filter, instead of a panic.
    // Not for the commands that drive a robot: they notice a closed output
    // as a write error and stop the robot before they exit.
    #[cfg(unix)]
    if !matches!(cli.command, Command::Drive { .. } | Command::EmulatePowerbot { .. }) {
        // SAFETY: restoring the default action of a signal, before any
        // thread has started.
        unsafe {
            libc::signal(libc::SIGPIPE, libc::SIG_DFL);
        }
    }
    match cli.command {
        Command::Run { file, seed, out, json, huge, log_images } => {
            run_command(&registry, file, seed, out, json, huge, log_images)
        }
        Command::Check { files } => check_command(&registry, &files),
        Command::Sweep { action: Some(SweepAction::Merge { dirs, out }), .. } => {
            let out = out.unwrap_or_else(|| dirs[0].clone());
            match crate::sweep::merge(&dirs, &out) {
                Ok(summary) => {
                    let runs: usize = summary.scenarios.values().map(|s| s.runs).sum();
                    let failed: usize = summary.scenarios.values().map(|s| s.failed.len()).sum();
                    println!("merged {runs} runs of {} scenario(s); {failed} failed", summary.scenarios.len());
                    println!("summary: {}/summary.csv, {}/summary.json", out.display(), out.display());
                    ExitCode::SUCCESS
                }
                Err(crate::sweep::MergeError::Write(e)) => {
                    eprintln!("error: {e}");
                    ExitCode::from(EXIT_FAILURE)
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(EXIT_BAD_INPUT)
                }
            }
        }
        Command::Sweep { action: None, files, seeds, jobs, out, shard, trajectories, overwrite, huge } => {
            let (Some(seeds), Some(out)) = (seeds, out) else {
                unreachable!("clap requires --seeds and --out without a subcommand")
            };
            let share = shard.map_or(1, |s| s.count);
            let runs = (seeds.end - seeds.start).saturating_mul(files.len() as u64).div_ceil(share);
            if runs > MOST_SWEEP_RUNS && !huge {
                eprintln!(
                    "error: {runs} runs ({} seeds × {} files), more than {MOST_SWEEP_RUNS}: each leaves a \
                     directory and a report; narrow --seeds, or pass --huge to run them anyway",
                    seeds.end - seeds.start,
                    files.len()
                );
                return ExitCode::from(EXIT_BAD_INPUT);
            }
            let cleared = match shard {
                None => clear_sweep_output(&out, overwrite),
                Some(shard) => clear_shard_output(&out, shard, overwrite),
            };
            if let Err(message) = cleared {
                eprintln!("error: {message}");
                return ExitCode::from(EXIT_BAD_INPUT);
            }
            sweep_command(&registry, &files, seeds, shard, jobs, &out, trajectories, huge)
        }
        Command::Model { action } => model_command(&registry, action),
        Command::Experiment { which } => experiment_command(&registry, which),
        Command::Drive { file, dry_run, status, until_goal } => {
            drive_command(&registry, &file, dry_run, status, until_goal)
        }
        Command::EmulatePowerbot { listen, pty, room, sip_period_ms, silence } => {
            let mut config =
                ubf_robots::arcos::emulator::EmulatorConfig::new(ubf_robots::model::RobotModel::powerbot());
            if let Some((length, width)) = room {
                config = config.in_room(length, width);
            }
            config.sip_period = std::time::Duration::from_secs_f64(sip_period_ms / 1000.0);
            config.silence = silence.map(|(after, span)| {
                (std::time::Duration::from_secs_f64(after), std::time::Duration::from_secs_f64(span))
            });
            if pty {
                emulate_on_pty(&config)
            } else {
                emulate_command(&listen, &config)
            }
        }
        Command::Frames { file, out, seed, max_frames, huge } => {
            frames_command(&registry, &file, &out, seed, max_frames, huge)
        }
        Command::Pipeline {
            dir,
            json,
            poses,
            max_speed,
            max_turn_rate,
            keyframe_range,
            disparity_offset,
            plot,
            landmarks,
        } => {
            let options = crate::frames::ReplayOptions {
                features: ubf_perception::features::FeatureConfig::default(),
                max_speed,
                max_turn_rate_deg: max_turn_rate,
                poses,
                keyframe_range_m: keyframe_range,
                disparity_offset_px: disparity_offset,
                landmarks,
            };
            pipeline_command(&dir, &options, json, plot.as_deref())
        }
        Command::Tree { file, mermaid } => tree_command(&registry, &file, mermaid),
        Command::Replay { file, plot } => replay_command(&file, plot),
        Command::Behaviors { describe, names } => behaviors_command(&registry, describe, &names),
    }
}

fn replay_command(file: &std::path::Path, plot: Option<PathBuf>) -> ExitCode {
    let replayed = match crate::mcap_log::read(file) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let Some(run) = &replayed.run else {
        let why = replayed.cut_short.as_ref().map_or(String::new(), |e| format!(" ({e})"));
        eprintln!("error: {}: no /run message: not a ubf run log, or cut before its start{why}", file.display());
        return ExitCode::from(EXIT_BAD_INPUT);
    };
    println!("scenario        {} (seed {})", run.scenario, run.seed);
    println!("ticks logged    {}", replayed.timeline.time.len());
    let end_time = replayed.timeline.time.last().copied().unwrap_or(0.0);
    println!("logged until    {end_time:.1} s");
    println!("decisions       {}", replayed.decisions.len());
    println!("collisions      {}", replayed.collisions.len());
    match &replayed.report {
        Some(report) => {
            let number = |key: &str| report[key].as_f64().map_or("—".to_owned(), |v| format!("{v:.3}"));
            println!("ended           {}", report["end"].as_str().unwrap_or("?"));
            println!("distance        {} m", number("distance_m"));
            println!("estimate error  {} m", number("estimate_error_m"));
            if report["endpoint_error_m"].is_number() {
                println!("egomotion error {} m at the last frame", number("endpoint_error_m"));
            }
        }
        None => println!(
            "ended           not recorded: the log stops early{}",
            replayed.cut_short.as_ref().map_or(String::new(), |e| format!(" ({e})"))
        ),
    }
    let plot = plot.unwrap_or_else(|| {
        let stem = file.file_stem().map_or("run".into(), |s| s.to_string_lossy().into_owned());
        file.with_file_name(format!("{stem}-replay.png"))
    });
    let title = format!("{} (seed {}), from its log", run.scenario, run.seed);
    if let Err(e) = crate::plot::draw_replayed(&replayed, &title, &plot) {
        eprintln!("error: {e}");
        return ExitCode::from(EXIT_FAILURE);
    }
    println!("plot            {}", plot.display());
    ExitCode::SUCCESS
}

fn behaviors_command(registry: &Registry, describe: bool, names: &[String]) -> ExitCode {
    if let Some(unknown) = names.iter().find(|n| !registry.contains(n)) {
        let known: Vec<&str> = registry.names().collect();
        eprintln!("error: unknown behaviour `{unknown}`; known behaviours: {}", known.join(", "));
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    let chosen: Vec<&str> =
        if names.is_empty() { registry.names().collect() } else { names.iter().map(String::as_str).collect() };
    for (i, name) in chosen.iter().enumerate() {
        if !describe {
            println!("{name}");
            continue;
        }
        let fields = registry.fields(name).unwrap_or_default();
        if i > 0 {
            println!();
        }
        println!("### `{name}`\n");
        if fields.is_empty() {
            println!("No settings: `{name}()`.");
        } else {
            print!("{}", ubf_core::markdown_table(fields));
        }
    }
    ExitCode::SUCCESS
}

/// Log to stderr at the level RUST_LOG sets, or else `-v`/`-q` (warnings by
/// default).
fn init_tracing(verbose: u8, quiet: bool) {
    use tracing_subscriber::EnvFilter;
    let level = match (quiet, verbose) {
        (true, _) => "error",
        (false, 0) => "warn",
        (false, 1) => "info",
        (false, 2) => "debug",
        (false, _) => "trace",
    };
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(level));
    use std::io::IsTerminal;
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .try_init();
}

fn run_command(
    registry: &Registry,
    file: PathBuf,
    seed: Option<u64>,
    out: Option<PathBuf>,
    json: bool,
    huge: bool,
    log_images: bool,
) -> ExitCode {
    let loaded = if huge { Scenario::load_unbounded(registry, &file) } else { Scenario::load(registry, &file) };
    let scenario = match loaded {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let seed = seed.unwrap_or(scenario.seed);
    // A run a behaviour ended, or Ctrl-C, still reports, but does not pass.
    let status = |summary: &RunReport| match summary.end {
        EndReason::BehaviorFailed => ExitCode::from(EXIT_FAILURE),
        EndReason::Interrupted => ExitCode::from(EXIT_INTERRUPTED),
        EndReason::GoalReached | EndReason::TimeLimit => ExitCode::SUCCESS,
    };
    let stop = crate::drive::install_stop_flag();
    let outputs = out.as_deref().map(|dir| crate::run::Outputs { dir, images: log_images });
    match run_until(&scenario, seed, outputs, &stop) {
        Ok(summary) if json => match serde_json::to_string_pretty(&summary) {
            Ok(text) => {
                println!("{text}");
                status(&summary)
            }
            Err(e) => {
                eprintln!("error: writing the summary: {e}");
                ExitCode::from(EXIT_FAILURE)
            }
        },
        Ok(summary) => {
            print_summary(&summary);
            if let Some(dir) = &out {
                println!("outputs         {}/{{report.json, trajectory.csv, run.mcap, plot.png}}", dir.display());
            }
            status(&summary)
        }
        Err(e) => {
            eprintln!("error: {}: {e}", file.display());
            ExitCode::from(EXIT_FAILURE)
        }
    }
}

fn drive_command(
    registry: &Registry,
    file: &std::path::Path,
    dry_run: bool,
    status: bool,
    until_goal: bool,
) -> ExitCode {
    use crate::drive::{drive, DriveConfig, DriveEnd};
    let (mut config, model) = match DriveConfig::load(registry, file) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    config.until_goal |= until_goal;
    let stop = crate::drive::install_stop_flag();
    if dry_run {
        return match crate::drive::dry_run(&config, &model, &stop) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(EXIT_FAILURE)
            }
        };
    }
    use std::io::IsTerminal;
    let status = match (std::io::stderr().is_terminal(), status) {
        (true, _) => crate::drive::Status::Line,
        (false, true) => crate::drive::Status::Lines,
        (false, false) => crate::drive::Status::Off,
    };
    let outcome = drive(&config, &model, &stop, status);
    match outcome.logs.as_slice() {
        [] => eprintln!("no session opened; no log written"),
        [one] => eprintln!("log in {}", one.display()),
        many => {
            let names: Vec<String> = many.iter().map(|p| p.display().to_string()).collect();
            eprintln!("logs (CSV and MCAP), per session: {}", names.join(", "));
        }
    }
    match outcome.end {
        Ok(DriveEnd::Stopped) => {
            eprintln!("stopped");
            ExitCode::SUCCESS
        }
        Ok(DriveEnd::GoalReached) => {
            eprintln!("at the goal; stopped");
            ExitCode::SUCCESS
        }
        Ok(DriveEnd::LinkLost) => ExitCode::from(EXIT_FAILURE),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_FAILURE)
        }
    }
}

fn frames_command(
    registry: &Registry,
    file: &std::path::Path,
    out: &std::path::Path,
    seed: Option<u64>,
    max: usize,
    huge: bool,
) -> ExitCode {
    let loaded = if huge { Scenario::load_unbounded(registry, file) } else { Scenario::load(registry, file) };
    let scenario = match loaded {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let bytes = crate::frames::recording_bytes(&scenario, max);
    if bytes > crate::scenario::Work::MOST_RECORDING_BYTES && !huge {
        eprintln!(
            "error: up to {} of images (PNG compresses rendered noise little), more than {}; \
             lower --max-frames, or pass --huge to record them anyway",
            crate::scenario::Work::bytes_text(bytes),
            crate::scenario::Work::bytes_text(crate::scenario::Work::MOST_RECORDING_BYTES)
        );
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    match crate::frames::record(&scenario, seed.unwrap_or(scenario.seed), out, max) {
        Ok(count) => {
            println!("{count} stereo pairs in {}", out.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_FAILURE)
        }
    }
}

fn pipeline_command(
    dir: &std::path::Path,
    options: &crate::frames::ReplayOptions,
    json: bool,
    plot: Option<&std::path::Path>,
) -> ExitCode {
    let replay = match crate::frames::replay(dir, options) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    if let Some(path) = plot {
        if let Err(e) = crate::plot::draw_paths(&replay.estimate, replay.truth.as_deref(), path) {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_FAILURE);
        }
    }
    let report = &replay.report;
    if json {
        println!("{}", serde_json::to_string_pretty(report).expect("the report serialises"));
        return ExitCode::SUCCESS;
    }
    println!(
        "{} stereo pairs ({}), {:.0} landmarks each on average",
        report.frames, report.layout, report.landmarks_mean
    );
    println!(
        "median per pair: features and stereo {:.2} ms, egomotion {:.2} ms, total {:.2} ms ({:.0} pairs/s on one core)",
        report.pipeline_ms_median, report.egomotion_ms_median, report.total_ms_median, report.frames_per_s
    );
    println!(
        "egomotion: {} failures; end pose ({:.2}, {:.2}) m, {:.1}°; limits {} m/s, {} °/s",
        report.failures,
        report.final_pose[0],
        report.final_pose[1],
        report.final_pose[2].to_degrees(),
        report.limits[0],
        report.limits[1]
    );
    if let Some(a) = &report.accuracy {
        let lengths: Vec<String> = a.segment_lengths_m.iter().map(|l| format!("{l}")).collect();
        println!("path {:.1} m; end point off by {:.2} % of it", a.path_m, a.endpoint_drift_pct);
        println!(
            "KITTI error over {} m segments: translation {:.2} %, rotation {:.4} °/m",
            lengths.join(", "),
            a.translation_error_pct,
            a.rotation_error_deg_per_m
        );
        println!(
            "per step (median): translation error {:.2} %, scale {:.3}, rotation {:.4} °/m",
            a.step_translation_error_pct_median, a.step_scale_median, a.step_rotation_error_deg_per_m_median
        );
    }
    ExitCode::SUCCESS
}

/// A speed or turn-rate limit: finite and positive.
fn parse_limit(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1e4 => Ok(v),
        _ => Err(format!("expected a number above 0 and at most 10 000; got {text:?}")),
    }
}

/// A disparity offset, px: any finite number (the camera's check bounds it
/// by the image width).
fn parse_offset(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("expected a number of pixels; got {text:?}")),
    }
}

/// `LENGTHxWIDTH` in metres, both positive.
fn parse_room(text: &str) -> Result<(f64, f64), String> {
    let parse = |s: &str| s.trim().parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0);
    match text.split_once(['x', 'X']).map(|(l, w)| (parse(l), parse(w))) {
        Some((Some(length), Some(width))) => Ok((length, width)),
        _ => Err(format!("expected LENGTHxWIDTH in metres, both positive, e.g. 8x4; got {text:?}")),
    }
}

fn parse_sip_period(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(ms) if (0.1..=1000.0).contains(&ms) => Ok(ms),
        _ => Err(format!("expected milliseconds from 0.1 to 1000; got {text:?}")),
    }
}

fn parse_silence(text: &str) -> Result<(f64, f64), String> {
    let parse = |s: &str| s.trim().parse::<f64>().ok().filter(|v| v.is_finite() && (0.0..=86_400.0).contains(v));
    match text.split_once(':').map(|(a, f)| (parse(a), parse(f))) {
        Some((Some(after), Some(span))) => Ok((after, span)),
        _ => Err(format!("expected AFTER:FOR in seconds, e.g. 3:2; got {text:?}")),
    }
}

/// Prints what the emulator saw of a client, one line, the timings as
/// `name=value` (`-` when it did not happen). Nobody reading the output is
/// no reason to stop emulating: a closed pipe is ignored.
fn print_emulator_report(report: &ubf_robots::arcos::emulator::EmulatorReport) {
    use std::io::Write;
    let show = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{v:.3}"));
    let limits = report.speed_limits.map_or("-".to_owned(), |(v, w)| format!("{v},{w}"));
    let _ = writeln!(
        std::io::stdout(),
        "client gone: {} commands, closed {}, pose ({:.3}, {:.3}) m; sips={} motion_before_first_sip={} \
         last_motion_after_silence_s={} stop_after_silence_s={} stop_to_disable_s={} speed_at_disable_mm_s={} \
         speed_limits={limits} stalled_cycles={} host_baud={}",
        report.commands,
        report.closed,
        report.pose.0 / 1000.0,
        report.pose.1 / 1000.0,
        report.sips,
        report.motion_before_first_sip,
        show(report.last_motion_after_silence_s),
        show(report.stop_after_silence_s),
        show(report.stop_to_disable_s),
        show(report.speed_at_disable),
        report.stalled_cycles,
        report.host_baud.map_or("-".to_owned(), |b| b.to_string()),
    );
}

/// Serves clients one after another on a new pseudo-terminal until Ctrl-C
/// or SIGTERM.
#[cfg(unix)]
fn emulate_on_pty(config: &ubf_robots::arcos::emulator::EmulatorConfig) -> ExitCode {
    use ubf_robots::arcos::emulator::serve;
    let (master, path) = match ubf_robots::arcos::link::pseudo_terminal() {
        Ok(pair) => pair,
        Err(e) => {
            eprintln!("error: opening a pseudo-terminal: {e}");
            return ExitCode::from(EXIT_FAILURE);
        }
    };
    println!("emulating a Powerbot on {path}");
    let stop = crate::drive::install_stop_flag();
    while !stop.load(std::sync::atomic::Ordering::SeqCst) {
        let link = match master.try_clone_native() {
            Ok(link) => link,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(EXIT_FAILURE);
            }
        };
        match serve(Box::new(link), config, &stop) {
            // Nobody on the other end yet.
            Ok(report) if report.commands == 0 => std::thread::sleep(std::time::Duration::from_millis(100)),
            Ok(report) => print_emulator_report(&report),
            Err(e) => {
                eprintln!("client error: {e}");
                std::thread::sleep(std::time::Duration::from_millis(100));
            }
        }
    }
    ExitCode::SUCCESS
}

#[cfg(not(unix))]
fn emulate_on_pty(_config: &ubf_robots::arcos::emulator::EmulatorConfig) -> ExitCode {
    eprintln!("error: pseudo-terminals are supported on Unix only");
    ExitCode::from(EXIT_FAILURE)
}

fn emulate_command(listen: &str, config: &ubf_robots::arcos::emulator::EmulatorConfig) -> ExitCode {
    use ubf_robots::arcos::emulator::serve;
    let listener = match std::net::TcpListener::bind(listen) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("error: listening on {listen}: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    match listener.local_addr() {
        Ok(address) => println!("emulating a Powerbot on tcp://{address}"),
        Err(e) => eprintln!("warning: {e}"),
    }
    let stop = crate::drive::install_stop_flag();
    // Poll for clients so that Ctrl-C or SIGTERM ends a waiting emulator.
    if let Err(e) = listener.set_nonblocking(true) {
        eprintln!("error: {e}");
        return ExitCode::from(EXIT_FAILURE);
    }
    while !stop.load(std::sync::atomic::Ordering::SeqCst) {
        let stream = match listener.accept() {
            Ok((stream, _)) => stream,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(std::time::Duration::from_millis(50));
                continue;
            }
            Err(e) => {
                eprintln!("error: accepting a client: {e}");
                continue;
            }
        };
        let _ = stream.set_nonblocking(false);
        let _ = stream.set_read_timeout(Some(ubf_robots::arcos::link::READ_TIMEOUT));
        match serve(Box::new(stream), config, &stop) {
            Ok(report) => print_emulator_report(&report),
            Err(e) => eprintln!("client error: {e}"),
        }
    }
    ExitCode::SUCCESS
}

fn experiment_command(registry: &Registry, which: ExperimentCommand) -> ExitCode {
    use crate::experiment::{thesis_endpoint, thesis_table2, thesis_table4, EndpointOptions, TECHNIQUES};
    let cores = || std::thread::available_parallelism().map_or(1, |n| n.get());
    let result = match which {
        ExperimentCommand::WhereAidingPays { seeds, held_out_seeds, layout_seed, jobs, plot, json } => {
            let runs = 3 * seeds.clone().count() + 2 * held_out_seeds.clone().count();
            if runs == 0 || runs > 100_000 {
                eprintln!("error: need 1 to 20000 seeds in each set");
                return ExitCode::from(EXIT_BAD_INPUT);
            }
            let bar = crate::sweep::progress_bar(24, "environments");
            let progress = |done: usize, total: usize| {
                bar.set_length(total as u64);
                bar.set_position(done as u64);
            };
            let jobs = jobs.unwrap_or_else(cores);
            let result = crate::environment_map::where_aiding_pays(
                registry,
                seeds,
                held_out_seeds,
                layout_seed,
                jobs,
                &progress,
            );
            bar.finish_and_clear();
            result.map(|map| {
                if let Some(path) = &plot {
                    match crate::plot::draw_environment_map(&map, path) {
                        Ok(()) => eprintln!("wrote {}", path.display()),
                        Err(e) => eprintln!("error: {e}"),
                    }
                }
                if json {
                    println!("{}", serde_json::to_string_pretty(&map).expect("results serialise"));
                    return;
                }
                println!(
                    "Best aided technique (chosen on seeds {}..{}) over straight driving, end-point error on seeds {}..{} in layout {}",
                    map.development_seeds[0],
                    map.development_seeds[1],
                    map.held_out_seeds[0],
                    map.held_out_seeds[1],
                    map.held_out_layout_seed
                );
                println!(
                    "{:<20} {:>9} {:>9} {:>11} {:>10} {:>7} {:>16}",
                    "factor", "level", "best", "straight m", "aided m", "ratio", "95 % CI"
                );
                for c in &map.cells {
                    let base = if c.base { " (base)" } else { "" };
                    println!(
                        "{:<20} {:>9} {:>9} {:>11.3} {:>10.3} {:>7.2} [{:>5.2}, {:>5.2}]{base}",
                        c.factor, c.level, c.best, c.straight_m, c.aided_m, c.ratio, c.ratio_ci95[0], c.ratio_ci95[1]
                    );
                }
            })
        }
        ExperimentCommand::ThesisTable2 { step, trials, jobs, json } => {
            if !(step.is_finite() && step > 0.0 && step < 10.0) || trials == 0 || trials > 100_000 {
                eprintln!("error: need 0 < --step < 10 m and 1 ≤ --trials ≤ 100000");
                return ExitCode::from(EXIT_BAD_INPUT);
            }
            let shares: Vec<f64> = (0..=20).map(|k| f64::from(k) / 100.0).collect();
            thesis_table2(registry, step, trials, &shares, jobs.unwrap_or_else(cores)).map(|table| {
                if json {
                    println!("{}", serde_json::to_string_pretty(&table).expect("results serialise"));
                    return;
                }
                println!(
                    "Single-landmark egomotion error for one {:.2} m frame step, pixel noise {} px, {} frame pairs per row",
                    table.step_m, table.pixel_noise_px, table.trials
                );
                println!("{:>10} {:>10} {:>12} {:>8} {:>8} {:>8}", "outliers", "landmarks", "median |e| m", ">0.1 m", ">1 m", ">2 m");
                let row = |label: String, s: &crate::experiment::Table2Stats| {
                    println!(
                        "{label:>10} {:>10} {:>12.3} {:>7.0}% {:>7.0}% {:>7.0}%",
                        s.landmarks,
                        s.median_abs_m,
                        100.0 * s.beyond_0_1_m,
                        100.0 * s.beyond_1_m,
                        100.0 * s.beyond_2_m
                    );
                };
                row("thesis".into(), &table.thesis);
                for r in &table.rows {
                    let mark = if r.outlier_share == table.best_outlier_share { " *" } else { "" };
                    row(format!("{:.0} %{mark}", 100.0 * r.outlier_share), &r.stats);
                }
                println!("(* nearest the thesis beyond 1 m and 2 m: outlier_share {:.2})", table.best_outlier_share);
            })
        }
        ExperimentCommand::ThesisTable4 { seeds, objective, jobs, json } => {
            thesis_table4(registry, seeds, jobs.unwrap_or_else(cores), objective).map(|table| {
                if json {
                    println!("{}", serde_json::to_string_pretty(&table).expect("results serialise"));
                    return;
                }
                println!("Journey CV (lower is better); egomotion failures in brackets");
                println!("{:>8} {:>14} {:>14} {:>14} {:>14}", "corridor", "none", "zigzag", "scan", "tracking");
                for chunk in table.runs.chunks(TECHNIQUES.len()) {
                    print!("{:>8}", chunk[0].corridor);
                    for r in chunk {
                        let unfinished = if r.reached_goal { "" } else { "*" };
                        print!(" {:>8.3} ({:>3}){unfinished}", r.journey_cv, r.egomotion_failures);
                    }
                    println!();
                }
                print!("{:>8}", "mean");
                for t in TECHNIQUES {
                    print!(" {:>8.3} ({:>3.0})", table.mean[t.name()], table.mean_failures[t.name()]);
                }
                println!();
                print!("{:>8}", "vs none");
                for t in TECHNIQUES {
                    print!(" {:>13.0}%", -table.improvement_pct[t.name()]);
                }
                println!("\n(* did not reach the goal in time)");
            })
        }
        ExperimentCommand::ThesisEndpoint {
            seeds,
            jobs,
            json,
            rendered,
            layout_seed,
            objective,
            rotate_then_translate,
        } => {
            let profile = rotate_then_translate
                .then_some(ubf_robots::sim::MotionProfile::RotateThenTranslate { heading_tolerance_deg: 2.0 });
            let options =
                EndpointOptions { seeds, jobs: jobs.unwrap_or_else(cores), rendered, layout_seed, objective, profile };
            thesis_endpoint(registry, &options).map(|result| {
                if json {
                    println!("{}", serde_json::to_string_pretty(&result).expect("results serialise"));
                    return;
                }
                let layout = result.layout_seed.map_or("each route's own layout".into(), |s| format!("layout seed {s}"));
                println!(
                    "End-point egomotion error, m: mean [95 % CI] over seeds {}..{}, {} camera, {layout}, {:?} objective",
                    result.seeds[0], result.seeds[1], result.camera, result.objective
                );
                for (route, estimators) in &result.routes {
                    for (estimator, techniques) in estimators {
                        println!("\n{route}, {estimator} estimator");
                        println!(
                            "{:>9} {:>24} {:>7} {:>8} {:>8} {:>8} {:>9} {:>7} {:>7} {:>7}",
                            "technique",
                            "end-point error m",
                            "% dist",
                            "pred σ",
                            "act/pred",
                            "failures",
                            "outages",
                            "time lim",
                            "path +%",
                            "time +%"
                        );
                        for t in TECHNIQUES {
                            let Some(c) = techniques.get(t.name()) else { continue };
                            let e = &c.endpoint_error_m;
                            println!(
                                "{:>9} {:>7.2} {:>16} {:>7.2} {:>8.2} {:>8.2} {:>8.1} {:>9.1} {:>7} {:>7.1} {:>7.1}",
                                t.name(),
                                e.mean,
                                e.ci95.map_or("(n too small)".to_owned(), |[l, h]| format!("[{l:>6.2}, {h:>6.2}]")),
                                c.endpoint_error_pct.mean,
                                c.predicted_sigma_m.mean,
                                c.actual_over_predicted,
                                c.egomotion_failures.mean,
                                c.outages.mean,
                                c.runs_time_limit,
                                c.path_overhead_pct.mean,
                                c.time_overhead_pct.mean
                            );
                        }
                    }
                }
            })
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_FAILURE)
        }
    }
}

fn parse_jobs(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(0) => Err("at least one job is needed".into()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!("`{text}` is not a number of jobs")),
    }
}

fn parse_objective(text: &str) -> Result<DecisionObjective, String> {
    match text {
        "end-point" => Ok(DecisionObjective::EndPoint),
        "cv" => Ok(DecisionObjective::Cv),
        _ => Err("expected `end-point` or `cv`".into()),
    }
}

fn parse_depths(text: &str) -> Result<[f64; 2], String> {
    let (a, b) = text.split_once("..").ok_or("expected NEAR..FAR, in metres")?;
    let number = |s: &str| s.trim().parse::<f64>().map_err(|_| format!("`{s}` is not a depth in metres"));
    let (near, far) = (number(a)?, number(b)?);
    if !(near.is_finite() && far.is_finite() && 0.0 < near && near < far && far <= 1000.0) {
        return Err(format!("`{text}`: need 0 < NEAR < FAR ≤ 1000 m"));
    }
    Ok([near, far])
}

fn fit_costs_command(logs: &[PathBuf], json: bool) -> ExitCode {
    use crate::cost_fit::{find_logs, fit_costs};
    let fit = match find_logs(logs).and_then(|paths| fit_costs(&paths)) {
        Ok(fit) => fit,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&fit).expect("a fit serialises"));
        return ExitCode::SUCCESS;
    }
    println!("logs            {} ({} turns, {} straight steps)", fit.logs, fit.turns, fit.steps);
    println!("turns           mean {:.1}°, RMS heading error {:.3}°", fit.turn_mean_deg, fit.turn_rms_error_deg);
    println!("steps           RMS translation error {:.4} m", fit.step_rms_error_m);
    println!("as the decision's costs (paste into ActionAiding(costs: ...)):");
    println!(
        "  (step_sigma_per_cv: {:.4e}, heading_var_per_rad: {:.4e}, heading_var_per_turn: {:.4e})",
        fit.step_sigma_per_cv, fit.heading_var_per_rad, fit.heading_var_per_turn
    );
    ExitCode::SUCCESS
}

fn model_command(registry: &Registry, action: ModelCommand) -> ExitCode {
    use ubf_perception::error_model::{fit_exponential, GeometricModel};
    let args = match &action {
        ModelCommand::Fit { camera, .. } | ModelCommand::Heatmap { camera, .. } => camera,
        ModelCommand::FitCosts { logs, json } => return fit_costs_command(logs, *json),
    };
    if !(args.step.is_finite() && args.step > 0.0) {
        eprintln!("error: --step must be a positive number of metres");
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    let camera = match &args.scenario {
        None => ubf_perception::StereoCamera::default(),
        Some(file) => match Scenario::load(registry, file) {
            Ok(s) => s.robot.camera.map(|c| c.stereo).unwrap_or_default(),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(EXIT_BAD_INPUT);
            }
        },
    };
    let geometric = GeometricModel::new(&camera, args.step);
    let depths = [args.depths[0].max(geometric.min_depth()), args.depths[1]];
    if depths[1] <= depths[0] {
        eprintln!(
            "error: --depths: FAR must exceed the camera's nearest stereo depth, {:.2} m (with this camera)",
            depths[0]
        );
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    let fit = fit_exponential(|x, y| geometric.cv(x, y), &camera, depths, 0.25);
    match action {
        ModelCommand::Fit { json: true, .. } => {
            println!("{}", serde_json::to_string_pretty(&fit).expect("a fit report always serialises"));
        }
        ModelCommand::Fit { .. } => {
            println!(
                "camera          f = {:.1} px, T = {:.3} m, {}×{} px",
                camera.focal_px, camera.baseline_m, camera.width_px, camera.height_px
            );
            println!(
                "model step      {} m; fitted over depths {:.2}–{:.2} m, {} points of the field of view",
                args.step, depths[0], depths[1], fit.samples
            );
            println!("CV(x, y)        α·exp(β·y)·exp(−γ·|x|)");
            println!("α               {:.6e}", fit.model.alpha);
            println!("β               {:.5} 1/m", fit.model.beta);
            println!("γ               {:.5} 1/m", fit.model.gamma);
            println!("R² of ln CV     {:.4}", fit.r_squared_log);
            println!(
                "relative error  median {:.1} %, 95th percentile {:.1} %",
                100.0 * fit.median_relative_error,
                100.0 * fit.p95_relative_error
            );
            println!(
                "pair ordering   {:.1} % of landmark pairs ranked as the geometric model ranks them",
                100.0 * fit.pair_order_agreement
            );
        }
        // Answered before a camera was needed.
        ModelCommand::FitCosts { .. } => {}
        ModelCommand::Heatmap { exponential, out, .. } => {
            let m = fit.model;
            let (title, cv): (&str, &dyn Fn(f64, f64) -> f64) = if exponential {
                ("Fitted exponential model (eq. 24)", &|x, y| m.cv(x, y))
            } else {
                ("Geometric error model (eq. 16-23)", &|x, y| geometric.cv(x, y))
            };
            let result = crate::plot::draw_error_model(title, cv, &camera, depths[1], &out);
            if let Err(e) = result {
                eprintln!("error: {e}");
                return ExitCode::from(EXIT_FAILURE);
            }
            println!("wrote {}", out.display());
        }
    }
    ExitCode::SUCCESS
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
    if range.end - range.start > 10_000_000 {
        return Err(format!("`{text}` holds {} seeds; at most 10 000 000", range.end - range.start));
    }
    Ok(range)
}

/// Makes `out` ready for a sweep: absent or empty, or, with `overwrite`,
/// an earlier sweep's output (it holds a summary.json), which is removed.
fn clear_sweep_output(out: &std::path::Path, overwrite: bool) -> Result<(), String> {
    let shown = out.display();
    let mut entries = match std::fs::read_dir(out) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(format!("--out {shown}: {e}")),
    };
    if entries.next().is_none() {
        return Ok(());
    }
    if !overwrite {
        return Err(format!(
            "--out {shown} is not empty: earlier runs would sit beside the new summary. \
             Choose another directory, or pass --overwrite to replace an earlier sweep's output"
        ));
    }
    if !out.join("summary.json").is_file() {
        return Err(format!("--out {shown} holds no summary.json, so it is not a sweep's output: not deleting it"));
    }
    std::fs::remove_dir_all(out).map_err(|e| format!("clearing --out {shown}: {e}"))
}

/// Makes `out` ready for one shard of a sweep: other shards' output may be
/// there (shards often share a directory), but this shard's record only
/// with `overwrite`.
fn clear_shard_output(out: &std::path::Path, shard: crate::sweep::Shard, overwrite: bool) -> Result<(), String> {
    let record = out.join(shard.record_name());
    if !record.exists() {
        return Ok(());
    }
    if !overwrite {
        return Err(format!(
            "{} exists: this shard has run before. Pass --overwrite to run it again",
            record.display()
        ));
    }
    std::fs::remove_file(&record).map_err(|e| format!("removing {}: {e}", record.display()))
}

#[allow(clippy::too_many_arguments)]
fn sweep_command(
    registry: &Registry,
    files: &[PathBuf],
    seeds: std::ops::Range<u64>,
    shard: Option<crate::sweep::Shard>,
    jobs: Option<usize>,
    out: &std::path::Path,
    trajectories: bool,
    huge: bool,
) -> ExitCode {
    let mut items: Vec<crate::sweep::SweepItem> = Vec::new();
    for file in files {
        let loaded = if huge { Scenario::load_unbounded(registry, file) } else { Scenario::load(registry, file) };
        let scenario = match loaded {
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
    if let Some(shard) = shard {
        return match crate::sweep::sweep_shard(&items, seeds.clone(), shard, jobs, out, trajectories) {
            Ok(record) => {
                let total = items.len() * (seeds.end - seeds.start) as usize;
                let runs = (0..total).filter(|&t| shard.takes(t)).count();
                println!(
                    "shard {}/{}: {runs} runs in {:.2} s on {jobs} job(s); {} failed",
                    shard.index,
                    shard.count,
                    stopwatch.elapsed_s(),
                    record.failed.len()
                );
                println!(
                    "record: {}; once every shard has run: ubf sweep merge DIR...",
                    out.join(shard.record_name()).display()
                );
                for (label, seed, error) in &record.failed {
                    eprintln!("error: {label} seed {seed}: {error}");
                }
                if record.failed.is_empty() {
                    ExitCode::SUCCESS
                } else {
                    ExitCode::from(EXIT_FAILURE)
                }
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(EXIT_FAILURE)
            }
        };
    }
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

fn tree_command(registry: &Registry, file: &std::path::Path, mermaid: bool) -> ExitCode {
    let spec = if is_robot_file(file) {
        crate::drive::DriveConfig::load(registry, file).map(|(config, _)| config.root)
    } else {
        Scenario::load(registry, file).map(|s| s.root).map_err(|e| e.to_string())
    };
    let root = match spec {
        Ok(spec) => spec.build(&ubf_core::BuildContext::new(0)),
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    print!("{}", if mermaid { crate::tree::mermaid(root.as_ref()) } else { crate::tree::dot(root.as_ref()) });
    ExitCode::SUCCESS
}

fn check_command(registry: &Registry, files: &[PathBuf]) -> ExitCode {
    let mut code = ExitCode::SUCCESS;
    for file in files {
        let checked = if is_robot_file(file) {
            crate::drive::DriveConfig::load(registry, file).map(|(config, model)| {
                format!(
                    "robot file \"{}\": a {} at {}, {} behaviour nodes",
                    config.name,
                    model.name,
                    config.connection,
                    {
                        ubf_core::TreeLayout::of(config.root.build(&ubf_core::BuildContext::new(0)).as_ref())
                            .nodes
                            .len()
                    }
                )
            })
        } else {
            Scenario::load(registry, file).map(|s| format!("scenario \"{}\"", s.name)).map_err(|e| e.to_string())
        };
        match checked {
            Ok(what) => println!("{}: ok, {what}", file.display()),
            Err(e) => {
                eprintln!("error: {e}");
                code = ExitCode::from(EXIT_BAD_INPUT);
            }
        }
    }
    code
}

/// Whether `file` is a robot file for `ubf drive` rather than a scenario:
/// it names itself `RobotConfig(…)`, or has a `connection`.
fn is_robot_file(file: &std::path::Path) -> bool {
    let Ok(text) = std::fs::read_to_string(file) else { return false };
    let body: String = text.lines().map(|l| l.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n");
    let body = body.trim_start();
    body.starts_with("RobotConfig") || (body.starts_with('(') && body.contains("connection:"))
}

fn pose_text(p: &Pose2) -> String {
    format!("({:.3}, {:.3}) m, {:.1}°", p.x, p.y, p.theta.to_degrees())
}

fn print_summary(s: &RunReport) {
    let ending = match s.end {
        EndReason::GoalReached => "robot believes it reached the goal",
        EndReason::TimeLimit => "time limit",
        EndReason::BehaviorFailed => "a behaviour failed; the robot was stopped",
        EndReason::Interrupted => "interrupted",
    };
    println!("scenario        {} (seed {})", s.scenario, s.seed);
    println!("ended           {ending} after {:.1} s simulated, {} ticks", s.sim_time_s, s.ticks);
    if let Some(failure) = &s.failure {
        println!("failure         {failure}");
    }
    println!("goal reached    {}", if s.reached_goal { "yes" } else { "no" });
    println!("distance        {:.2} m", s.distance_m);
    println!("collisions      {}", s.collisions);
    println!("true pose       {}", pose_text(&s.final_true_pose));
    println!("estimated pose  {}", pose_text(&s.final_estimated_pose));
    if let (Some(error), Some(steps), Some(failures)) = (s.endpoint_error_m, s.egomotion_steps, s.egomotion_failures) {
        println!("egomotion       end-point error {error:.2} m; {steps} steps, {failures} failed");
        if let Some(sigma) = s.predicted_endpoint_sigma_m {
            println!("predicted       end-point σ {sigma:.2} m (the decision's error model)");
        }
        println!(
            "outages         {} ({:.1} s, {:.2} m driven on odometry)",
            s.outages.unwrap_or(0),
            s.outage_s.unwrap_or(0.0),
            s.outage_m.unwrap_or(0.0)
        );
    }
    println!("wall time       {:.3} s", s.wall_time_s);
}
