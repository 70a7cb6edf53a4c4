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

mod bug_report;
mod experiment;
mod images;
mod inspect;
mod network_log;
mod new;
mod out_dir;
mod repeated_warnings;
mod robot;
mod run;
mod shard;
mod sweep;

use crate::ros2_log::LogFormat;
use clap::{Parser, Subcommand};
use experiment::{parse_depths, parse_fusion, parse_heights, parse_model, parse_objective};
use images::{parse_frame_count, parse_limit, parse_offset};
use robot::{parse_room, parse_silence, parse_sip_period};
use run::{parse_seconds, parse_speed};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use sweep::{parse_jobs, parse_seeds};
use ubf_behaviors::DecisionObjective;
use ubf_core::Registry;
use ubf_perception::egomotion::OdometryFusion;
use ubf_perception::error_model::ErrorModelKind;

/// Exit code for bad input: a malformed file, a bad argument.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code for a run that failed after its input was accepted.
pub const EXIT_FAILURE: u8 = 1;

/// Exit code for a run stopped by Ctrl-C or SIGTERM (128 + SIGINT, as
/// shells report it).
pub const EXIT_INTERRUPTED: u8 = 130;

/// How a command that did its job ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Exit {
    /// All well (exit code 0).
    Success,
    /// What it ran failed, and it said so: a behaviour, a run of a sweep, a
    /// lost link (exit code 1).
    Failure,
    /// Ctrl-C or SIGTERM ended it, and it reported what it had (130).
    Interrupted,
    /// Some of its input was bad, and each was reported (exit code 2).
    BadInput,
}

/// Why a command could not do its job. Which variant decides the exit
/// code; [`finish`] is the one place that maps them.
#[derive(Debug, thiserror::Error)]
enum CliError {
    /// Bad input: a malformed file, a bad argument (exit code 2).
    #[error("{0}")]
    BadInput(Box<dyn std::error::Error + Send + Sync>),
    /// The input was accepted and then something failed (exit code 1).
    #[error("{0}")]
    Failed(Box<dyn std::error::Error + Send + Sync>),
}

impl CliError {
    fn bad_input(error: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        CliError::BadInput(error.into())
    }

    fn failed(error: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        CliError::Failed(error.into())
    }

    /// A failure to do something with `file`, which the message names.
    fn failed_in(file: &std::path::Path, error: impl std::fmt::Display) -> Self {
        CliError::Failed(format!("{}: {error}", file.display()).into())
    }
}

type Outcome = Result<Exit, CliError>;

/// The exit code for how a command ended, its error printed.
fn finish(outcome: Outcome) -> ExitCode {
    match outcome {
        Ok(Exit::Success) => ExitCode::SUCCESS,
        Ok(Exit::Failure) => ExitCode::from(EXIT_FAILURE),
        Ok(Exit::Interrupted) => ExitCode::from(EXIT_INTERRUPTED),
        Ok(Exit::BadInput) => ExitCode::from(EXIT_BAD_INPUT),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(match e {
                CliError::BadInput(_) => EXIT_BAD_INPUT,
                CliError::Failed(_) => EXIT_FAILURE,
            })
        }
    }
}

/// Prints a report as text, or with `json` as JSON: one path for both.
fn show<T: std::fmt::Display + serde::Serialize>(report: &T, json: bool) -> Result<(), CliError> {
    if json {
        let text = serde_json::to_string_pretty(report).map_err(|e| CliError::failed(format!("writing JSON: {e}")))?;
        println!("{text}");
    } else {
        print!("{report}");
    }
    Ok(())
}

