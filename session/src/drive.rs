//! `ubf drive ROBOT.ron`: the behaviour tree on a real robot (or anything
//! speaking its protocol), stopped safely.

use crate::ros2_log::{LogFormat, Ros2Log};
use crate::ros2_view::Shown;
use crate::trajectory::{Columns, TrajectoryWriter};
use serde::Deserialize;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use ubf_core::config::{positive, RonError};
use ubf_core::{
    BackgroundSink, BehaviorSpec, BuildContext, Controller, ControllerError, Ends, Goal, Limits, OnBehaviorPanic,
    Pose2, ProgressCheck, Registry, Robot, RobotError, SafetyGuard, SafetyPolicy, Session, SessionEnd, State,
    TickRecord, TickSink, TracingSink, TreeLayout, WallClock,
};
use ubf_perception::egomotion::{EgomotionConfig, Tracker};
use ubf_perception::features::FeatureConfig;
use ubf_perception::source::{CameraSource, ImageDirectory, SourceError};
use ubf_perception::StereoCamera;
use ubf_robots::arcos::client::{Accelerations, ArcosRobot, ConnectOptions, EmergencyStop};
use ubf_robots::arcos::link;
use ubf_robots::camera::CameraRobot;
use ubf_robots::egomotion::EgomotionRobot;
use ubf_robots::model::RobotModel;
use ubf_robots::ptu::{Ptu, PtuConfig};
use ubf_robots::ros2::{Ros2Config, Ros2Robot};

/// Which robot model a configuration names.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub enum ModelChoice {
    /// The MobileRobots Powerbot.
    Powerbot,
    /// The Pioneer 3-DX.
    P3dx,
    /// A model file (`robots/models/*.ron` shows the format), relative to the
    /// configuration file.
    File(String),
}

/// What to do when the robot stops answering.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum OnLinkLoss {
    /// Stop commanding and try to connect again, until stopped.
    #[default]
    Reconnect,
    /// Stop and exit with an error.
    Exit,
}

/// Where a robot's stereo pairs come from.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub enum CameraSourceChoice {
    /// A directory of recorded pairs (`frames.csv`, as `ubf frames` writes),
    /// relative to the configuration file, replayed at its own pace: for
    /// trying the whole chain before the cameras are fitted.
    Directory(String),
    /// Two Video4Linux cameras giving rectified images (builds with the
    /// `v4l` feature only).
    V4l {
        /// The left camera's device, e.g. `/dev/video0`.
        left: String,
        /// The right camera's device.
        right: String,
    },
}

/// Opens the source a configuration names; `true` if it is a recording to
/// be replayed at its own pace.
fn open_source(camera: &DriveCamera) -> Result<(Box<dyn CameraSource + Send>, bool), CameraError> {
    let (raw, paced): (Box<dyn CameraSource + Send>, bool) = match &camera.source {
        CameraSourceChoice::Directory(dir) => (Box::new(ImageDirectory::open(Path::new(dir))?), true),
        CameraSourceChoice::V4l { left, right } => (open_v4l(left, right, &camera.stereo)?, false),
    };
    match &camera.rectify {
        None => Ok((raw, paced)),
        Some(files) => {
            let rectifier = files.load()?;
            Ok((Box::new(ubf_perception::rectify::Rectified::new(raw, rectifier)), paced))
        }
    }
}

/// Why the robot's camera could not be used.
#[derive(Debug, thiserror::Error)]
pub enum CameraError {
    /// The recording or the device could not be opened.
    #[error(transparent)]
    Source(#[from] SourceError),
    /// The rectification files are not a usable calibration.
    #[error(transparent)]
    Rectify(#[from] RectifyFilesError),
    /// The file names Video4Linux cameras and this build cannot read them.
    #[error(
        "this build cannot read Video4Linux cameras: build with `cargo build --release --features v4l` \
         (scripts/install-v4l-deps.sh installs what that needs)"
    )]
    NoV4l,
    /// The camera's thread could not be started.
    #[error(transparent)]
    Start(RobotError),
    /// The pan-tilt head could not be reached or set up.
    #[error(transparent)]
    PanTilt(RobotError),
}

