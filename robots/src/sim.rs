//! A headless simulated differential-drive robot.
//!
//! The robot moves on a plane under velocity and acceleration limits. It
//! knows its true pose (for reports, never for behaviours) and reports its
//! odometric pose in the state.

use serde::Deserialize;
use ubf_core::config::{finite, positive};
use ubf_core::{wrap_angle, Command, Limits, Pose2, Robot, RobotError, State, Turn};

/// Where the robot starts, as written in a scenario file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartPose {
    /// Metres.
    #[serde(default, deserialize_with = "finite")]
    pub x: f64,
    /// Metres.
    #[serde(default, deserialize_with = "finite")]
    pub y: f64,
    /// Degrees from the x axis, counter-clockwise.
    #[serde(default, deserialize_with = "finite")]
    pub heading_deg: f64,
}

impl StartPose {
    /// The start as a pose in SI units.
    pub fn pose(&self) -> Pose2 {
        Pose2::new(self.x, self.y, wrap_angle(self.heading_deg.to_radians()))
    }
}

/// The simulated robot's settings, as written in a scenario file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimRobotConfig {
    /// Where the robot starts.
    #[serde(default)]
    pub start: StartPose,
    /// Largest forward speed, m/s. The default is the thesis robot's
    /// reduced top speed (§4.4.6).
    #[serde(default = "SimRobotConfig::default_max_velocity", deserialize_with = "positive")]
    pub max_velocity: f64,
    /// Largest turn rate, °/s.
    #[serde(default = "SimRobotConfig::default_max_rot_velocity_deg", deserialize_with = "positive")]
    pub max_rot_velocity_deg: f64,
    /// Largest change of forward speed, m/s².
    #[serde(default = "SimRobotConfig::default_max_acceleration", deserialize_with = "positive")]
    pub max_acceleration: f64,
    /// Largest change of turn rate, °/s².
    #[serde(default = "SimRobotConfig::default_max_rot_acceleration_deg", deserialize_with = "positive")]
    pub max_rot_acceleration_deg: f64,
    /// Turn rate per radian of heading error when a command gives a
    /// heading, 1/s.
    #[serde(default = "SimRobotConfig::default_heading_gain", deserialize_with = "positive")]
    pub heading_gain: f64,
}

impl SimRobotConfig {
    fn default_max_velocity() -> f64 {
        0.6
    }
    fn default_max_rot_velocity_deg() -> f64 {
        60.0
    }
    fn default_max_acceleration() -> f64 {
        0.5
    }
    fn default_max_rot_acceleration_deg() -> f64 {
        120.0
    }
    fn default_heading_gain() -> f64 {
        2.0
    }
}

impl Default for SimRobotConfig {
    fn default() -> Self {
        SimRobotConfig {
            start: StartPose::default(),
            max_velocity: Self::default_max_velocity(),
            max_rot_velocity_deg: Self::default_max_rot_velocity_deg(),
            max_acceleration: Self::default_max_acceleration(),
            max_rot_acceleration_deg: Self::default_max_rot_acceleration_deg(),
            heading_gain: Self::default_heading_gain(),
        }
    }
}

/// A simulated differential-drive robot. Each [`Robot::act`] advances the
/// simulation by one period.
#[derive(Clone, Debug)]
pub struct SimRobot {
    config: SimRobotConfig,
    period: f64,
    true_pose: Pose2,
    odometry: Pose2,
    velocity: f64,
    rot_velocity: f64,
    distance: f64,
}

impl SimRobot {
    /// A robot at its configured start, stepping `period` seconds per act.
    pub fn new(config: SimRobotConfig, period: f64) -> Self {
        let start = config.start.pose();
        SimRobot { config, period, true_pose: start, odometry: start, velocity: 0.0, rot_velocity: 0.0, distance: 0.0 }
    }

    /// Where the robot really is.
    pub fn true_pose(&self) -> Pose2 {
        self.true_pose
    }

