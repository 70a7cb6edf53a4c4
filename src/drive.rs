//! `ubf drive ROBOT.ron`: the behaviour tree on a real robot (or anything
//! speaking its protocol), stopped safely.

use crate::trajectory::TrajectoryWriter;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use ubf_core::config::{positive, RonError};
use ubf_core::{BehaviorSpec, BuildContext, Controller, Goal, Registry, Robot, State, WallClock};
use ubf_perception::egomotion::{EgomotionConfig, Tracker};
use ubf_perception::features::FeatureConfig;
use ubf_perception::source::{CameraSource, ImageDirectory};
use ubf_perception::StereoCamera;
use ubf_robots::arcos::client::{Accelerations, ArcosRobot, ConnectOptions};
use ubf_robots::arcos::link;
use ubf_robots::camera::CameraRobot;
use ubf_robots::egomotion::EgomotionRobot;
use ubf_robots::model::RobotModel;

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
fn open_source(
    source: &CameraSourceChoice,
    stereo: &StereoCamera,
) -> Result<(Box<dyn CameraSource + Send>, bool), String> {
    match source {
        CameraSourceChoice::Directory(dir) => {
            Ok((Box::new(ImageDirectory::open(Path::new(dir)).map_err(|e| e.to_string())?), true))
        }
        CameraSourceChoice::V4l { left, right } => open_v4l(left, right, stereo).map(|s| (s, false)),
    }
}

#[cfg(feature = "v4l")]
fn open_v4l(left: &str, right: &str, stereo: &StereoCamera) -> Result<Box<dyn CameraSource + Send>, String> {
    let pair = ubf_perception::v4l_source::V4lStereo::open(
        Path::new(left),
        Path::new(right),
        stereo.width_px,
        stereo.height_px,
    )
    .map_err(|e| e.to_string())?;
    Ok(Box::new(pair))
}

#[cfg(not(feature = "v4l"))]
fn open_v4l(_: &str, _: &str, _: &StereoCamera) -> Result<Box<dyn CameraSource + Send>, String> {
    Err("this build cannot read Video4Linux cameras: build with `cargo build --release --features v4l` \
         (scripts/install-v4l-deps.sh installs what that needs)"
        .into())
}

/// The robot's stereo camera.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveCamera {
    /// Where pairs come from.
    pub source: CameraSourceChoice,
    /// The pair's calibration: focal length, image size (the principal
    /// point is its centre), baseline and mounting.
    #[serde(default)]
    pub stereo: StereoCamera,
    /// The feature pipeline's settings.
    #[serde(default)]
    pub features: FeatureConfig,
}