/// Jobs by default: one per core.
fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

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
    #[command(group(clap::ArgGroup::new("paced").args(["ros2", "live", "watch"]).multiple(true)))]
    Run {
        /// The scenario file (RON).
        file: PathBuf,
        /// Use this seed instead of the scenario's.
        #[arg(long)]
        seed: Option<u64>,
        /// Write report.json, trajectory.csv, run.mcap and plot.png into
        /// this directory (absent or empty).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Replace an earlier run's output in `--out` (a directory holding
        /// its report.json or run.mcap); without this a non-empty `--out`
        /// is refused, so an earlier run is never overwritten by accident.
        #[arg(long, requires = "out")]
        overwrite: bool,
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
        /// `ros2` also writes the log as a rosbag2 directory
        /// (`run-rosbag2/` in `--out`: CDR messages, standard ROS 2 types),
        /// for `ros2 bag` and the rosbags library; the JSON `run.mcap`
        /// stays, for Foxglove, `ubf replay` and the plot.
        #[arg(long, value_enum, default_value_t = LogFormat::Json, requires = "out")]
        log_format: LogFormat,
        /// Publish the run on ROS 2 as it goes (in `ROS_DOMAIN_ID`):
        /// `/tf`, `/odom`, `/scan`, camera images, `/ubf/tick`, `/ubf/goal`,
        /// paced at real time, for RViz, Foxglove or `ros2 topic echo`.
        #[arg(long)]
        ros2: bool,
        /// Serve the run live to Foxglove on this address (e.g.
        /// `127.0.0.1:8765`; port 0 picks a free one), paced at real time:
        /// the topics of `run.mcap` on the Foxglove WebSocket protocol.
        /// Anyone who can reach the address can watch.
        #[arg(long, value_name = "ADDRESS")]
        live: Option<SocketAddr>,
        /// Watch the scenario file: each edit of its tree is checked and
        /// swapped in at a tick boundary; an edit that fails its check, or
        /// changes more than the tree, is refused and the running tree goes
        /// on. Paced at real time, like `--live`.
        #[arg(long)]
        watch: bool,
        /// With `--ros2`, `--live` or `--watch`, run this many times faster
        /// than real time.
        #[arg(long, default_value_t = 1.0, value_parser = parse_speed, requires = "paced")]
        speed: f64,
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
        /// Also run each scenario in these landmark layouts (its
        /// `random_landmarks` redrawn from each seed: `2121,2222,3000..3003`),
        /// labelled `NAME@SEED`: results on layouts nobody tuned on.
        #[arg(long, value_name = "SEEDS", value_parser = sweep::parse_layout_seeds)]
        layout_seeds: Option<sweep::LayoutSeeds>,
        /// Runs at once (at least 1); by default one per core.
        #[arg(long, value_parser = parse_jobs)]
        jobs: Option<usize>,
        /// Where the reports and the summary go.
        #[arg(long, required = true)]
        out: Option<PathBuf>,
        /// Run only share K of N (from 0) of the runs, leaving their
        /// reports and `shard-K-of-N.json` in `--out` (which may hold other
        /// shards' output) instead of a summary; `ubf sweep merge` then
        /// combines the shards. `auto` takes K and N from a Slurm job
        /// array's variables, `auto/N` takes K from a Kubernetes Indexed
        /// Job's `JOB_COMPLETION_INDEX` (docs/cluster.md).
        #[arg(long, value_name = "K/N|auto|auto/N", value_parser = shard::ShardSpec::parse)]
        shard: Option<shard::ShardSpec>,
        /// Also write every run's trajectory.csv and plot.png.
        #[arg(long)]
        trajectories: bool,
        /// Replace an earlier sweep's output in `--out` (a directory holding
        /// its summary.json); without this a non-empty `--out` is refused,
        /// so old runs never sit beside a new summary.
        #[arg(long)]
        overwrite: bool,
        /// Finish a sweep (or shard) that Ctrl-C or SIGTERM stopped in
        /// `--out`: run only the runs without a finished `seed-N/`, then
        /// write the summary. The same files, scenarios, seeds and options
        /// as the interrupted command are required.
        #[arg(long, conflicts_with = "overwrite")]
        resume: bool,
        /// Run it even beyond the bounds on runs and on ticks per run.
        #[arg(long)]
        huge: bool,
    },
    /// Write a new crate for your own behaviours into DIR (named after it):
    /// a behaviour, a scenario file using it, a test, and a Cargo.toml that
    /// builds the simulator optimised (docs/writing-a-behavior.md).
    New {
        /// The directory (absent or empty); its name is the crate's.
        dir: PathBuf,
        /// Take ubf from this checkout (default: the one this ubf was built
        /// from).
        #[arg(long, value_name = "DIR")]
        ubf_path: Option<PathBuf>,
        /// Take ubf from this git repository.
        #[arg(long, value_name = "URL", conflicts_with = "ubf_path")]
        ubf_git: Option<String>,
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
        #[arg(long, value_name = "FILE.png", value_parser = parse_png_path)]
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
        /// Where the images go (absent or empty).
        #[arg(long)]
        out: PathBuf,
        /// Replace an earlier recording in `--out` (a directory holding its
        /// frames.csv or camera.ron); without this a non-empty `--out` is
        /// refused.
        #[arg(long)]
        overwrite: bool,
        /// Seed (default: the scenario's).
        #[arg(long)]
        seed: Option<u64>,
        /// Stop after this many pairs (at least 1).
        #[arg(long, default_value_t = 100_000, value_parser = parse_frame_count)]
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
        /// Leave the landmarks as the calibration's disparity offset puts
        /// them, and only report the offset egomotion reads from the frames
        /// (`disparity_offset_px` in the JSON); without this flag they are
        /// corrected by it once it has settled (over ten steps).
        #[arg(long)]
        keep_disparity_offset: bool,
        /// Draw the estimated path (over the true one, if known) here (PNG).
        #[arg(long, value_name = "FILE.png", value_parser = parse_png_path)]
        plot: Option<PathBuf>,
        /// Write every landmark of every pair here (CSV: pair, pixels with
        /// the first pixel's centre at (0, 0), disparity as matched,
        /// camera-frame point, and the disparity offset the point was
        /// triangulated with). Each point is triangulated as egomotion
        /// triangulates it when its pair comes in: corrected by the offset
        /// read from the frames once it has settled, unless
        /// --keep-disparity-offset.
        #[arg(long, value_name = "FILE.csv")]
        landmarks: Option<PathBuf>,
    },
    /// Drive a real robot (or an emulator) with a behaviour tree; Ctrl-C or
    /// SIGTERM stops it safely.
    Drive {
        /// The robot configuration file (RON).
        file: PathBuf,
        #[command(flatten)]
        options: robot::DriveOptions,
    },
    /// Emulate a FLIR PTU pan-tilt head on a TCP port or a pseudo-terminal,
    /// for trying a robot file's `pan_tilt` without the head.
    EmulatePtu {
        /// Address to listen on.
        #[arg(long, default_value = "127.0.0.1:4000", conflicts_with = "pty")]
        listen: String,
        /// Serve on a new pseudo-terminal instead, as the head's serial port
        /// would be; prints its device path for `connection`.
        #[arg(long)]
        pty: bool,
        /// The head counts its pan clockwise (a robot file then needs
        /// `invert_pan: true`).
        #[arg(long)]
        clockwise: bool,
    },
    /// Serve a scenario's simulated robot as a ROS 2 robot (in
    /// `ROS_DOMAIN_ID`), for another stack to drive: it takes `/cmd_vel` and
    /// publishes `/odom`, `/tf`, `/scan` and camera images, paced at real
    /// time, until Ctrl-C.
    Simulate {
        /// The scenario file (RON): its world, robot and start are served;
        /// its tree is not used.
        file: PathBuf,
        /// Serve it on ROS 2 (the only way so far).
        #[arg(long, required = true)]
        ros2: bool,
        /// Use this seed instead of the scenario's.
        #[arg(long)]
        seed: Option<u64>,
        /// Run this many times faster than real time.
        #[arg(long, default_value_t = 1.0, value_parser = parse_speed)]
        speed: f64,
        /// Stop after this many simulated seconds.
        #[arg(long, value_parser = parse_seconds)]
        max_time: Option<f64>,
        /// Take `geometry_msgs/msg/TwistStamped` on `/cmd_vel`, as Nav2
        /// sends from Kilted on, instead of `Twist`.
        #[arg(long)]
        cmd_vel_stamped: bool,
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
        /// Cut the link AFTER seconds into each session, for FOR seconds:
        /// nothing read or sent while the robot drives on under its last
        /// command (and its watchdog), as with a cable pulled and plugged
        /// back in.
        #[arg(long, value_name = "AFTER:FOR", value_parser = parse_silence)]
        cut: Option<(f64, f64)>,
        /// Cut only the first N sessions (default: every one).
        #[arg(long, value_name = "N", requires = "cut")]
        cuts: Option<u32>,
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
        #[arg(long, value_name = "FILE.png", value_parser = parse_png_path)]
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
        /// The error model the evaluative techniques weigh landmarks by:
        /// `geometric` (eq. 16–23), `geometric-3d` (also in image rows,
        /// §5.3.1), `fitted-exponential` or `fitted-exponential-3d`.
        #[arg(long, default_value = "geometric", value_parser = parse_model)]
        model: ErrorModelKind,
        /// Drive with the thesis's decoupled motion (turn on the spot, then
        /// translate) instead of the routes' continuous profile.
        #[arg(long)]
        rotate_then_translate: bool,
        /// What of odometry's motion the rigid estimator's visual motions
        /// are combined with, in place of what the route files say (`off`,
        /// as the thesis measured): `off`, `sideways` or `full` (see
        /// `odometry_fusion` in docs/scenario-format.md).
        #[arg(long, value_parser = parse_fusion)]
        odometry_fusion: Option<OdometryFusion>,
    },
}

