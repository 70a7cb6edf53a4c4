//! A drive's logs: the CSV log every session must have, the MCAP log
//! beside it (with the session's report at its end, a wall-clock anchor at
//! its start and a cap on its size) and, where asked, a rosbag2 directory.

use super::{DriveConfig, DriveError};
use crate::json_topics::RunMessage;
use crate::mcap_log::McapLog;
use crate::ros2_log::{LogFormat, Ros2Log};
use crate::ros2_view::Shown;
use crate::trajectory::{Columns, TrajectoryWriter};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use ubf_core::{BackgroundSink, Controller, Pose2, Robot, TickRecord, TickSink, TreeLayout};
use ubf_robots::model::RobotModel;

/// How a session ended, set by the drive once it knows (before it stops the
/// robot and closes the logs) and read by the MCAP log as it closes.
#[derive(Clone, Debug, Default)]
pub(super) struct SessionEnding(Arc<Mutex<Option<Ending>>>);

/// An ending's name, and what failed if something did.
type Ending = (String, Option<String>);

impl SessionEnding {
    /// The session ended as `end` (`goal_reached`, `interrupted`, …), with
    /// the failure's description if it failed.
    pub(super) fn set(&self, end: &str, failure: Option<String>) {
        *self.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = Some((end.to_owned(), failure));
    }

    fn get(&self) -> Option<Ending> {
        self.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner).clone()
    }
}

/// The report at the end of a drive session's MCAP log (`/report`,
/// `ubf.DriveReport`).
#[derive(Debug, serde::Serialize, schemars::JsonSchema)]
pub struct DriveReport {
    /// The robot model driven.
    pub robot: String,
    /// Ticks run.
    pub ticks: u64,
    /// Controller time at the last tick, s.
    pub time_s: f64,
    /// Distance driven by odometry, m.
    pub distance_m: f64,
    /// Whether the robot believed itself within the goal's tolerance at the
    /// last tick.
    pub reached_goal: bool,
    /// How the session ended: `goal_reached`, `interrupted`, `time_limit`,
    /// `no_progress`, `link_lost` or `failed`.
    pub end: String,
    /// What failed, if something did.
    pub failure: Option<String>,
    /// The odometric pose at the last tick, in the drive's world frame.
    #[schemars(with = "crate::report::PoseSchema")]
    pub final_pose: Pose2,
}

/// A drive session's MCAP log: every tick, until the log reaches its cap,
/// and the session's report when it closes.
struct DriveMcap {
    log: McapLog,
    robot: String,
    ending: SessionEnding,
    /// Bytes at which the log stops taking images; at twice this it stops
    /// taking anything.
    cap_bytes: u64,
    ticks: u64,
    time: f64,
    distance: f64,
    last_pose: Option<Pose2>,
    reached_goal: bool,
    /// Images stopped for the cap.
    images_capped: bool,
    /// Everything stopped for the cap.
    full: bool,
}

impl DriveMcap {
    fn new(log: McapLog, robot: String, ending: SessionEnding, cap_mb: f64) -> Self {
        DriveMcap {
            log,
            robot,
            ending,
            cap_bytes: (cap_mb * 1e6) as u64,
            ticks: 0,
            time: 0.0,
            distance: 0.0,
            last_pose: None,
            reached_goal: false,
            images_capped: false,
            full: false,
        }
    }
}

impl TickSink for DriveMcap {
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.log.start(layout)
    }

    fn tree_changed(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.log.tree_changed(layout)
    }

    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        let pose = record.state.pose;
        self.distance += self.last_pose.map_or(0.0, |p| (pose.x - p.x).hypot(pose.y - p.y));
        self.last_pose = Some(pose);
        self.ticks += 1;
        self.time = record.time();
        self.reached_goal = record.state.goal.is_some_and(|g| (pose.x - g.x).hypot(pose.y - g.y) <= g.tolerance);
        let logged = self.log.logged_bytes();
        if logged >= self.cap_bytes && !self.images_capped {
            self.images_capped = true;
            self.log.log_images(false);
            crate::say!(
                "warning: the MCAP log holds {:.0} MB, its cap (log_max_mb); it takes no more images",
                logged as f64 / 1e6
            );
        }
        if logged >= 2 * self.cap_bytes && !self.full {
            self.full = true;
            crate::say!(
                "warning: the MCAP log holds {:.0} MB, twice its cap (log_max_mb); nothing more is written to it \
                 but its report (the CSV log goes on)",
                logged as f64 / 1e6
            );
        }
        if self.full {
            return Ok(());
        }
        self.log.record(record)
    }

    /// Writes the session's report, if the drive said how it ended, and
    /// closes the chunk under way.
    fn finish(&mut self) -> std::io::Result<()> {
        if let Some((end, failure)) = self.ending.get() {
            let report = DriveReport {
                robot: self.robot.clone(),
                ticks: self.ticks,
                time_s: self.time,
                distance_m: self.distance,
                reached_goal: self.reached_goal,
                end,
                failure,
                final_pose: self.last_pose.unwrap_or_default(),
            };
            self.log.write_report(self.time, &report).map_err(std::io::Error::other)?;
        }
        self.log.finish()
    }
}

