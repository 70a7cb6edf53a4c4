//! The robot file, `RobotConfig(...)`: its schema, its defaults and its
//! loader, whose errors name the file, line and column.

use crate::ros2_log::LogFormat;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::time::Duration;
use ubf_core::config::RonError;
use ubf_core::{
    BehaviorSpec, BuildContext, Goal, Limits, OnBehaviorPanic, Pose2, ProgressCheck, Registry, SafetyPolicy,
};
use ubf_perception::egomotion::{EgomotionConfig, Tracker};
use ubf_perception::features::FeatureConfig;
use ubf_perception::StereoCamera;
use ubf_robots::arcos::client::{Accelerations, ConnectOptions};
use ubf_robots::model::RobotModel;
use ubf_robots::ptu::PtuConfig;
use ubf_robots::ros2::Ros2Config;
use ubf_robots::wall_compass::WallCompassConfig;

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
    pub(super) fn load(&self) -> Result<ubf_perception::rectify::Rectifier, RectifyFilesError> {
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
    #[serde(deserialize_with = "ubf_core::config::shown_name")]
    pub name: String,
    /// A serial device (`/dev/ttyUSB0`) or `tcp://host:port` for an ARCOS
    /// robot, or `ros2` for a ROS 2 robot (`/cmd_vel` in, `/odom` out).
    #[serde(deserialize_with = "connection")]
    pub connection: String,
    /// Serial baud rate (ARCOS starts at 9600).
    #[serde(default = "DriveConfig::default_baud", deserialize_with = "baud")]
    pub baud: u32,
    /// The robot model.
    pub model: ModelChoice,
    /// Seconds between control ticks (ARCOS sends a SIP every 0.1 s).
    #[serde(default = "DriveConfig::default_period", deserialize_with = "drive_period_s")]
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
    /// Megabytes at which a session's MCAP log stops taking images; at
    /// twice this it stops taking anything but its report (the CSV log, a
    /// few kilobytes a minute, goes on), so a long drive cannot fill the
    /// disk.
    #[serde(default = "DriveConfig::default_log_max_mb", deserialize_with = "log_max_mb")]
    pub log_max_mb: f64,
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
    /// Odometry's heading held by the walls the side sonars (or the
    /// scanner's beams square to the robot) run along
    /// (`ubf_robots::wall_compass`), for buildings whose long walls are
    /// square; none by default.
    #[serde(default)]
    pub wall_compass: Option<WallCompassConfig>,
    /// Accelerations to set on the controller (unset: its own).
    #[serde(default)]
    pub accelerations: Option<Accelerations>,
    /// A cap on translational speed, m/s, below the model's (sent as SETV
    /// on connect and applied to every command).
    #[serde(default, deserialize_with = "optional_speed_m_s")]
    pub max_velocity: Option<f64>,
    /// A cap on rotational speed, °/s, below the model's (sent as SETRV).
    #[serde(default, deserialize_with = "optional_rate_deg_s")]
    pub max_rot_velocity_deg: Option<f64>,
    /// When to hold the robot still whatever the tree wants: stale data,
    /// a lost link, a stall or a bumper.
    #[serde(default, deserialize_with = "ubf_core::config::checked")]
    pub safety: SafetyPolicy,
    /// What a panicking behaviour does: `Stop` ends the drive (the robot
    /// is stopped and the session closed), `SkipBehavior` carries on
    /// without it.
    #[serde(default)]
    pub on_behavior_panic: OnBehaviorPanic,
    /// Margin on the way out, beyond the time the robot needs to brake from
    /// its speed at STOP, to wait for it to report standstill before its
    /// motors are switched off, s.
    #[serde(default = "DriveConfig::default_stop_wait", deserialize_with = "stop_wait_s")]
    pub stop_wait_s: f64,
    /// Where the drive keeps the robot's pose in its world frame (once a
    /// second and at the end of each session, atomically). A drive that
    /// finds the file resumes in that frame, as after a reconnect: a
    /// service restarted after a crash keeps its goal in place. Remove the
    /// file to start a new frame where the robot stands.
    #[serde(default)]
    pub pose_file: Option<PathBuf>,
    /// Stop by itself after this long, s (unset: run until stopped).
    #[serde(default, deserialize_with = "ubf_core::config::optional_duration_s")]
    pub max_time_s: Option<f64>,
    /// End the drive (robot stopped, session closed) once the robot
    /// believes it is at the goal; `ubf drive --until-goal` sets it.
    #[serde(default)]
    pub until_goal: bool,
    /// Publish the drive on ROS 2 (`/tf`, `/odom`, `/scan`, `/ubf/tick`,
    /// `/ubf/goal`, `/ubf/pose/...`); `ubf drive --ros2` sets it. A ROS 2 robot always
    /// publishes the tree's topics, and leaves the robot's to its driver.
    #[serde(default)]
    pub publish_ros2: bool,
    /// Serve the drive live to Foxglove on this address
    /// (`"127.0.0.1:8765"`); `ubf drive --live ADDRESS` sets it. Anyone
    /// who can reach the address can watch the robot (not steer it).
    #[serde(default)]
    pub live: Option<std::net::SocketAddr>,
    /// Give up (robot stopped, session closed, exit code 1) once the robot,
    /// by its own pose, has stayed within `radius_m` of one spot for
    /// `window_s` short of the goal: pressed against a wall its goal lies
    /// behind, say. [`ProgressCheck::STANDARD`] unless set; `progress:
    /// None`, only the goal, the time limit or the operator ends a drive.
    /// A drive without a goal is never ended by it.
    #[serde(default = "ProgressCheck::standard")]
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

/// A drive's control period: 10 ms to 1 s (a Powerbot's SIP comes every
/// 100 ms; a longer period would leave SIGTERM and the watchdog waiting).
fn drive_period_s<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    ubf_core::config::number_in(d, 0.01..=1.0, "from 0.01 to 1 s")
}

