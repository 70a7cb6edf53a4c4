//! What the estimators share: the motion of one step, the matched
//! landmarks they estimate it from, and what the robot was commanded to do
//! meanwhile.

use ubf_core::{Command, Pose2, Turn};

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
