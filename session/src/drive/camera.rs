//! A robot file's camera: its source opened before the motors go on, and
//! the robot equipped with it and with egomotion.

use super::robot_file::{CameraSourceChoice, DriveCamera, DriveConfig, RectifyFilesError};
use std::path::Path;
use ubf_core::{Pose2, Robot, RobotError};
use ubf_perception::egomotion::Tracker;
use ubf_perception::source::{CameraSource, ImageDirectory, SourceError};
use ubf_perception::StereoCamera;
use ubf_robots::camera::CameraRobot;
use ubf_robots::egomotion::EgomotionRobot;
use ubf_robots::ptu::Ptu;
use ubf_robots::wall_compass::WallCompassRobot;

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

/// A robot as a drive runs it: its heading held by the walls, its camera
/// and egomotion around it.
pub(super) type EquippedRobot<R> = EgomotionRobot<CameraRobot<WallCompassRobot<R>>>;

/// A camera opened before its session.
pub(super) struct OpenCamera {
    source: Box<dyn CameraSource + Send>,
    paced: bool,
    pan_tilt: Option<Ptu>,
}

impl DriveConfig {
    /// Opens the camera and its pan-tilt head, if there are: before
    /// connecting, so that a camera that fails never leaves the motors on.
    pub(super) fn open_camera(&self) -> Result<Option<OpenCamera>, CameraError> {
        let Some(camera) = &self.camera else { return Ok(None) };
        let (source, paced) = open_source(camera)?;
        let pan_tilt = camera.pan_tilt.clone().map(Ptu::connect).transpose().map_err(CameraError::PanTilt)?;
        Ok(Some(OpenCamera { source, paced, pan_tilt }))
    }

    /// Opens the camera's source and lets it go, for `ubf check`: a
    /// directory that is not there, or a device that cannot be opened, is
    /// found before the drive. The pan-tilt head is left alone: it may be
    /// switched off until the drive.
    pub fn check_camera(&self) -> Result<(), CameraError> {
        match &self.camera {
            Some(camera) => open_source(camera).map(drop),
            None => Ok(()),
        }
    }

    /// `robot` with its heading held by the walls (where the drive has a
    /// wall compass), the opened camera and the egomotion tracker (starting
    /// at `origin`) around it.
    pub(super) fn equip<R: Robot>(
        &self,
        robot: R,
        camera: Option<OpenCamera>,
        origin: Pose2,
    ) -> Result<EquippedRobot<R>, CameraError> {
        let robot = WallCompassRobot::new(robot, self.wall_compass);
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
}