/// A robot configuration file: `RobotConfig(...)`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "RobotConfig")]
pub struct DriveConfig {
    /// A name for logs.
    pub name: String,
    /// A serial device (`/dev/ttyUSB0`) or `tcp://host:port`.
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
    /// Stop by itself after this long, s (unset: run until stopped).
    #[serde(default)]
    pub max_time_s: Option<f64>,
    /// The behaviour tree.
    pub root: BehaviorSpec,
}

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

    /// `robot` with the configured camera and egomotion around it.
    fn equip(&self, robot: ArcosRobot) -> Result<EgomotionRobot<CameraRobot<ArcosRobot>>, String> {
        let Some(camera) = &self.camera else {
            return Ok(EgomotionRobot::new(CameraRobot::without_camera(robot), None));
        };
        let (source, paced) = open_source(&camera.source, &camera.stereo)?;
        let robot =
            CameraRobot::new(robot, source, camera.stereo, camera.features, paced).map_err(|e| e.to_string())?;
        let tracker = self.egomotion.map(|config| Tracker::new(config, camera.stereo, ubf_core::Pose2::default(), 0));
        Ok(EgomotionRobot::new(robot, tracker))
    }

    /// How to open a session, motors on or not.
    fn connect_options(&self, enable_motors: bool) -> ConnectOptions {
        ConnectOptions { enable_motors, accelerations: self.accelerations, ..ConnectOptions::default() }
    }

    /// Reads a configuration file. Paths in it (a model file, a camera's
    /// image directory) become relative to the file's directory.
    pub fn load(registry: &Registry, path: &Path) -> Result<(DriveConfig, RobotModel), String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut config: DriveConfig =
            registry.from_ron(&text).map_err(|e: RonError| format!("{}:{e}", path.display()))?;
        if config.egomotion.is_some() && config.camera.is_none() {
            return Err(format!("{}: egomotion needs a camera: add `camera: (...)`", path.display()));
        }
        if let Some(DriveCamera { source: CameraSourceChoice::Directory(dir), .. }) = &mut config.camera {
            *dir = path.parent().unwrap_or(Path::new(".")).join(&*dir).to_string_lossy().into_owned();
        }
        let model = match &config.model {
            ModelChoice::Powerbot => RobotModel::powerbot(),
            ModelChoice::P3dx => RobotModel::p3dx(),
            ModelChoice::File(file) => {
                let model_path = path.parent().unwrap_or(Path::new(".")).join(file);
                let text =
                    std::fs::read_to_string(&model_path).map_err(|e| format!("{}: {e}", model_path.display()))?;
                RobotModel::from_ron(&text).map_err(|e| format!("{}:{e}", model_path.display()))?
            }
        };
        Ok((config, model))
    }
}

/// Set by Ctrl-C or SIGTERM.
pub fn install_stop_flag() -> Arc<AtomicBool> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    // A second handler cannot be installed; then only the time limit stops.
    let _ = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst));
    stop
}

/// How a drive ended.
#[derive(Debug, PartialEq, Eq)]
pub enum DriveEnd {
    /// Ctrl-C, SIGTERM or the time limit.
    Stopped,
    /// The link was lost and the configuration says exit.
    LinkLost,
}

/// Runs the tree against the robot until `stop` is set (or the time limit),
/// reconnecting after a lost link if configured. Every tick goes to the log;
/// on the way out the robot gets STOP, ENABLE 0 and CLOSE and the log is
/// flushed.
pub fn drive(config: &DriveConfig, model: &RobotModel, stop: &AtomicBool) -> Result<DriveEnd, String> {
    let started = Instant::now();
    let out_of_time = || config.max_time_s.is_some_and(|t| started.elapsed().as_secs_f64() >= t);
    let mut log_path = config.log.clone();
    let mut session = 0;
    loop {
        if stop.load(Ordering::SeqCst) || out_of_time() {
            return Ok(DriveEnd::Stopped);
        }
        let robot = match link::open(&config.connection, config.baud).map_err(|e| e.to_string()).and_then(|l| {
            ArcosRobot::connect(l, model.clone(), &config.connect_options(true)).map_err(|e| e.to_string())
        }) {
            Ok(robot) => robot,
            Err(e) => {
                tracing::warn!("connecting to {}: {e}", config.connection);
                if config.on_link_loss == OnLinkLoss::Exit {
                    return Err(format!("{}: {e}", config.connection));
                }
                std::thread::sleep(Duration::from_secs(1));
                continue;
            }
        };
        eprintln!("connected to {} ({} {})", robot.identity().name, robot.identity().class, robot.identity().subclass);
        session += 1;
        if session > 1 {
            log_path = config.log.with_extension(format!("{session}.csv"));
        }
        let robot = match config.equip(robot) {
            Ok(robot) => robot,
            // The session closes as the robot is dropped.
            Err(e) => return Err(format!("camera: {e}")),
        };
        let root = config.root.build(&BuildContext::new(0));
        let mut controller = Controller::new(robot, root, Box::new(WallClock::new(config.period_s)));
        controller.set_goal(config.goal);
        let mut log = TrajectoryWriter::create(&log_path, controller.layout())
            .map_err(|e| format!("{}: {e}", log_path.display()))?;
        let lost = run_session(&mut controller, &mut log, config, stop, &out_of_time);
        // Whatever happened: stop the robot, close the session, keep the log.
        if let Err(e) = controller.shutdown() {
            tracing::warn!("shutting down: {e}");
        }
        log.finish().map_err(|e| format!("{}: {e}", log_path.display()))?;
        match lost {
            None => return Ok(DriveEnd::Stopped),
            Some(why) => {
                eprintln!("link lost: {why}");
                if config.on_link_loss == OnLinkLoss::Exit {
                    return Ok(DriveEnd::LinkLost);
                }
                std::thread::sleep(Duration::from_secs(1));
            }
        }
    }
}

