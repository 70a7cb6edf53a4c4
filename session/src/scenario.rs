//! Scenario files: a robot, a goal, a behaviour tree, run headless.
//!
//! ```ron
//! Scenario(
//!     name: "go-to-open-floor",
//!     max_time_s: 60.0,
//!     goal: (x: 8.0, y: 3.0),
//!     root: Composite(
//!         arbiter: HighestPriority,
//!         children: [
//!             (behavior: Stop(), weight: 2.0),
//!             (behavior: GoTo(cruise_speed: 0.5)),
//!         ],
//!     ),
//! )
//! ```
//!
//! `docs/scenario-format.md` describes every field with its unit and default.

use serde::Deserialize;
use std::path::{Path, PathBuf};
use ubf_core::config::{checked, shown, RonError};
use ubf_core::{BehaviorSpec, Goal, OnBehaviorPanic, ProgressCheck, Registry};
use ubf_robots::sim::{SimRobotConfig, WorldConfig};

/// A headless run: a simulated robot, a goal and the behaviour tree.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// A short name for reports.
    #[serde(deserialize_with = "ubf_core::config::shown_name")]
    pub name: String,
    /// What the scenario is for.
    #[serde(default)]
    pub description: String,
    /// The seed of every random draw; `ubf run --seed` overrides it.
    #[serde(default)]
    pub seed: u64,
    /// Seconds between control ticks.
    #[serde(default = "Scenario::default_period_s", deserialize_with = "ubf_core::config::period_s")]
    pub period_s: f64,
    /// The run ends after this many simulated seconds if the goal is not
    /// reached first.
    #[serde(deserialize_with = "ubf_core::config::duration_s")]
    pub max_time_s: f64,
    /// The simulated robot.
    #[serde(default, deserialize_with = "checked")]
    pub robot: SimRobotConfig,
    /// Walls, boxes, landmarks and people; an open floor by default.
    #[serde(default, deserialize_with = "checked")]
    pub world: WorldConfig,
    /// Where the robot should go; without one the run lasts `max_time_s`.
    #[serde(default)]
    pub goal: Option<Goal>,
    /// End the run (`end: no_progress`) once the robot, by the pose it
    /// believes, has stayed within `radius_m` of one spot for `window_s`
    /// short of the goal: [`ProgressCheck::STANDARD`] unless set;
    /// `progress: None`, only the goal or the time limit ends it. A run
    /// without a goal is never ended by it.
    #[serde(default = "ProgressCheck::standard")]
    pub progress: Option<ProgressCheck>,
    /// What a panicking behaviour does: `Stop` (the default) ends the run
    /// with its report; `SkipBehavior` carries on without it.
    #[serde(default)]
    pub on_behavior_panic: OnBehaviorPanic,
    /// The behaviour tree.
    pub root: BehaviorSpec,
}

impl Scenario {
    /// Ticks the time limit allows: at least one, and rounded so that 60 s
    /// at 0.1 s is 600 ticks, not 601 from 599.999….
    pub fn max_ticks(&self) -> u64 {
        (self.max_time_s / self.period_s - 1e-9).ceil().max(1.0) as u64
    }

    fn default_period_s() -> f64 {
        0.1
    }

    /// Reads a scenario from RON text.
    pub fn from_ron(registry: &Registry, text: &str) -> Result<Scenario, RonError> {
        registry.from_ron(text)
    }

    /// Reads a scenario file, and refuses one whose robot starts touching a
    /// wall, a box or a person (a run from there could not move).
    pub fn load(registry: &Registry, path: &Path) -> Result<Scenario, LoadError> {
        Scenario::load_checked(registry, path, true)
    }

    /// [`Scenario::load`] without the bound on the work a run may do: for a
    /// deliberately huge run (`--huge`).
    pub fn load_unbounded(registry: &Registry, path: &Path) -> Result<Scenario, LoadError> {
        Scenario::load_checked(registry, path, false)
    }