    /// Where its odometry says it is.
    pub fn odometry_pose(&self) -> Pose2 {
        self.odometry
    }

    /// Metres driven so far (path length).
    pub fn distance_travelled(&self) -> f64 {
        self.distance
    }

    fn targets(&self, command: &Command) -> (f64, f64) {
        match *command {
            Command::Stop => (0.0, 0.0),
            Command::Drive { velocity, turn: Turn::Rate(rate) } => (velocity, rate),
            Command::Drive { velocity, turn: Turn::Heading { heading, max_rate } } => {
                let error = wrap_angle(heading - self.odometry.theta);
                (velocity, (self.config.heading_gain * error).clamp(-max_rate, max_rate))
            }
        }
    }
}

/// Moves `current` towards `target` by at most `step`.
fn approach(current: f64, target: f64, step: f64) -> f64 {
    current + (target - current).clamp(-step, step)
}

/// Advances `pose` along the arc of speeds `(v, w)` for `dt` seconds.
fn integrate(pose: Pose2, v: f64, w: f64, dt: f64) -> Pose2 {
    let dtheta = w * dt;
    let (dx, dy) = if dtheta.abs() < 1e-9 {
        (v * dt, 0.0)
    } else {
        let radius = v / w;
        (radius * dtheta.sin(), radius * (1.0 - dtheta.cos()))
    };
    pose.compose(&Pose2::new(dx, dy, dtheta))
}

impl Robot for SimRobot {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        state.pose = self.odometry;
        state.velocity = self.velocity;
        state.rot_velocity = self.rot_velocity;
        state.motors_enabled = true;
        state.sensor_age = 0.0;
        Ok(())
    }

    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        let limits = self.limits();
        let (v_target, w_target) = self.targets(command);
        let dt = self.period;
        self.velocity = approach(self.velocity, v_target, self.config.max_acceleration * dt)
            .clamp(-limits.max_velocity, limits.max_velocity);
        self.rot_velocity =
            approach(self.rot_velocity, w_target, self.config.max_rot_acceleration_deg.to_radians() * dt)
                .clamp(-limits.max_rot_velocity, limits.max_rot_velocity);
        self.true_pose = integrate(self.true_pose, self.velocity, self.rot_velocity, dt);
        self.odometry = integrate(self.odometry, self.velocity, self.rot_velocity, dt);
        self.distance += self.velocity.abs() * dt;
        Ok(())
    }

    fn shutdown(&mut self) -> Result<(), RobotError> {
        self.velocity = 0.0;
        self.rot_velocity = 0.0;
        Ok(())
    }

    fn limits(&self) -> Limits {
        Limits::new(self.config.max_velocity, self.config.max_rot_velocity_deg.to_radians())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn a_full_circle_returns_home() {
        let pose = (0..1000).fold(Pose2::default(), |p, _| integrate(p, 1.0, 2.0 * PI / 10.0, 0.01));
        assert!(pose.x.abs() < 1e-9 && pose.y.abs() < 1e-9 && pose.theta.abs() < 1e-9, "{pose:?}");
    }

    #[test]
    fn acceleration_is_limited() {
        let mut robot = SimRobot::new(SimRobotConfig::default(), 0.1);
        robot.act(&Command::Drive { velocity: 0.6, turn: Turn::Rate(0.0) }).unwrap();
        assert!((robot.velocity - 0.05).abs() < 1e-12);
        for _ in 0..100 {
            robot.act(&Command::Drive { velocity: 5.0, turn: Turn::Rate(0.0) }).unwrap();
        }
        assert_eq!(robot.velocity, 0.6);
    }

    #[test]
    fn heading_commands_turn_the_short_way() {
        let mut robot = SimRobot::new(SimRobotConfig::default(), 0.1);
        robot.act(&Command::Drive { velocity: 0.0, turn: Turn::Heading { heading: -0.5, max_rate: 1.0 } }).unwrap();
        assert!(robot.rot_velocity < 0.0);
    }
}