/// Why `ubf drive` (or its dry run) ended in failure. A robot that was
/// reached has been stopped and its session closed before this is
/// reported.
#[derive(Debug, thiserror::Error)]
pub enum DriveError {
    /// The camera could not be used (checked before the motors go on).
    #[error("camera: {0}")]
    Camera(#[from] CameraError),
    /// The robot could not be reached or did not complete the handshake.
    #[error("{connection}: {source}")]
    Connect {
        /// The serial device or address tried.
        connection: String,
        /// What went wrong.
        source: RobotError,
    },
    /// The session's log could not be created.
    #[error("{}: {source}", path.display())]
    Log {
        /// The log asked for.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// Publishing on ROS 2 could not start.
    #[error("{0}")]
    Ros2(String),
    /// A log writer's thread could not be started.
    #[error("starting the log writer: {0}")]
    LogWriter(std::io::Error),
    /// The robot failed while driving (the dry run: while watching).
    #[error(transparent)]
    Robot(#[from] RobotError),
    /// The tree failed: a behaviour panicked with `on_behavior_panic: Stop`,
    /// or a sink failed.
    #[error(transparent)]
    Controller(ControllerError),
    /// A bug: the session panicked outside the behaviours.
    #[error("internal error: {0}")]
    Panic(String),
    /// The dry run needs a robot whose motors can stay off while it is
    /// watched; a ROS 2 robot's driver owns its motors.
    #[error(
        "--dry-run watches an ARCOS robot with its motors off; a ROS 2 robot's motors belong to its driver: use \
         `ros2 topic echo /odom` to watch it"
    )]
    NoDryRun,
    /// The dry run's report could not be written.
    #[error("writing: {0}")]
    Output(std::io::Error),
}

/// A calibrated, unrectified pair's calibration files, relative to the
/// configuration file: either the two cameras' ROS `camera_info` files
/// (`left`, `right`), or OpenCV's `stereoCalibrate` result (`stereo`).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RectifyFiles {
    /// The left camera's `camera_info`.
    #[serde(default)]
    pub left: Option<String>,
    /// The right camera's `camera_info`.
    #[serde(default)]
    pub right: Option<String>,
    /// `K1`, `D1`, `K2`, `D2`, `R`, `T` as OpenCV's `FileStorage` writes
    /// them; the rectification is computed as OpenCV's `stereoRectify`
    /// does.
    #[serde(default)]
    pub stereo: Option<String>,
}

impl RectifyFiles {
    fn load(&self) -> Result<ubf_perception::rectify::Rectifier, RectifyFilesError> {
        match (&self.left, &self.right, &self.stereo) {
            (Some(left), Some(right), None) => {
                Ok(ubf_perception::rectify::load_pair(Path::new(left), Path::new(right))?)
            }
            (None, None, Some(stereo)) => Ok(ubf_perception::rectify::load_stereo(Path::new(stereo))?),
            _ => Err(RectifyFilesError::Choice),
        }
    }
}

/// Why a robot file's rectification files could not be used.
#[derive(Debug, thiserror::Error)]
pub enum RectifyFilesError {
    /// Neither or both kinds of calibration were given.
    #[error(
        "give either `left` and `right` (camera_info files) or `stereo` (an OpenCV stereo calibration), not both \
         or neither"
    )]
    Choice,
    /// The files were given but are not a usable calibration.
    #[error(transparent)]
    Calibration(#[from] ubf_perception::rectify::CalibrationError),
}

#[cfg(feature = "v4l")]
fn open_v4l(left: &str, right: &str, stereo: &StereoCamera) -> Result<Box<dyn CameraSource + Send>, CameraError> {
    let pair = ubf_perception::v4l_source::V4lStereo::open(
        Path::new(left),
        Path::new(right),
        stereo.width_px,
        stereo.height_px,
    )?;
    Ok(Box::new(pair))
}

#[cfg(not(feature = "v4l"))]
fn open_v4l(_: &str, _: &str, _: &StereoCamera) -> Result<Box<dyn CameraSource + Send>, CameraError> {
    Err(CameraError::NoV4l)
}

/// The robot's stereo camera.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveCamera {
    /// Where pairs come from.
    pub source: CameraSourceChoice,
    /// The pair's calibration: focal length, image size (the principal
    /// point is its centre), baseline and mounting.
    #[serde(default, deserialize_with = "ubf_core::config::checked")]
    pub stereo: StereoCamera,
    /// The feature pipeline's settings.
    #[serde(default, deserialize_with = "ubf_core::config::checked")]
    pub features: FeatureConfig,
    /// The pair is calibrated but not rectified: rectify each pair by these
    /// `camera_info` files, whose projections then give the calibration
    /// (`stereo` keeps only its `mount`).
    #[serde(default)]
    pub rectify: Option<RectifyFiles>,
    /// The pan-tilt head the pair rides on (a FLIR PTU), for trees that
    /// steer the camera (`ActionAiding(steer: Camera)`).
    #[serde(default)]
    pub pan_tilt: Option<PtuConfig>,
}