    fn load_checked(registry: &Registry, path: &Path, bound_work: bool) -> Result<Scenario, LoadError> {
        let bytes = ubf_core::config::read_bounded(path, ubf_core::config::MOST_SETTINGS_BYTES)
            .map_err(|source| LoadError::Io { path: path.to_owned(), source })?;
        let parse_error = |error| LoadError::Parse { path: path.to_owned(), error };
        let text = ubf_core::config::utf8_text(bytes).map_err(parse_error)?;
        let scenario = Scenario::from_ron(registry, &text).map_err(parse_error)?;
        let checked = scenario.check_start().and_then(|()| if bound_work { scenario.check_work() } else { Ok(()) });
        checked.map_err(|refusal| parse_error(refusal.at(&text)))?;
        Ok(scenario)
    }

    /// What a run of this scenario costs at most: ticks, and the bytes of
    /// `trajectory.csv` (about 24 bytes a column a row).
    pub fn work(&self) -> Work {
        let ticks = self.max_ticks();
        let tree = self.root.build(&ubf_core::BuildContext::new(0));
        let nodes = ubf_core::TreeLayout::of(tree.as_ref()).nodes.len() as u64;
        let camera = self.robot.camera.as_ref();
        let camera_pairs = camera.map_or(0, |c| (self.max_time_s * c.rate_hz).ceil() as u64 + 1);
        let renders = camera.is_some_and(|c| c.images.is_some());
        Work {
            ticks,
            nodes,
            log_bytes: ticks.saturating_mul(Work::LOG_BYTES_PER_TICK + Work::LOG_BYTES_PER_NODE * nodes),
            camera_pairs,
            rendered_pairs: if renders { camera_pairs } else { 0 },
            pair_bytes: camera.map_or(0, |c| 2 * u64::from(c.stereo.width_px) * u64::from(c.stereo.height_px)),
        }
    }

    /// Refuses a run beyond [`Work::MOST_TICKS`] ticks or the rendering
    /// bound, saying how to proceed.
    pub fn check_work(&self) -> Result<(), Refusal> {
        let work = self.work();
        if work.ticks > Work::MOST_TICKS {
            return Err(Refusal::new(
                &["max_time_s"],
                format!(
                    "max_time_s / period_s: {} ticks, more than {} (logs of about {}); \
                 shorten max_time_s, lengthen period_s, or pass --huge to run it anyway",
                    work.ticks,
                    Work::MOST_TICKS,
                    Work::bytes_text(work.log_bytes)
                ),
            ));
        }
        let pixels = work.rendered_pairs.saturating_mul(work.pair_bytes);
        if pixels > Work::MOST_RENDERED_PIXELS {
            return Err(Refusal::new(
                &["robot", "camera", "images"],
                format!(
                    "robot.camera.images: {} rendered pairs of {} each, more than {:.0e} pixels (hours of rendering); \
                 shorten max_time_s, lower rate_hz or the image size, or pass --huge to run it anyway",
                    work.rendered_pairs,
                    Work::bytes_text(work.pair_bytes),
                    Work::MOST_RENDERED_PIXELS as f64
                ),
            ));
        }
        Ok(())
    }

    /// Refuses a run whose logs (`--out`, a sweep's `--trajectories`) would
    /// pass [`Work::MOST_LOG_BYTES`], saying how to proceed.
    pub fn check_logs(&self) -> Result<(), String> {
        let work = self.work();
        if work.log_bytes > Work::MOST_LOG_BYTES {
            return Err(format!(
                "max_time_s / period_s: {} ticks × {} nodes of the tree, logs of about {}, more than {}; \
                 shorten max_time_s, lengthen period_s, or pass --huge to run it anyway",
                work.ticks,
                work.nodes,
                Work::bytes_text(work.log_bytes),
                Work::bytes_text(Work::MOST_LOG_BYTES)
            ));
        }
        Ok(())
    }

