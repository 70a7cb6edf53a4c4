//! Egomotion on any robot: a wrapper that feeds the robot's stereo frames to
//! an estimator and puts the result in the state.

use ubf_core::{Command, Robot, RobotError, RobotWrapper, State, Wraps};
use ubf_perception::egomotion::Tracker;

/// Wraps a robot and, when given a tracker, runs egomotion on its stereo
/// frames every tick, filling [`State::egomotion`] (and, where the tracker
/// navigates, replacing the odometric [`State::pose`] with egomotion's). A
/// [`State::heading_fix`] (the wall compass's) turns egomotion's heading.
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

    /// The estimator, if any.
    pub fn tracker(&self) -> Option<&Tracker> {
        self.tracker.as_ref()
    }
}

impl<R: Robot> Wraps for EgomotionRobot<R> {
    type Inner = R;
    fn inner(&self) -> &R {
        &self.inner
    }
    fn inner_mut(&mut self) -> &mut R {
        &mut self.inner
    }
}

impl<R: Robot> RobotWrapper for EgomotionRobot<R> {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        self.inner.sense(state)?;
        if let Some(tracker) = &mut self.tracker {
            if let Some(fix) = state.heading_fix {
                tracker.fix_heading(fix, &state.pose);
            }
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
}