/// A robot configuration file: `RobotConfig(...)`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "RobotConfig")]
pub struct DriveConfig {
    /// A name for logs.
    pub name: String,
    /// A serial device (`/dev/ttyUSB0`) or `tcp://host:port` for an ARCOS
    /// robot, or `ros2` for a ROS 2 robot (`/cmd_vel` in, `/odom` out).
    pub connection: String,
    /// Serial baud rate (ARCOS starts at 9600).
    #[serde(default = "DriveConfig::default_baud")]
    pub baud: u32,
    /// The robot model.
    pub model: ModelChoice,
    /// Seconds between control ticks (ARCOS sends a SIP every 0.1 s).
    #[serde(default = "DriveConfig::default_period", deserialize_with = "positive")]
    pub period_s: f64,
    /// Where the tick log goes, relative to the working directory.
    #[serde(default = "DriveConfig::default_log")]
    pub log: PathBuf,
    /// `Ros2` also logs the session as a rosbag2 directory beside the CSV
    /// log (`NAME-rosbag2/`), for `ros2 bag` and the rosbags library.
    #[serde(default)]
    pub log_format: LogFormat,
    /// Whether the session's MCAP log holds the camera's stereo pairs
    /// (PNG, about 0.2 MB a 640 × 480 pair).
    #[serde(default)]
    pub log_images: bool,
    /// What to do when the robot stops answering.
    #[serde(default)]
    pub on_link_loss: OnLinkLoss,
    /// A goal in odometry coordinates, for trees that use one.
    #[serde(default)]
    pub goal: Option<Goal>,
    /// A stereo camera, for trees that use landmarks (action aiding).
    #[serde(default)]
    pub camera: Option<DriveCamera>,
    /// Visual egomotion on the camera's frames.
    #[serde(default)]
    pub egomotion: Option<EgomotionConfig>,
    /// Accelerations to set on the controller (unset: its own).
    #[serde(default)]
    pub accelerations: Option<Accelerations>,
    /// A cap on translational speed, m/s, below the model's (sent as SETV
    /// on connect and applied to every command).
    #[serde(default, deserialize_with = "ubf_core::config::optional_positive")]
    pub max_velocity: Option<f64>,
    /// A cap on rotational speed, °/s, below the model's (sent as SETRV).
    #[serde(default, deserialize_with = "ubf_core::config::optional_positive")]
    pub max_rot_velocity_deg: Option<f64>,
    /// When to hold the robot still whatever the tree wants: stale data,
    /// a lost link, a stall or a bumper.
    #[serde(default)]
    pub safety: SafetyPolicy,
    /// What a panicking behaviour does: `Stop` ends the drive (the robot
    /// is stopped and the session closed), `SkipBehavior` carries on
    /// without it.
    #[serde(default)]
    pub on_behavior_panic: OnBehaviorPanic,
    /// Longest wait on the way out for the robot to report standstill after
    /// STOP, before its motors are switched off, s.
    #[serde(default = "DriveConfig::default_stop_wait", deserialize_with = "positive")]
    pub stop_wait_s: f64,
    /// Stop by itself after this long, s (unset: run until stopped).
    #[serde(default)]
    pub max_time_s: Option<f64>,
    /// End the drive (robot stopped, session closed) once the robot
    /// believes it is at the goal; `ubf drive --until-goal` sets it.
    #[serde(default)]
    pub until_goal: bool,
    /// Publish the drive on ROS 2 (`/tf`, `/odom`, `/scan`, `/ubf/tick`,
    /// `/ubf/goal`); `ubf drive --ros2` sets it. A ROS 2 robot always
    /// publishes the tree's topics, and leaves the robot's to its driver.
    #[serde(default)]
    pub publish_ros2: bool,
    /// Give up (robot stopped, session closed, exit code 1) once the robot,
    /// by its own pose, has stayed within `radius_m` of one spot for
    /// `window_s`: pressed against a wall its goal lies behind, say.
    /// Unset, only the goal, the time limit or the operator ends a drive.
    #[serde(default)]
    pub progress: Option<ProgressCheck>,
    /// A ROS 2 robot's topics, namespace, domain and QoS, with
    /// `connection: "ros2"` (unset: ROS 2's conventions).
    #[serde(default)]
    pub ros2: Option<Ros2Config>,
    /// The behaviour tree.
    pub root: BehaviorSpec,
}

/// The `connection` that names a ROS 2 robot.
pub const ROS2_CONNECTION: &str = "ros2";

impl DriveConfig {
    fn default_baud() -> u32 {
        9600
    }
    fn default_period() -> f64 {
        0.1
    }
    fn default_log() -> PathBuf {
        PathBuf::from("drive-log.csv")
    }
    fn default_stop_wait() -> f64 {
        1.0
    }

    /// Opens the camera and its pan-tilt head, if there are: before
    /// connecting, so that a camera that fails never leaves the motors on.
    fn open_camera(&self) -> Result<Option<OpenCamera>, CameraError> {
        let Some(camera) = &self.camera else { return Ok(None) };
        let (source, paced) = open_source(camera)?;
        let pan_tilt = camera.pan_tilt.clone().map(Ptu::connect).transpose().map_err(CameraError::PanTilt)?;
        Ok(Some(OpenCamera { source, paced, pan_tilt }))
    }