#[derive(Debug, Subcommand)]
enum ModelCommand {
    /// Fit the exponential model (eq. 24) to the geometric one (eq. 16–23)
    /// and report the fit's quality: the thesis's planar form beside the 3D
    /// form, which also counts image motion in rows (§5.3.1).
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
        /// Instead of fitting, compare the model's form with others on
        /// seeds kept apart (the logs must be in a sweep's `seed-N`
        /// directories, at least three seeds): the first two thirds of the
        /// seeds fit, the end points of the rest test.
        #[arg(long, conflicts_with = "against")]
        check: bool,
        /// Logs (or directories of logs) of straight runs: fit each other
        /// log's difference from the straight run of the same scenario and
        /// seed (named by the report.json beside each log), which is what
        /// the decision chooses between, instead of the end points as they
        /// are, where the step term is also credited with whatever
        /// separates one route from another.
        #[arg(long, num_args = 1..)]
        against: Vec<PathBuf>,
        /// Write the fitted coefficients into the decision's coefficients
        /// file (`behaviors/src/decision_costs.ron`, built into the next
        /// build): the `against_straight` part with `--against`, `levels`
        /// without.
        #[arg(long, value_name = "FILE", conflicts_with = "check")]
        write: Option<PathBuf>,
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
    /// Lowest and highest landmark height of the 3D fit, relative to the
    /// cameras, m, as `LOW..HIGH` (default: the floor to a 2.5 m ceiling).
    #[arg(long, value_parser = parse_heights, allow_hyphen_values = true)]
    heights: Option<[f64; 2]>,
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
    bug_report::install();
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
    if !matches!(
        cli.command,
        Command::Drive { .. } | Command::Simulate { .. } | Command::EmulatePowerbot { .. } | Command::EmulatePtu { .. }
    ) {
        // SAFETY: restoring the default action of a signal, before any
        // thread has started.
        unsafe {
            libc::signal(libc::SIGPIPE, libc::SIG_DFL);
        }
    }
    // A bad ROS_DOMAIN_ID is bad input, said before anything runs.
    let ros2 = match &cli.command {
        Command::Run { ros2, .. } => *ros2,
        Command::Simulate { .. } => true,
        _ => false,
    };
    if ros2 {
        if let Err(e) = ubf_robots::ros2::domain_from_env() {
            return finish(Err(CliError::bad_input(e)));
        }
    }
    let outcome = match cli.command {
        Command::Run { file, seed, out, overwrite, json, huge, log_images, log_format, ros2, live, watch, speed } => {
            let paced = ros2 || live.is_some() || watch;
            let live = paced.then_some(crate::run::Live { speed, ros2, foxglove: live, trees: None });
            let rosbag = log_format == LogFormat::Ros2;
            let outputs = out.as_deref().map(|dir| crate::run::Outputs { dir, images: log_images, rosbag });
            run::command(&registry, &file, seed, outputs, run::RunFlags { json, huge, watch, overwrite }, live)
        }
        Command::Replay { file, plot } => run::replay(&file, plot),
        Command::Check { files } => inspect::check(&registry, &files),
        Command::New { dir, ubf_path, ubf_git } => {
            let source = ubf_path.map(new::UbfSource::Path).or(ubf_git.map(new::UbfSource::Git));
            new::command(&dir, source)
        }
        Command::Tree { file, mermaid } => inspect::tree(&registry, &file, mermaid),
        Command::Behaviors { describe, names } => inspect::behaviors(&registry, describe, &names),
        Command::Sweep { action: Some(SweepAction::Merge { dirs, out }), .. } => sweep::merge(&dirs, out.as_deref()),
        Command::Sweep {
            action: None,
            files,
            seeds,
            layout_seeds,
            jobs,
            out,
            shard,
            trajectories,
            overwrite,
            resume,
            huge,
        } => {
            let (Some(seeds), Some(out)) = (seeds, out) else {
                unreachable!("clap requires --seeds and --out without a subcommand")
            };
            let request = sweep::SweepRequest {
                files: &files,
                seeds,
                layout_seeds: layout_seeds.as_ref().map(|l| l.0.as_slice()),
                shard,
                jobs,
                out: &out,
                trajectories,
                overwrite,
                resume,
                huge,
            };
            sweep::command(&registry, request)
        }
        Command::Model { action } => experiment::model(&registry, action),
        Command::Experiment { which } => experiment::command(&registry, which),
        Command::Drive { file, options } => robot::drive(&registry, &file, options),
        Command::Simulate { file, ros2: _, seed, speed, max_time, cmd_vel_stamped } => {
            run::simulate(&registry, &file, seed, speed, max_time, cmd_vel_stamped)
        }
        Command::EmulatePowerbot { listen, pty, room, sip_period_ms, silence, cut, cuts } => {
            let mut config =
                ubf_robots::arcos::emulator::EmulatorConfig::new(ubf_robots::model::RobotModel::powerbot());
            if let Some((length, width)) = room {
                config = config.in_room(length, width);
            }
            config.sip_period = std::time::Duration::from_secs_f64(sip_period_ms / 1000.0);
            let window =
                |(after, span)| (std::time::Duration::from_secs_f64(after), std::time::Duration::from_secs_f64(span));
            config.silence = silence.map(window);
            config.cut = cut.map(window);
            robot::emulate(&listen, pty, &config, cuts)
        }
        Command::EmulatePtu { listen, pty, clockwise } => {
            let config = ubf_robots::ptu::PtuEmulatorConfig {
                clockwise_positive: clockwise,
                ..ubf_robots::ptu::PtuEmulatorConfig::default()
            };
            robot::emulate_ptu(&listen, pty, &config)
        }
        Command::Frames { file, out, seed, max_frames, huge, overwrite } => images::frames(
            &registry,
            images::FramesRequest { file: &file, out: &out, seed, max: max_frames, huge, overwrite },
        ),
        Command::Pipeline {
            dir,
            json,
            poses,
            max_speed,
            max_turn_rate,
            keyframe_range,
            disparity_offset,
            keep_disparity_offset,
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
                keep_disparity_offset,
                landmarks,
            };
            images::pipeline(&dir, &options, json, plot.as_deref())
        }
    };
    finish(outcome)
}

