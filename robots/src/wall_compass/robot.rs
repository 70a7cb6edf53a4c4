//! The wall compass on any robot with side sonars.

use super::{WallCompass, WallCompassConfig};
use ubf_core::{Pose2, Robot, RobotError, RobotWrapper, State, Wraps};

/// Wraps a robot and, when given a compass, replaces the odometric
/// [`State::pose`] with odometry's heading held by the walls
/// ([`WallCompass`]) every tick, and gives each wall's correction as
/// [`State::heading_fix`] for egomotion. Without one it passes everything
/// straight through.
pub struct WallCompassRobot<R> {
    inner: R,
    compass: Option<WallCompass>,
}

impl<R: Robot> WallCompassRobot<R> {
    /// `inner`, its heading held by the walls if `config` is given.
    pub fn new(inner: R, config: Option<WallCompassConfig>) -> Self {
        WallCompassRobot { inner, compass: config.map(WallCompass::new) }
    }

    /// The inner robot's `odometry` pose as this wrapper would pass it on:
    /// corrected by the walls where there is a compass (with the motion
    /// since its last update, which a robot that acted after it sensed has
    /// made), as it is otherwise.
    pub fn odometry(&self, odometry: Pose2) -> Pose2 {
        self.compass.as_ref().map_or(odometry, |c| c.corrected(&odometry))
    }
}

impl<R: Robot> Wraps for WallCompassRobot<R> {
    type Inner = R;
    fn inner(&self) -> &R {
        &self.inner
    }
    fn inner_mut(&mut self) -> &mut R {
        &mut self.inner
    }
}

impl<R: Robot> RobotWrapper for WallCompassRobot<R> {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        self.inner.sense(state)?;
        if let Some(compass) = &mut self.compass {
            state.pose = compass.update(&state.pose, &state.ranges);
            state.heading_fix = compass.heading_fix();
        }
        Ok(())
    }
}