    /// `robot` with the opened camera and the egomotion tracker (starting
    /// at `origin`) around it.
    fn equip<R: Robot>(
        &self,
        robot: R,
        camera: Option<OpenCamera>,
        origin: Pose2,
    ) -> Result<EgomotionRobot<CameraRobot<R>>, CameraError> {
        let (Some(open), Some(camera)) = (camera, &self.camera) else {
            return Ok(EgomotionRobot::new(CameraRobot::without_camera(robot), None));
        };
        let mut robot = CameraRobot::new(robot, open.source, camera.stereo, camera.features, open.paced)
            .map_err(CameraError::Start)?;
        if let Some(unit) = open.pan_tilt {
            robot = robot.with_pan_tilt(Box::new(unit));
        }
        let tracker = self.egomotion.map(|config| Tracker::new(config, camera.stereo, origin, 0));
        Ok(EgomotionRobot::new(robot, tracker))
    }

    /// The robot's speed limits: the model's, under the file's caps.
    fn limits(&self, model: &RobotModel) -> Limits {
        let max_velocity = self.max_velocity.map_or(model.max_velocity, |cap| cap.min(model.max_velocity));
        let max_rot_deg =
            self.max_rot_velocity_deg.map_or(model.max_rot_velocity_deg, |cap| cap.min(model.max_rot_velocity_deg));
        Limits::new(max_velocity, max_rot_deg.to_radians())
    }

    /// How to open a session, motors on or not, with the world frame's
    /// origin at `origin`.
    fn connect_options(&self, enable_motors: bool, origin: Pose2) -> ConnectOptions {
        ConnectOptions {
            enable_motors,
            max_velocity: self.max_velocity,
            max_rot_velocity_deg: self.max_rot_velocity_deg,
            accelerations: self.accelerations,
            origin,
            standstill_wait: Duration::from_secs_f64(self.stop_wait_s.min(10.0)),
        }
    }

    /// Builds what can be built without the robot (the tree, the egomotion
    /// tables for the camera) before connecting, so that nothing after
    /// ENABLE is built for the first time.
    pub fn validate(&self) {
        if let (Some(config), Some(camera)) = (self.egomotion, &self.camera) {
            let _ = Tracker::new(config, camera.stereo, Pose2::default(), 0);
        }
        let _ = self.root.build(&BuildContext::new(0));
    }

    /// Reads a configuration file. Paths in it (a model file, a camera's
    /// image directory) become relative to the file's directory.
    pub fn load(registry: &Registry, path: &Path) -> Result<(DriveConfig, RobotModel), RobotFileError> {
        let read =
            |path: &Path| std::fs::read(path).map_err(|source| RobotFileError::Read { path: path.into(), source });
        let parse = RobotFileError::parse;
        let text = ubf_core::config::utf8_text(read(path)?).map_err(parse(path))?;
        let mut config: DriveConfig = registry.from_ron(&text).map_err(parse(path))?;
        if config.ros2.is_some() && config.connection != ROS2_CONNECTION {
            return Err(RobotFileError::Ros2WithoutRos2 { path: path.into() });
        }
        if config.egomotion.is_some() && config.camera.is_none() {
            return Err(RobotFileError::EgomotionWithoutCamera { path: path.into() });
        }
        let beside = |file: &str| path.parent().unwrap_or(Path::new(".")).join(file).to_string_lossy().into_owned();
        if let Some(camera) = &mut config.camera {
            if let CameraSourceChoice::Directory(dir) = &mut camera.source {
                *dir = beside(dir);
            }
            if let Some(files) = &mut camera.rectify {
                for file in [&mut files.left, &mut files.right, &mut files.stereo].into_iter().flatten() {
                    *file = beside(file);
                }
                let rectified = files.load().map_err(|source| RobotFileError::Rectify { path: path.into(), source })?;
                camera.stereo = StereoCamera { mount: camera.stereo.mount, ..rectified.camera() };
            }
        }
        let model = match &config.model {
            ModelChoice::Powerbot => RobotModel::powerbot(),
            ModelChoice::P3dx => RobotModel::p3dx(),
            ModelChoice::File(file) => {
                let model_path = path.parent().unwrap_or(Path::new(".")).join(file);
                let text = ubf_core::config::utf8_text(read(&model_path)?).map_err(parse(&model_path))?;
                RobotModel::from_ron(&text).map_err(parse(&model_path))?
            }
        };
        config.validate();
        Ok((config, model))
    }
}

/// Why a robot file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum RobotFileError {
    /// The file, or the model file it names, could not be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file, or its model file, is not what it should be; the error
    /// says where (line, column, field).
    #[error("{}:{source}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// Where and why.
        source: RonError,
    },
    /// ROS 2 settings were given for a robot that is not a ROS 2 one.
    #[error("{}: `ros2: (...)` is for `connection: \"ros2\"`; remove it or change the connection", path.display())]
    Ros2WithoutRos2 {
        /// The file.
        path: PathBuf,
    },
    /// Egomotion was asked for without a camera.
    #[error("{}: egomotion needs a camera: add `camera: (...)`", path.display())]
    EgomotionWithoutCamera {
        /// The file.
        path: PathBuf,
    },
    /// The rectification files it names could not be used.
    #[error("{}: camera.rectify: {source}", path.display())]
    Rectify {
        /// The robot file.
        path: PathBuf,
        /// What was wrong with them.
        source: RectifyFilesError,
    },
}

