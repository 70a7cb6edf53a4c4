//! What the estimators share: the motion of one step, the matched
//! landmarks they estimate it from, what the robot was commanded to do
//! meanwhile, and the [`StepEstimator`] trait the tracker asks them through.

use crate::stereo::StereoCamera;
use nalgebra::Matrix3;
use rand_chacha::ChaCha8Rng;
use ubf_core::{CameraMount, Command, Pose2, StereoPixels, Turn};

/// A planar motion of the robot between two frames, in the earlier frame's
/// robot frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlanarMotion {
    /// Metres forward.
    pub forward: f64,
    /// Metres to the left.
    pub left: f64,
    /// Radians turned, counter-clockwise.
    pub yaw: f64,
}

impl PlanarMotion {
    pub(super) fn as_pose(&self) -> Pose2 {
        Pose2::new(self.forward, self.left, self.yaw)
    }
}

/// What the estimators know of one matched landmark.
#[derive(Clone, Copy, Debug)]
pub(super) struct Pair {
    pub(super) before: [f64; 3],
    pub(super) after: [f64; 3],
    pub(super) cv: f64,
    /// The pixels it was seen at in the earlier and the later frame, where
    /// they triangulate: the disparity offset is read from them.
    pub(super) pixels: Option<[StereoPixels; 2]>,
}

impl Pair {
    /// A landmark seen at `before` and `after`, weighed by `cv`; its pixels
    /// are left for the tracker to fill in.
    pub(super) fn new(before: [f64; 3], after: [f64; 3], cv: f64) -> Pair {
        Pair { before, after, cv, pixels: None }
    }
}

/// What the robot was commanded to do between two frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MotionPhase {
    /// Nothing known, or a mix of turning and driving.
    #[default]
    Unknown,
    /// Only turns on the spot.
    Turning,
    /// Only driving straight (turn rates under a few degrees a second).
    Translating,
    /// Standing still.
    Still,
}

impl MotionPhase {
    /// The phase after also being commanded `command`.
    pub(super) fn and(self, command: &Command) -> MotionPhase {
        // Below this, a turn rate is steering, not turning, rad/s.
        const STEERING: f64 = 0.05;
        let this = match *command {
            Command::Stop => MotionPhase::Still,
            Command::Drive { velocity, turn: Turn::Rate(rate) } => match (velocity.abs() < 1e-3, rate.abs() < STEERING)
            {
                (true, true) => MotionPhase::Still,
                (true, false) => MotionPhase::Turning,
                (false, true) => MotionPhase::Translating,
                (false, false) => MotionPhase::Unknown,
            },
            Command::Drive { turn: Turn::Heading { .. }, .. } => MotionPhase::Unknown,
        };
        match (self, this) {
            (MotionPhase::Still, other) | (other, MotionPhase::Still) => other,
            (a, b) if a == b => a,
            _ => MotionPhase::Unknown,
        }
    }
}

/// The mounts a step's two frames were taken with, to lift each frame's
/// landmarks out of its own camera frame: a pan of the camera between the
/// frames is then not read as a turn of the robot.
#[derive(Clone, Copy, Debug)]
pub(super) struct Mounts {
    /// The earlier frame's mount.
    pub(super) before: CameraMount,
    /// The later frame's mount.
    pub(super) after: CameraMount,
    /// The tracker's camera where it sits, looking straight ahead.
    pub(super) ahead: CameraMount,
}

/// What an estimator is told of a step besides its matched landmarks.
pub(super) struct StepInput<'a> {
    /// The camera the frames were taken with.
    pub(super) camera: &'a StereoCamera,
    /// The longest translation the robot can have made between the
    /// frames, m.
    pub(super) max_step_m: f64,
    /// What the robot was commanded to do between the frames.
    pub(super) phase: MotionPhase,
    /// The turn between the frames as odometry measured it (or, without
    /// odometry, as egomotion last put it), rad.
    pub(super) turned_rad: f64,
    /// The fewest consistent landmarks a motion may rest on.
    pub(super) min_landmarks: usize,
    /// The tracker's generator, for random draws (RANSAC's samples).
    pub(super) rng: &'a mut ChaCha8Rng,
}

/// The motion an estimator found for a step.
pub(super) struct StepMotion {
    /// The motion, in the earlier frame's robot frame.
    pub(super) motion: PlanarMotion,
    /// How many matched landmarks it rests on.
    pub(super) landmarks: usize,
    /// Its covariance (forward, left, yaw), where the estimator gives one.
    pub(super) covariance: Option<Matrix3<f64>>,
    /// The matched landmarks consistent with it, where the estimator says
    /// (empty where it does not): the disparity offset is read from them.
    pub(super) inliers: Vec<Pair>,
}

/// An egomotion estimator: from the landmarks matched between two frames,
/// the robot's motion between them. The scenario's settings choose one
/// (`EstimatorKind::estimator`), and the tracker asks it only this, so
/// another estimator needs no change to the tracker.
pub(super) trait StepEstimator {
    /// Whether it must work frame to frame: given the newest keyframe
    /// first, with every matched frame becoming a keyframe.
    fn frame_to_frame(&self) -> bool;

    /// A landmark seen at `before` and `after`, each in the camera frame of
    /// the mount in `mounts` it was taken with, lifted into the frame the
    /// estimator works in; `cv` weighs it.
    fn pair(&self, before: [f64; 3], after: [f64; 3], mounts: &Mounts, cv: f64) -> Pair;

    /// The motion `pairs` give, or `None` when they give none the
    /// estimator trusts.
    fn estimate(&self, pairs: &[Pair], input: StepInput<'_>) -> Option<StepMotion>;
}