    /// Whether the robot can start where the scenario puts it, and reach
    /// its goal's place.
    pub fn check_start(&self) -> Result<(), Refusal> {
        let robot = ubf_robots::sim::SimRobot::new(&self.robot, &self.world, self.period_s, self.seed);
        if robot.starts_in_contact() {
            let start = self.robot.start;
            return Err(Refusal::new(
                &["robot", "start"],
                format!(
                    "robot.start: at ({}, {}) the robot's outline overlaps a wall, a box or a person; \
                 a corridor runs from x = 0, so start it at least a metre in",
                    shown(start.x),
                    shown(start.y)
                ),
            ));
        }
        if let (Some(goal), Some(corridor)) = (self.goal, self.world.corridor) {
            let inside = goal.x > 0.0 && goal.x < corridor.length && goal.y.abs() < corridor.width / 2.0;
            if !inside {
                return Err(Refusal::new(
                    &["goal"],
                    format!(
                        "goal: ({}, {}) lies outside the corridor (x from 0 to {}, y within ±{}); the robot could \
                     never reach it",
                        shown(goal.x),
                        shown(goal.y),
                        shown(corridor.length),
                        shown(corridor.width / 2.0)
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Why a scenario that parses cannot run, and the field that says so.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct Refusal {
    /// The field's path from the top (`["robot", "start"]`).
    pub field: &'static [&'static str],
    /// What is wrong, naming the field.
    pub message: String,
}

impl Refusal {
    fn new(field: &'static [&'static str], message: String) -> Refusal {
        Refusal { field, message }
    }

    /// The refusal as an error at the field in the scenario's `text` (at
    /// its start where the field is not written).
    pub fn at(&self, text: &str) -> RonError {
        let (line, column) = ubf_core::config::field_position(text, self.field).unwrap_or((1, 1));
        RonError { line, column, message: self.message.clone() }
    }
}

/// The most a run can cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Work {
    /// Control ticks, at most.
    pub ticks: u64,
    /// The tree's nodes, each voting every tick.
    pub nodes: u64,
    /// Bytes of the run's logs (`trajectory.csv` and `run.mcap`), about.
    pub log_bytes: u64,
    /// Stereo pairs the camera takes, at most (0 without a camera).
    pub camera_pairs: u64,
    /// Of those, the pairs rendered as images (0 when the camera renders
    /// none).
    pub rendered_pairs: u64,
    /// Bytes (pixels) of one stereo pair, both images; 0 without a camera.
    pub pair_bytes: u64,
}

impl Work {
    /// The most ticks a run may take without `--huge`: a week of simulated
    /// time at 0.1 s.
    pub const MOST_TICKS: u64 = 6_000_000;

    /// The most bytes of logs a run may write without `--huge`.
    pub const MOST_LOG_BYTES: u64 = 4_000_000_000;

    /// Log bytes a tick costs besides its votes: measured, about 120 of
    /// trajectory and 800 of MCAP with a small tree (60 000 ticks).
    const LOG_BYTES_PER_TICK: u64 = 1_000;

    /// Log bytes each of a tree's nodes adds to a tick: its vote in both
    /// logs, its path in the MCAP's JSON.
    const LOG_BYTES_PER_NODE: u64 = 24;

    /// The most pixels a run may render without `--huge`: about 160 000
    /// pairs of 640 × 480, over an hour of rendering at 30 ms a pair.
    pub const MOST_RENDERED_PIXELS: u64 = 100_000_000_000;

    /// The most bytes `ubf frames` may write without `--huge`.
    pub const MOST_RECORDING_BYTES: u64 = 10_000_000_000;

    /// `1.2 GB`, `350 kB`.
    pub fn bytes_text(bytes: u64) -> String {
        let b = bytes as f64;
        match b {
            _ if b >= 1e9 => format!("{:.1} GB", b / 1e9),
            _ if b >= 1e6 => format!("{:.0} MB", b / 1e6),
            _ => format!("{:.0} kB", (b / 1e3).max(1.0)),
        }
    }
}

/// A scenario file that could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be read.
    #[error("{}: {}", path.display(), ubf_core::config::why_unread(path, source))]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not a valid scenario, or describes a run that cannot
    /// work: `FILE:LINE:COL: message`.
    #[error("{}:{error}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// Where and what.
        error: RonError,
    },
}