impl RobotFileError {
    /// A parse error in `path`.
    fn parse(path: &Path) -> impl FnOnce(RonError) -> RobotFileError + '_ {
        move |source| RobotFileError::Parse { path: path.into(), source }
    }
}

/// What a second Ctrl-C or SIGTERM runs before the process exits: the
/// robot's emergency stop, while a session is open.
static ON_SECOND_INTERRUPT: Mutex<Option<EmergencyStop>> = Mutex::new(None);

/// Set by Ctrl-C or SIGTERM. A second one does not wait for the orderly
/// stop: it sends STOP, ENABLE 0 and CLOSE on the open session, if any, and
/// exits with status 130.
pub fn install_stop_flag() -> Arc<AtomicBool> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    // A second handler cannot be installed; then only the time limit stops.
    let _ = ctrlc::set_handler(move || {
        if !flag.swap(true, Ordering::SeqCst) {
            return;
        }
        if let Ok(guard) = ON_SECOND_INTERRUPT.try_lock() {
            if let Some(emergency) = guard.as_ref() {
                let _ = emergency.stop_now();
            }
        }
        eprintln!("interrupted twice: robot sent STOP, ENABLE 0, CLOSE; exiting now");
        std::process::exit(130);
    });
    stop
}

/// Registers (or clears) what a second interrupt stops.
fn arm_second_interrupt(emergency: Option<EmergencyStop>) {
    *ON_SECOND_INTERRUPT.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = emergency;
}

/// A camera opened before its session.
struct OpenCamera {
    source: Box<dyn CameraSource + Send>,
    paced: bool,
    pan_tilt: Option<Ptu>,
}

/// How a drive ended.
#[derive(Debug, PartialEq, Eq)]
pub enum DriveEnd {
    /// Ctrl-C, SIGTERM or the time limit.
    Stopped,
    /// At the goal, with `until_goal`.
    GoalReached,
    /// The link was lost and the configuration says exit.
    LinkLost,
    /// The robot got nowhere for the `progress` check's window.
    NoProgress,
}

/// What a drive leaves: how it ended and the logs it wrote, one per
/// session, in order.
#[derive(Debug)]
pub struct DriveOutcome {
    /// How it ended, or why it failed.
    pub end: Result<DriveEnd, DriveError>,
    /// The sessions' logs.
    pub logs: Vec<PathBuf>,
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

/// How `ubf drive` shows its live state on stderr.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Not at all (stderr is not a terminal and nobody asked).
    Off,
    /// One line, rewritten twice a second (a terminal).
    Line,
    /// A line a second (asked for, stderr not a terminal).
    Lines,
}

impl Status {
    /// How often the state is shown.
    fn every(self) -> Duration {
        match self {
            Status::Line => Duration::from_millis(500),
            Status::Off | Status::Lines => Duration::from_secs(1),
        }
    }
}

/// Shows the live state on stderr as the ticks go by: link, pose, speeds,
/// winning behaviour, hold.
struct StatusLine {
    status: Status,
    layout: TreeLayout,
    shown: Instant,
}

impl StatusLine {
    fn new(status: Status) -> Self {
        StatusLine { status, layout: TreeLayout::default(), shown: Instant::now() }
    }

    fn line(&self, record: &TickRecord) -> String {
        let state = &record.state;
        let layout = &self.layout;
        let winner = layout.winning_leaf(record).map_or("-", |i| layout.nodes[i].path.as_str());
        let hold = match record.hold {
            Some(ubf_core::Hold::StaleData) => "stale data",
            Some(ubf_core::Hold::Contact) => "contact",
            None => "-",
        };
        format!(
            "t {:.1} s | SIP {:.2} s old | pose ({:.2}, {:.2}) m {:.0}° | {:.2} m/s {:.0}°/s | winner {winner} | hold \
             {hold}",
            state.time,
            state.sensor_age,
            state.pose.x,
            state.pose.y,
            state.pose.theta.to_degrees(),
            state.velocity,
            state.rot_velocity.to_degrees()
        )
    }
}

impl TickSink for StatusLine {
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.layout = layout.clone();
        Ok(())
    }

    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        if self.shown.elapsed() >= self.status.every() {
            self.shown = Instant::now();
            match self.status {
                Status::Line => eprint!("\r{}\x1b[K", self.line(record)),
                Status::Lines | Status::Off => eprintln!("{}", self.line(record)),
            }
        }
        Ok(())
    }

    fn finish(&mut self) -> std::io::Result<()> {
        if self.status == Status::Line {
            eprintln!();
        }
        Ok(())
    }
}

