//! Egomotion on any robot: a wrapper that feeds the robot's stereo frames to
//! an estimator and puts the result in the state.

use ubf_core::{Command, Limits, Robot, RobotError, State};
use ubf_perception::egomotion::Tracker;

/// Wraps a robot and, when given a tracker, runs egomotion on its stereo
/// frames every tick, filling [`State::egomotion`] (and, where the tracker
/// navigates, replacing the odometric [`State::pose`] with egomotion's).
/// Without a tracker it passes everything straight through.
pub struct EgomotionRobot<R> {
    inner: R,
    tracker: Option<Tracker>,
}

impl<R: Robot> EgomotionRobot<R> {
    /// `inner`, with egomotion from `tracker` if there is one.
    pub fn new(inner: R, tracker: Option<Tracker>) -> Self {
        EgomotionRobot { inner, tracker }
    }

    /// The wrapped robot.
    pub fn inner(&self) -> &R {
        &self.inner
    }

    /// The wrapped robot, to talk to it directly.
    pub fn inner_mut(&mut self) -> &mut R {
        &mut self.inner
    }

    /// The estimator, if any.
    pub fn tracker(&self) -> Option<&Tracker> {
        self.tracker.as_ref()
    }
}

impl<R: Robot> Robot for EgomotionRobot<R> {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        self.inner.sense(state)?;
        if let Some(tracker) = &mut self.tracker {
            tracker.update(&state.stereo, &state.pose);
            state.egomotion = tracker.state();
            if let Some(pose) = tracker.navigation_pose(&state.pose) {
                state.pose = pose;
            }
        }
        Ok(())
    }

    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        if let Some(tracker) = &mut self.tracker {
            tracker.commanded(command);
        }
        self.inner.act(command)
    }

    fn shutdown(&mut self) -> Result<(), RobotError> {
        self.inner.shutdown()
    }

    fn limits(&self) -> Limits {
        self.inner.limits()
    }
    fn ground_truth(&self) -> Option<ubf_core::GroundTruth> {
        self.inner.ground_truth()
    }
    fn aim_camera(&mut self, pan: f64) -> Result<(), RobotError> {
        self.inner.aim_camera(pan)
    }

    fn hold(&self) -> Option<ubf_core::Hold> {
        self.inner.hold()
    }
}
