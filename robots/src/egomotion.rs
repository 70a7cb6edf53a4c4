//! Egomotion on any robot: a wrapper that feeds the robot's stereo frames to
//! an estimator and puts the result in the state.

use crate::timed_readings::TimedReadings;
use ubf_core::{Command, Pose2, Robot, RobotError, RobotWrapper, State, Wraps};
use ubf_perception::egomotion::Tracker;

/// Wraps a robot and, when given a tracker, runs egomotion on its stereo
/// frames every tick, filling [`State::egomotion`] (and, where the tracker
/// navigates, replacing the odometric [`State::pose`] with egomotion's). A
/// [`State::heading_fix`] (the wall compass's) turns egomotion's heading.
/// Without a tracker it passes everything straight through.
///
/// Each frame is matched to odometry as it read when the frame's pair was
/// taken ([`StereoFrame::time`](ubf_core::StereoFrame::time)), on the line
/// between the robot's reports either side (each stamped
/// [`State::sensor_age`] before its tick: for an ARCOS robot when its
/// packet arrived, for a ROS 2 robot the tick that first saw it): a real
/// camera's frame reaches the control loop a tick or more after its pair
/// was taken, and the robot has driven on since. (The simulator's frames
/// are taken at the tick, and take that tick's odometry as it is.)
pub struct EgomotionRobot<R> {
    inner: R,
    tracker: Option<Tracker>,
    /// Odometry's recent readings, by the controller's clock.
    odometry: TimedReadings<f64, Pose2>,
}

impl<R: Robot> EgomotionRobot<R> {
    /// `inner`, with egomotion from `tracker` if there is one.
    pub fn new(inner: R, tracker: Option<Tracker>) -> Self {
        EgomotionRobot { inner, tracker, odometry: TimedReadings::default() }
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
                // The sensor turned odometry about this tick's pose: the
                // poses kept from before are turned with it, so that a frame
                // taken before the fix is placed in the frame after it.
                let before = Pose2 { theta: state.pose.theta - fix.correction, ..state.pose };
                self.odometry.remake(|pose| state.pose.compose(&pose.relative_to(&before)));
            }
            // Odometry as read when the robot last reported, not at the tick.
            let read_at = state.time - state.sensor_age;
            if read_at.is_finite() {
                self.odometry.push(read_at, state.pose);
            }
            if tracker.is_new(&state.stereo) {
                // A frame taken at this tick (the simulator's) takes this
                // tick's odometry, the newest reading.
                let when_taken = self.odometry.at(state.stereo.time).unwrap_or(state.pose);
                tracker.update(&state.stereo, &when_taken);
            }
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