/// Runs the tree against the robot until `stop` is set (or the time limit),
/// reconnecting after a lost link if configured, with the world frame (and
/// so the goal) carried over from the last pose. Every tick goes to the
/// session's log; on the way out the robot gets STOP, ENABLE 0 and CLOSE and
/// the log is flushed, whatever ended the session (a panic included).
pub fn drive(config: &DriveConfig, model: &RobotModel, stop: &AtomicBool, status: Status) -> DriveOutcome {
    let mut logs = Vec::new();
    let end = drive_sessions(config, model, stop, status, &mut logs);
    DriveOutcome { end, logs }
}

fn drive_sessions(
    config: &DriveConfig,
    model: &RobotModel,
    stop: &AtomicBool,
    status: Status,
    logs: &mut Vec<PathBuf>,
) -> Result<DriveEnd, DriveError> {
    let started = Instant::now();
    let out_of_time = || config.max_time_s.is_some_and(|t| started.elapsed().as_secs_f64() >= t);
    let mut pose = Pose2::default();
    loop {
        if stop.load(Ordering::SeqCst) || out_of_time() {
            return Ok(DriveEnd::Stopped);
        }
        let camera = config.open_camera()?;
        let Connected { robot, name, emergency } = match connect_driving(config, model, pose) {
            Ok(connected) => connected,
            Err(e) => {
                tracing::warn!("connecting: {e}");
                if config.on_link_loss == OnLinkLoss::Exit {
                    return Err(e);
                }
                std::thread::sleep(Duration::from_secs(1));
                continue;
            }
        };
        eprintln!("connected to {name}");
        arm_second_interrupt(emergency);
        // From here the motors are on: every path out goes through shutdown
        // (a robot dropped on the way out shuts itself down).
        let robot = match config.equip(robot, camera, pose) {
            Ok(robot) => SafetyGuard::new(robot, config.safety),
            Err(e) => {
                arm_second_interrupt(None);
                return Err(e.into());
            }
        };
        let root = config.root.build(&BuildContext::new(0));
        let mut controller = Controller::new(robot, root, Box::new(WallClock::new(config.period_s)));
        controller.set_goal(config.goal);
        controller.set_on_behavior_panic(config.on_behavior_panic);
        controller.add_sink(Box::new(TracingSink));
        if status != Status::Off {
            controller.add_sink(Box::new(StatusLine::new(status)));
        }
        let attached =
            attach_logs(&mut controller, config, model, logs).and_then(|()| attach_ros2(&mut controller, config));
        let ends = Ends {
            at_goal: config.until_goal,
            progress: config.progress,
            max_ticks: None,
            max_time_s: config.max_time_s.map(|limit| limit - started.elapsed().as_secs_f64()),
        };
        let mut session = Session::new(controller, ends);
        let ended = match &attached {
            Ok(()) => session.run(stop, |_| ControlFlow::Continue(())),
            Err(_) => SessionEnd::Done,
        };
        // Whatever happened: stop the robot, close the session and flush
        // the logs.
        let (controller, shutdown) = session.finish();
        pose = controller.state().pose;
        if let Err(e) = shutdown {
            tracing::warn!("shutting down: {e}");
        }
        arm_second_interrupt(None);
        attached?;
        match ended {
            SessionEnd::Interrupted | SessionEnd::TimeLimit | SessionEnd::Done => return Ok(DriveEnd::Stopped),
            SessionEnd::GoalReached => return Ok(DriveEnd::GoalReached),
            SessionEnd::NoProgress => return Ok(DriveEnd::NoProgress),
            SessionEnd::Panicked(why) => return Err(DriveError::Panic(why)),
            SessionEnd::Failed(ControllerError::Robot(why)) => {
                eprintln!("link lost: {why}");
                if config.on_link_loss == OnLinkLoss::Exit {
                    return Ok(DriveEnd::LinkLost);
                }
                std::thread::sleep(Duration::from_secs(1));
            }
            SessionEnd::Failed(why) => return Err(DriveError::Controller(why)),
        }
    }
}