/// A plot's path, which must end in `.png`: the plot is drawn as PNG, and
/// a path that does not say so would fail only after all the work.
fn parse_png_path(text: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(text);
    match path.extension().and_then(|e| e.to_str()) {
        Some(extension) if extension.eq_ignore_ascii_case("png") => Ok(path),
        _ => Err(format!("`{text}` is not a FILE.png: the plot is drawn as PNG, named so")),
    }
}

/// Log to stderr at the level RUST_LOG sets, or else `-v`/`-q` (warnings by
/// default), with the warnings others on the network can cause budgeted
/// and, by default, a sweep's repeated warnings held back.
fn init_tracing(verbose: u8, quiet: bool) {
    use tracing_subscriber::EnvFilter;
    let level = match (quiet, verbose) {
        (true, _) => "error",
        (false, 0) => "warn",
        (false, 1) => "info",
        (false, 2) => "debug",
        (false, _) => "trace",
    };
    use tracing_subscriber::filter::FilterExt;
    use tracing_subscriber::layer::SubscriberExt;
    use tracing_subscriber::util::SubscriberInitExt;
    use tracing_subscriber::Layer;
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(level));
    // Counted only once the level lets a line through.
    let network = network_log::NetworkLines { datagram_sizes: verbose >= 2 };
    // Asked for more, or for what RUST_LOG says, the log holds no repeat back.
    let plain = verbose == 0 && std::env::var_os("RUST_LOG").is_none();
    let filter = filter.and(network).and(plain.then_some(repeated_warnings::RepeatedWarnings));
    use std::io::IsTerminal;
    let layer = tracing_subscriber::fmt::layer()
        .event_format(network_log::OneLineFromNetwork(tracing_subscriber::fmt::format()))
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .with_filter(filter);
    let _ = tracing_subscriber::registry().with(layer).try_init();
}