/// Ticks until stopped (returns `None`) or the link is lost (returns why).
fn run_session<R: Robot>(
    controller: &mut Controller<R>,
    log: &mut TrajectoryWriter,
    config: &DriveConfig,
    stop: &AtomicBool,
    out_of_time: &dyn Fn() -> bool,
) -> Option<String> {
    let stale_after = 3.0 * config.period_s;
    // The first SIP follows OPEN within a cycle or two; meanwhile the state
    // is stale and a Stop behaviour holds the robot.
    let grace = Instant::now() + Duration::from_secs(2);
    while !stop.load(Ordering::SeqCst) && !out_of_time() {
        if let Err(e) = controller.tick() {
            return Some(e.to_string());
        }
        let state: &State = controller.state();
        let (pose, age, egomotion, frame) = (state.pose, state.sensor_age, state.egomotion, state.stereo.number);
        if let Err(e) = log.write(controller.last_record(), controller.layout(), &pose, &pose, &egomotion, frame) {
            tracing::warn!("writing the log: {e}");
        }
        if age > stale_after {
            // No SIP for three cycles: never keep commanding motion blind.
            let _ = controller.robot_mut().act(&ubf_core::Command::Stop);
            if age > 10.0 * stale_after && Instant::now() > grace {
                return Some(if age.is_finite() { format!("no SIP for {age:.1} s") } else { "no SIP arrived".into() });
            }
        }
    }
    None
}

/// `--dry-run`: connect without enabling the motors, print who the robot is
/// and its configuration, then its odometry and nearest sonar echo once a
/// second until stopped. Output that cannot be written (a closed pipe) ends
/// the run like Ctrl-C: the session is closed either way.
pub fn dry_run(config: &DriveConfig, model: &RobotModel, stop: &AtomicBool) -> Result<(), String> {
    let link = link::open(&config.connection, config.baud).map_err(|e| format!("{}: {e}", config.connection))?;
    let robot = ArcosRobot::connect(link, model.clone(), &config.connect_options(false)).map_err(|e| e.to_string())?;
    let mut robot = config.equip(robot)?;
    let result = show_robot(&mut robot, config, model, stop, &mut std::io::stdout().lock());
    let closed = robot.shutdown().map_err(|e| e.to_string());
    match result {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => closed,
        Err(e) => Err(format!("writing: {e}")),
        Ok(Err(e)) => Err(e),
        Ok(Ok(())) => closed,
    }
}

/// The dry run's report: I/O errors are the output's, the inner ones the
/// robot's.
fn show_robot(
    robot: &mut EgomotionRobot<CameraRobot<ArcosRobot>>,
    config: &DriveConfig,
    model: &RobotModel,
    stop: &AtomicBool,
    out: &mut impl std::io::Write,
) -> std::io::Result<Result<(), String>> {
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
    let mut state = State::default();
    let started = Instant::now();
    let mut last_shown = Instant::now();
    while !stop.load(Ordering::SeqCst) && config.max_time_s.is_none_or(|t| started.elapsed().as_secs_f64() < t) {
        // Wake often enough to PULSE within the 500 ms; show once a second.
        std::thread::sleep(Duration::from_millis(250));
        if let Err(e) = robot.inner_mut().inner_mut().keep_alive().and_then(|_| robot.sense(&mut state)) {
            return Ok(Err(e.to_string()));
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