/// Attaches the session's logs, each written on a thread of its own (a
/// slow disk must not delay a tick, and a failed log must not stop the
/// robot), and adds their paths to `logs`. The CSV log is the one a session
/// cannot do without; the MCAP log beside it is left out, with a warning, if
/// it cannot be made.
fn attach_logs<R: Robot>(
    controller: &mut Controller<R>,
    config: &DriveConfig,
    model: &RobotModel,
    logs: &mut Vec<PathBuf>,
) -> Result<(), DriveError> {
    let (file, path) =
        create_fresh_log(&config.log).map_err(|source| DriveError::Log { path: config.log.clone(), source })?;
    eprintln!("logging to {}", path.display());
    logs.push(path.clone());
    let csv = TrajectoryWriter::new(file, &path, Columns { truth: false, hold: true, camera_pan: false });
    let sink = BackgroundSink::spawn("CSV log", csv, LOG_QUEUE).map_err(DriveError::LogWriter)?;
    controller.add_sink(Box::new(sink));
    let Some((mut mcap, mcap_path)) = open_session_mcap(&path, model, controller.state().pose, config.goal) else {
        return Ok(());
    };
    mcap.log_images(config.log_images);
    match BackgroundSink::spawn("MCAP log", mcap, LOG_QUEUE) {
        Ok(sink) => {
            eprintln!("and to {}", mcap_path.display());
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
    let opened = Ros2Log::create(&dir, Shown { robot: true, images: config.log_images }, epoch_s)
        .map_err(|e| e.to_string())
        .and_then(|bag| BackgroundSink::spawn("rosbag2 log", bag, LOG_QUEUE).map_err(|e| e.to_string()));
    match opened {
        Ok(sink) => {
            eprintln!("and to {}", dir.display());
            logs.push(dir);
            controller.add_sink(Box::new(sink));
        }
        Err(e) => tracing::warn!("{e}; this session has no rosbag2 log"),
    }
}

/// Publishes the session on ROS 2 where asked, and always for a ROS 2
/// robot: its tree and goal, and for another robot its pose and sensors
/// too (a ROS 2 robot's driver publishes those).
fn attach_ros2<R: Robot>(controller: &mut Controller<R>, config: &DriveConfig) -> Result<(), DriveError> {
    let ros2_robot = config.connection == ROS2_CONNECTION;
    if !(config.publish_ros2 || ros2_robot) {
        return Ok(());
    }
    let (domain, namespace) = config.ros2.as_ref().map_or((None, ""), |r| (r.domain_id, r.namespace.as_str()));
    let shown = Shown { robot: !ros2_robot, images: config.log_images };
    let publisher = crate::ros2_publish::background_publisher(shown, domain, namespace)
        .map_err(|e| DriveError::Ros2(e.to_string()))?;
    controller.add_sink(Box::new(publisher));
    Ok(())
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
    let run = crate::mcap_log::RunMessage {
        scenario: format!("drive ({})", model.name),
        seed: 0,
        start: [pose.x, pose.y, pose.theta],
        outline: model.footprint.corners().map(|(x, y)| {
            let (wx, wy) = pose.transform_point(x, y);
            [wx, wy]
        }),
        goal: goal.map(|g| [g.x, g.y, g.tolerance]),
    };
    let opened = crate::mcap_log::McapLog::create(&path, &run, &crate::mcap_log::WorldMessage::default());
    match opened {
        Ok(log) => Some((log, path)),
        Err(e) => {
            tracing::warn!("{e}; this session has only its CSV log");
            None
        }
    }
}

/// How far, ° (left), and for how long, s, the dry run turns a pan-tilt
/// head before aiming it ahead: long enough to watch which way it went.
const PAN_CHECK_DEG: f64 = 20.0;
const PAN_CHECK_S: f64 = 3.0;

/// `--dry-run`: connect without enabling the motors, print who the robot is
/// and its configuration, then its odometry and nearest sonar echo once a
/// second until stopped; a pan-tilt head is turned left and back, its
/// commanded and measured angles shown. Output that cannot be written (a closed pipe) ends
/// the run like Ctrl-C: the session is closed either way.
pub fn dry_run(config: &DriveConfig, model: &RobotModel, stop: &AtomicBool) -> Result<(), DriveError> {
    if config.connection == ROS2_CONNECTION {
        return Err(DriveError::NoDryRun);
    }
    let camera = config.open_camera()?;
    let robot = connect(config, model, false, Pose2::default())?;
    let mut robot = config.equip(robot, camera, Pose2::default())?;
    let result = show_robot(&mut robot, config, model, stop, &mut std::io::stdout().lock());
    let closed = robot.shutdown().map_err(DriveError::Robot);
    match result {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => closed,
        Err(e) => Err(DriveError::Output(e)),
        Ok(Err(e)) => Err(e.into()),
        Ok(Ok(())) => closed,
    }
}

/// A robot reached for a session, motors on.
struct Connected {
    robot: Box<dyn Robot>,
    /// Who answered, for the operator.
    name: String,
    /// What a second interrupt runs, where the robot has one.
    emergency: Option<EmergencyStop>,
}

/// Reaches the robot the configuration names, ready to drive, with its
/// pose reading `pose`: a ROS 2 robot (`connection: "ros2"`), or an ARCOS
/// controller with its motors enabled.
fn connect_driving(config: &DriveConfig, model: &RobotModel, pose: Pose2) -> Result<Connected, DriveError> {
    if config.connection == ROS2_CONNECTION {
        let limits = config.limits(model);
        let ros2 = config.ros2.clone().unwrap_or_default();
        let robot = Ros2Robot::connect(&ros2, limits, config.period_s, pose)
            .map_err(|source| DriveError::Connect { connection: config.connection.clone(), source })?;
        let name = format!("a ROS 2 robot in domain {} ({})", robot.domain(), model.name);
        return Ok(Connected { robot: Box::new(robot), name, emergency: None });
    }
    let robot = connect(config, model, true, pose)?;
    let id = robot.identity();
    let name = format!("{} ({} {})", id.name, id.class, id.subclass);
    let emergency = robot.emergency_stop().ok();
    Ok(Connected { robot: Box::new(robot), name, emergency })
}

/// Opens the link and completes the handshake, motors on or off, with
/// odometry starting at `pose`.
fn connect(config: &DriveConfig, model: &RobotModel, motors: bool, pose: Pose2) -> Result<ArcosRobot, DriveError> {
    link::open(&config.connection, config.baud)
        .map_err(RobotError::from)
        .and_then(|link| ArcosRobot::connect(link, model.clone(), &config.connect_options(motors, pose)))
        .map_err(|source| DriveError::Connect { connection: config.connection.clone(), source })
}

/// The dry run's report: I/O errors are the output's, the inner ones the
/// robot's.
fn show_robot(
    robot: &mut EgomotionRobot<CameraRobot<ArcosRobot>>,
    config: &DriveConfig,
    model: &RobotModel,
    stop: &AtomicBool,
    out: &mut impl std::io::Write,
) -> std::io::Result<Result<(), RobotError>> {
    let arcos = robot.inner().inner();
    let id = arcos.identity().clone();
    writeln!(out, "robot           {} ({} {})", id.name, id.class, id.subclass)?;
    writeln!(
        out,
        "model           {}: max {:.2} m/s, {:.0}°/s, {} sonars",
        model.name,
        model.max_velocity,
        model.max_rot_velocity_deg,
        model.sonar.len()
    )?;
    match arcos.config() {
        Some(c) => {
            writeln!(
                out,
                "controller      {} {}, serial {}, name {}",
                c.robot_type, c.subtype, c.serial_number, c.name
            )?;
            writeln!(
                out,
                "tops            {} mm/s, {}°/s, {} mm/s², {}°/s²; SIP every {} ms; host baud code {}",
                c.trans_vel_top, c.rot_vel_top, c.trans_acc_top, c.rot_acc_top, c.sip_cycle_ms, c.host_baud
            )?;
        }
        None => writeln!(out, "controller      sent no CONFIG reply")?,
    }
    let limits = robot.limits();
    writeln!(out, "limits in use   {:.2} m/s, {:.0}°/s", limits.max_velocity, limits.max_rot_velocity.to_degrees())?;
    writeln!(out, "motors          left disabled (dry run)")?;
    let pan_tilt = config.camera.as_ref().and_then(|c| c.pan_tilt.as_ref());
    if let Some(unit) = pan_tilt {
        writeln!(
            out,
            "pan-tilt        on {}: turning {PAN_CHECK_DEG}° left for {PAN_CHECK_S} s, then ahead (a head that turns \
             right first needs `invert_pan: true`)",
            unit.connection
        )?;
    }
    let mut state = State::default();
    let started = Instant::now();
    let mut last_shown = Instant::now();
    while !stop.load(Ordering::SeqCst) && config.max_time_s.is_none_or(|t| started.elapsed().as_secs_f64() < t) {
        // Wake often enough to PULSE within the 500 ms; show once a second.
        std::thread::sleep(Duration::from_millis(250));
        let pan = if started.elapsed().as_secs_f64() < PAN_CHECK_S { PAN_CHECK_DEG.to_radians() } else { 0.0 };
        let aimed = if pan_tilt.is_some() { robot.aim_camera(pan) } else { Ok(()) };
        if let Err(e) =
            aimed.and_then(|()| robot.inner_mut().inner_mut().keep_alive()).and_then(|_| robot.sense(&mut state))
        {
            return Ok(Err(e));
        }
        if last_shown.elapsed() < Duration::from_secs(1) {
            continue;
        }
        last_shown = Instant::now();
        let nearest = state.nearest_range().map_or("none".into(), |r| format!("{r:.2} m"));
        writeln!(
            out,
            "odometry        ({:.3}, {:.3}) m, {:.1}°; nearest sonar echo {nearest}; battery {:.1} V",
            state.pose.x,
            state.pose.y,
            state.pose.theta.to_degrees(),
            state.battery_volts.unwrap_or(f64::NAN)
        )?;
        if let Some(aim) = state.camera_aim {
            writeln!(
                out,
                "pan-tilt        commanded {:.1}°, measured {:.2}° (tilt {:.2}°)",
                pan.to_degrees(),
                aim.pan.to_degrees(),
                aim.tilt.to_degrees()
            )?;
        }
        if config.camera.is_some() {
            writeln!(
                out,
                "camera          frame {}: {} landmarks; egomotion {} steps, {} failures",
                state.stereo.number,
                state.stereo.landmarks.len(),
                state.egomotion.steps,
                state.egomotion.failures
            )?;
        }
        out.flush()?;
    }
    Ok(Ok(()))
}