/// A cap on a log, MB: 1 MB to 1 TB.
fn log_max_mb<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    ubf_core::config::number_in(d, 1.0..=1e6, "from 1 to 1000000 MB")
}

/// The margin on the stop wait: up to 10 s.
fn stop_wait_s<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    ubf_core::config::number_in(d, 0.0..=10.0, "from 0 to 10 s")
}

/// An optional cap on speed, m/s (as [`ubf_core::config::speed_m_s`]).
fn optional_speed_m_s<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    ubf_core::config::optional_number_in(d, f64::MIN_POSITIVE..=10.0, "> 0 and at most 10 m/s")
}

/// An optional cap on turn rate, °/s (as [`ubf_core::config::rate_deg_s`]).
fn optional_rate_deg_s<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    ubf_core::config::optional_number_in(d, f64::MIN_POSITIVE..=3600.0, "> 0 and at most 3600 °/s")
}

/// A connection `ubf` knows how to open: `ros2`, `tcp://HOST:PORT`, or a
/// serial device's path (no scheme).
fn connection<'de, D: serde::Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    use serde::de::Error;
    let text = String::deserialize(d)?;
    if text == ROS2_CONNECTION || known_device(&text) {
        return Ok(text);
    }
    Err(D::Error::custom(format!(
        "`{text}` is not a connection: give a serial device (`/dev/ttyUSB0`), `tcp://host:port` or `ros2`"
    )))
}

/// Whether `text` is a serial device's path or `tcp://HOST:PORT`.
pub(crate) fn known_device(text: &str) -> bool {
    match text.split_once("://") {
        Some(("tcp", address)) => {
            address.rsplit_once(':').is_some_and(|(host, port)| !host.is_empty() && port.parse::<u16>().is_ok())
        }
        Some(_) => false,
        None => !text.is_empty(),
    }
}

/// A serial line's baud rate, one a serial port offers.
fn baud<'de, D: serde::Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    use serde::de::Error;
    const RATES: [u32; 9] = [1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400];
    let rate = u32::deserialize(d)?;
    if RATES.contains(&rate) {
        Ok(rate)
    } else {
        Err(D::Error::custom(format!("{rate} is not a serial baud rate: one of {RATES:?}")))
    }
}

impl DriveConfig {
    fn default_baud() -> u32 {
        9600
    }
    fn default_period() -> f64 {
        0.1
    }
    fn default_log_max_mb() -> f64 {
        2000.0
    }
    fn default_log() -> PathBuf {
        PathBuf::from("drive-log.csv")
    }
    fn default_stop_wait() -> f64 {
        1.0
    }

    /// The robot's speed limits: the model's, under the file's caps.
    pub(super) fn limits(&self, model: &RobotModel) -> Limits {
        let max_velocity = self.max_velocity.map_or(model.max_velocity, |cap| cap.min(model.max_velocity));
        let max_rot_deg =
            self.max_rot_velocity_deg.map_or(model.max_rot_velocity_deg, |cap| cap.min(model.max_rot_velocity_deg));
        Limits::new(max_velocity, max_rot_deg.to_radians())
    }

    /// How to open a session, motors on or not, with the world frame's
    /// origin at `origin`.
    pub(super) fn connect_options(&self, enable_motors: bool, origin: Pose2) -> ConnectOptions {
        ConnectOptions {
            enable_motors,
            max_velocity: self.max_velocity,
            max_rot_velocity_deg: self.max_rot_velocity_deg,
            accelerations: self.accelerations,
            origin,
            standstill_wait: Duration::from_secs_f64(self.stop_wait_s),
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
        let read = |path: &Path| {
            ubf_core::config::read_bounded(path, ubf_core::config::MOST_SETTINGS_BYTES)
                .map_err(|source| RobotFileError::Read { path: path.into(), source })
        };
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
    #[error("{}: {}", path.display(), ubf_core::config::why_unread(path, source))]
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The progress check of a robot file holding `extra`.
    fn progress_of(extra: &str) -> Option<ProgressCheck> {
        let text = format!(
            r#"RobotConfig(name: "r", connection: "tcp://127.0.0.1:1", model: Powerbot, {extra} root: Stop())"#
        );
        crate::registry().from_ron::<DriveConfig>(&text).unwrap().progress
    }

    #[test]
    fn a_drive_gives_up_short_of_its_goal_by_default_unless_told_not_to() {
        assert_eq!(progress_of(""), Some(ProgressCheck::STANDARD));
        assert_eq!(progress_of("progress: None,"), None);
        let own = ProgressCheck { radius_m: 0.3, window_s: 10.0 };
        assert_eq!(progress_of("progress: (radius_m: 0.3, window_s: 10.0),"), Some(own));
    }
}