/// The first of `base`, `stem.2.ext`, `stem.3.ext`, … that does not exist,
/// created: a new session (or a new drive) never overwrites a log.
fn create_fresh_log(base: &Path) -> std::io::Result<(std::fs::File, PathBuf)> {
    let stem = base.file_stem().map_or_else(|| "drive-log".into(), |s| s.to_string_lossy().into_owned());
    let ext = base.extension().map_or_else(|| "csv".into(), |s| s.to_string_lossy().into_owned());
    for n in 1..10_000u32 {
        let path = if n == 1 { base.to_owned() } else { base.with_file_name(format!("{stem}.{n}.{ext}")) };
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(file) => return Ok((file, path)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::other(format!("{}: 10 000 logs already; move some away", base.display())))
}

/// Records a log writer may fall behind by before records are dropped: 25 s
/// of ticks at 10 Hz.
const LOG_QUEUE: usize = 256;

/// Attaches the session's logs, each written on a thread of its own (a
/// slow disk must not delay a tick, and a failed log must not stop the
/// robot), and adds their paths to `logs`. The CSV log is the one a session
/// cannot do without; the MCAP log beside it is left out, with a warning, if
/// it cannot be made.
pub(super) fn attach_logs<R: Robot>(
    controller: &mut Controller<R>,
    config: &DriveConfig,
    model: &RobotModel,
    logs: &mut Vec<PathBuf>,
    ending: &SessionEnding,
) -> Result<(), DriveError> {
    let (file, path) =
        create_fresh_log(&config.log).map_err(|source| DriveError::Log { path: config.log.clone(), source })?;
    crate::say!("logging to {}", path.display());
    logs.push(path.clone());
    let camera_pan = config.camera.as_ref().is_some_and(|camera| camera.pan_tilt.is_some());
    let csv = TrajectoryWriter::new(file, &path, Columns { truth: false, hold: true, camera_pan });
    let sink =
        BackgroundSink::spawn(format!("CSV log {}", path.display()), csv, LOG_QUEUE).map_err(DriveError::LogWriter)?;
    controller.add_sink(Box::new(sink));
    let Some((mut mcap, mcap_path)) = open_session_mcap(&path, model, controller.state().pose, config.goal) else {
        return Ok(());
    };
    mcap.log_images(config.log_images);
    let drive_log = DriveMcap::new(mcap, model.name.clone(), ending.clone(), config.log_max_mb);
    match BackgroundSink::spawn(format!("MCAP log {}", mcap_path.display()), drive_log, LOG_QUEUE) {
        Ok(sink) => {
            crate::say!("and to {}", mcap_path.display());
            logs.push(mcap_path);
            controller.add_sink(Box::new(sink));
        }
        Err(e) => tracing::warn!("{e}; this session has only its CSV log"),
    }
    if config.log_format == LogFormat::Ros2 {
        attach_rosbag(controller, config, &path, logs);
    }
    Ok(())
}

/// The session's rosbag2 directory beside its CSV log (`NAME-rosbag2/`),
/// or a warning if it cannot be made: the CSV log is the one a session
/// cannot do without.
fn attach_rosbag<R: Robot>(controller: &mut Controller<R>, config: &DriveConfig, csv: &Path, logs: &mut Vec<PathBuf>) {
    let stem = csv.file_stem().map_or_else(|| "drive-log".into(), |s| s.to_string_lossy().into_owned());
    let dir = csv.with_file_name(format!("{stem}-rosbag2"));
    let epoch_s = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64());
    let opened = Ros2Log::create(&dir, Shown { robot: true, images: config.log_images, tree: true }, epoch_s)
        .map_err(|e| e.to_string())
        .and_then(|bag| {
            BackgroundSink::spawn(format!("rosbag2 log {}", dir.display()), bag, LOG_QUEUE).map_err(|e| e.to_string())
        });
    match opened {
        Ok(sink) => {
            crate::say!("and to {}", dir.display());
            logs.push(dir);
            controller.add_sink(Box::new(sink));
        }
        Err(e) => tracing::warn!("{e}; this session has no rosbag2 log"),
    }
}

/// The session's MCAP log beside its CSV one (same name, `.mcap`), or
/// `None` with a warning if it cannot be made: the CSV log is the one a
/// session cannot do without.
fn open_session_mcap(
    csv: &Path,
    model: &RobotModel,
    pose: Pose2,
    goal: Option<ubf_core::Goal>,
) -> Option<(crate::mcap_log::McapLog, PathBuf)> {
    let path = csv.with_extension("mcap");
    if path.exists() {
        tracing::warn!("{} exists; this session has only its CSV log", path.display());
        return None;
    }
    let opened = McapLog::create_for_drive::<DriveReport>(&path, &run_message(model, pose, goal));
    match opened {
        Ok(log) => Some((log, path)),
        Err(e) => {
            tracing::warn!("{e}; this session has only its CSV log");
            None
        }
    }
}

/// What a drive session is, as its logs and live view say it: the robot
/// model, where it starts and its goal.
pub(super) fn run_message(model: &RobotModel, pose: Pose2, goal: Option<ubf_core::Goal>) -> RunMessage {
    RunMessage {
        scenario: format!("drive ({})", model.name),
        seed: 0,
        start: [pose.x, pose.y, pose.theta],
        outline: model.footprint.corners().map(|(x, y)| {
            let (wx, wy) = pose.transform_point(x, y);
            [wx, wy]
        }),
        goal: goal.map(|g| [g.x, g.y, g.tolerance]),
    }
}
