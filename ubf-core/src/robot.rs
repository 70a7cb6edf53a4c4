//! The robot seen from the controller: sense, act, shut down.

use crate::{Command, Hold, Limits, Pose2, RobotError, State};

/// A robot the controller can drive: a simulator, a serial-port Powerbot, or
/// a wrapper around either (a limiter, a recorder, a fault injector).
pub trait Robot: Send {
    /// Updates the sensor fields of `state` with the latest readings. The
    /// state's buffers are reused from tick to tick; mission fields (the
    /// goal) and `time` belong to the controller and are left alone. A
    /// robot reporting its wheels' odometry sets both `pose` and
    /// `odometry` to it: wrappers that correct the pose (the wall compass,
    /// egomotion) leave `odometry` as the wheels said, and logs show it.
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

/// A robot around another robot: [`Wraps::inner`] reaches the robot
/// inside (a wrapper's own methods are the [`RobotWrapper`]'s).
pub trait Wraps {
    /// The robot inside.
    type Inner: Robot + ?Sized;
    /// The robot inside.
    fn inner(&self) -> &Self::Inner;
    /// The robot inside, to talk to it directly.
    fn inner_mut(&mut self) -> &mut Self::Inner;
}

/// A wrapper that changes some of what the robot inside does: each method
/// goes to the inner robot unless the wrapper writes its own, so a wrapper
/// writes only what it changes (a velocity limiter, `act` and `limits`).
/// Every `RobotWrapper` is a [`Robot`]. Import this trait where a wrapper is
/// written, and [`Robot`] where one is used: with both in scope, a method
/// call such as `guard.sense(..)` is ambiguous.
pub trait RobotWrapper: Wraps + Send {
    /// See [`Robot::sense`].
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        self.inner_mut().sense(state)
    }
    /// See [`Robot::act`].
    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        self.inner_mut().act(command)
    }
    /// See [`Robot::shutdown`].
    fn shutdown(&mut self) -> Result<(), RobotError> {
        self.inner_mut().shutdown()
    }
    /// See [`Robot::limits`].
    fn limits(&self) -> Limits {
        self.inner().limits()
    }
    /// See [`Robot::ground_truth`].
    fn ground_truth(&self) -> Option<GroundTruth> {
        self.inner().ground_truth()
    }
    /// See [`Robot::aim_camera`].
    fn aim_camera(&mut self, pan: f64) -> Result<(), RobotError> {
        self.inner_mut().aim_camera(pan)
    }
    /// See [`Robot::hold`].
    fn hold(&self) -> Option<Hold> {
        self.inner().hold()
    }
}

impl<W: RobotWrapper> Robot for W {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        RobotWrapper::sense(self, state)
    }
    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        RobotWrapper::act(self, command)
    }
    fn shutdown(&mut self) -> Result<(), RobotError> {
        RobotWrapper::shutdown(self)
    }
    fn limits(&self) -> Limits {
        RobotWrapper::limits(self)
    }
    fn ground_truth(&self) -> Option<GroundTruth> {
        RobotWrapper::ground_truth(self)
    }
    fn aim_camera(&mut self, pan: f64) -> Result<(), RobotError> {
        RobotWrapper::aim_camera(self, pan)
    }
    fn hold(&self) -> Option<Hold> {
        RobotWrapper::hold(self)
    }
}

/// A boxed robot (`Box<dyn Robot>`) is the robot in the box.
impl<R: Robot + ?Sized> Wraps for Box<R> {
    type Inner = R;
    fn inner(&self) -> &R {
        self
    }
    fn inner_mut(&mut self) -> &mut R {
        self
    }
}

impl<R: Robot + ?Sized> RobotWrapper for Box<R> {}

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
}

impl<R: Robot> Wraps for VelocityLimiter<R> {
    type Inner = R;
    fn inner(&self) -> &R {
        &self.inner
    }
    fn inner_mut(&mut self) -> &mut R {
        &mut self.inner
    }
}

impl<R: Robot> RobotWrapper for VelocityLimiter<R> {
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
    fn limits(&self) -> Limits {
        self.limits
    }
}

#[cfg(test)]
mod tests {
    use super::{NullRobot, Robot, RobotWrapper, VelocityLimiter, Wraps};
    use crate::{Command, Limits, RobotError, State, Turn};

    /// A wrapper that writes only `act`: it counts the commands.
    struct Counting {
        inner: NullRobot,
        acts: u32,
    }

    impl Wraps for Counting {
        type Inner = NullRobot;
        fn inner(&self) -> &NullRobot {
            &self.inner
        }
        fn inner_mut(&mut self) -> &mut NullRobot {
            &mut self.inner
        }
    }

    impl RobotWrapper for Counting {
        fn act(&mut self, command: &Command) -> Result<(), RobotError> {
            self.acts += 1;
            self.inner.act(command)
        }
    }

    #[test]
    fn a_wrapper_forwards_what_it_does_not_write() {
        let mut robot = Counting { inner: NullRobot::default(), acts: 0 };
        robot.inner.reported.pose.x = 2.5;
        let mut state = State::default();
        Robot::sense(&mut robot, &mut state).unwrap();
        assert_eq!(state.pose.x, 2.5);
        Robot::act(&mut robot, &Command::Drive { velocity: 0.3, turn: Turn::Rate(0.0) }).unwrap();
        assert_eq!(robot.acts, 1);
        assert_eq!(Robot::limits(&robot), NullRobot::default().limits);
        Robot::shutdown(&mut robot).unwrap();
        assert!(robot.inner().shut_down);
    }

    #[test]
    fn a_velocity_limiter_clamps_and_a_boxed_robot_is_its_robot() {
        let mut limiter = VelocityLimiter::new(NullRobot::default(), Limits::new(0.2, 0.5));
        Robot::act(&mut limiter, &Command::Drive { velocity: 0.9, turn: Turn::Rate(-2.0) }).unwrap();
        assert_eq!(limiter.inner().last_command, Command::Drive { velocity: 0.2, turn: Turn::Rate(-0.5) });
        // (Called through `Robot`: with `RobotWrapper` in scope too, a
        // method call on a wrapper is ambiguous.)
        let mut boxed: Box<dyn Robot> = Box::new(limiter);
        assert_eq!(Robot::limits(&boxed), Limits::new(0.2, 0.5));
        Robot::shutdown(&mut boxed).unwrap();
    }
}
