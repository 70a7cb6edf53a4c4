//! The robot seen from the controller: sense, act, shut down.

use crate::{Command, Hold, Limits, Pose2, State};

/// Why a robot could not sense or act.
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    /// The link to the robot is gone (cable, socket, emulator killed).
    #[error("robot disconnected: {0}")]
    Disconnected(String),
    /// Reading or writing the link failed.
    #[error("robot I/O: {0}")]
    Io(#[from] std::io::Error),
    /// The robot said something that makes no sense.
    #[error("robot protocol: {0}")]
    Protocol(String),
    /// Anything else.
    #[error("{0}")]
    Other(String),
}

/// A robot the controller can drive: a simulator, a serial-port Powerbot, or
/// a wrapper around either (a limiter, a recorder, a fault injector).
pub trait Robot: Send {
    /// Updates the sensor fields of `state` with the latest readings. The
    /// state's buffers are reused from tick to tick; mission fields (the
    /// goal) and `time` belong to the controller and are left alone.
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError>;

    /// Executes one command. Must not block for long: it runs inside the
    /// control tick.
    fn act(&mut self, command: &Command) -> Result<(), RobotError>;

    /// Stops the robot and releases it (motors off, link closed).
    fn shutdown(&mut self) -> Result<(), RobotError>;

    /// The robot's own speed limits.
    fn limits(&self) -> Limits;

    /// Where the robot really was when it last sensed, and what it has
    /// touched: a simulator knows, a real robot does not (the default).
    /// Records carry it so that logs and reports can compare the robot's
    /// belief with the truth.
    fn ground_truth(&self) -> Option<GroundTruth> {
        None
    }

    /// Points the camera `pan` radians counter-clockwise from the heading,
    /// on a robot whose camera rides a pan-tilt unit ([`crate::PanTilt`]);
    /// a robot with a fixed camera ignores it (the default). The controller
    /// calls it after [`Robot::act`] whenever the winning action sets
    /// [`crate::Motion::camera_pan`].
    fn aim_camera(&mut self, pan: f64) -> Result<(), RobotError> {
        let _ = pan;
        Ok(())
    }

    /// Why the robot is holding still this tick instead of obeying its
    /// commands (a safety guard's verdict); `None` (the default) when it
    /// obeys.
    fn hold(&self) -> Option<Hold> {
        None
    }
}

/// What only a simulator knows: see [`Robot::ground_truth`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GroundTruth {
    /// The true pose at the instant the state was sensed.
    pub pose: Pose2,
    /// Times so far the robot came into contact with a wall, a box or a
    /// person.
    pub collisions: u32,
}

impl<R: Robot + ?Sized> Robot for Box<R> {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        (**self).sense(state)
    }
    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        (**self).act(command)
    }
    fn shutdown(&mut self) -> Result<(), RobotError> {
        (**self).shutdown()
    }
    fn limits(&self) -> Limits {
        (**self).limits()
    }
    fn ground_truth(&self) -> Option<GroundTruth> {
        (**self).ground_truth()
    }
    fn aim_camera(&mut self, pan: f64) -> Result<(), RobotError> {
        (**self).aim_camera(pan)
    }
    fn hold(&self) -> Option<Hold> {
        (**self).hold()
    }
}

/// A robot that stands still where it is put and remembers the last command:
/// for tests, benchmarks and examples.
#[derive(Clone, Debug)]
pub struct NullRobot {
    /// The state `sense` reports (its time and goal are left alone).
    pub reported: State,
    /// The last command received.
    pub last_command: Command,
    /// Whether `shutdown` was called.
    pub shut_down: bool,
    /// The robot's limits.
    pub limits: Limits,
}

impl Default for NullRobot {
    fn default() -> Self {
        NullRobot {
            reported: State::default(),
            last_command: Command::Stop,
            shut_down: false,
            limits: Limits::new(1.0, 1.0),
        }
    }
}

impl Robot for NullRobot {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        state.copy_sensors_from(&self.reported);
        Ok(())
    }
    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        self.last_command = *command;
        Ok(())
    }
    fn shutdown(&mut self) -> Result<(), RobotError> {
        self.last_command = Command::Stop;
        self.shut_down = true;
        Ok(())
    }
    fn limits(&self) -> Limits {
        self.limits
    }
}

/// Wraps any robot and lowers its speed limits: a cautious first run on a
/// real robot, without editing the behaviour tree.
pub struct VelocityLimiter<R> {
    inner: R,
    limits: Limits,
}

impl<R: Robot> VelocityLimiter<R> {
    /// Limits `inner` to the tighter of its own limits and `limits`.
    pub fn new(inner: R, limits: Limits) -> Self {
        let own = inner.limits();
        let limits =
            Limits::new(own.max_velocity.min(limits.max_velocity), own.max_rot_velocity.min(limits.max_rot_velocity));
        VelocityLimiter { inner, limits }
    }

    /// The wrapped robot.
    pub fn inner(&self) -> &R {
        &self.inner
    }
}

impl<R: Robot> Robot for VelocityLimiter<R> {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        self.inner.sense(state)
    }
    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        let limited = match *command {
            Command::Stop => Command::Stop,
            Command::Drive { velocity, turn } => Command::Drive {
                velocity: velocity.clamp(-self.limits.max_velocity, self.limits.max_velocity),
                turn: match turn {
                    crate::Turn::Rate(r) => {
                        crate::Turn::Rate(r.clamp(-self.limits.max_rot_velocity, self.limits.max_rot_velocity))
                    }
                    crate::Turn::Heading { heading, max_rate } => {
                        crate::Turn::Heading { heading, max_rate: max_rate.min(self.limits.max_rot_velocity) }
                    }
                },
            },
        };
        self.inner.act(&limited)
    }
    fn shutdown(&mut self) -> Result<(), RobotError> {
        self.inner.shutdown()
    }
    fn limits(&self) -> Limits {
        self.limits
    }
    fn ground_truth(&self) -> Option<GroundTruth> {
        self.inner.ground_truth()
    }
    fn aim_camera(&mut self, pan: f64) -> Result<(), RobotError> {
        self.inner.aim_camera(pan)
    }
    fn hold(&self) -> Option<Hold> {
        self.inner.hold()
    }
}
