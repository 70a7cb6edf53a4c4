//! [`EmergencyStop`]: what a signal handler stops a real robot with while
//! the control loop is busy or stuck.

use ubf_core::RobotError;

/// A robot's own handle for stopping it from outside the control loop
/// (Ctrl-C or SIGTERM arrive on a thread of their own). Each robot stops
/// its own way: an ARCOS controller by STOP, a ROS 2 base by a zero twist.
pub trait EmergencyStop: Send {
    /// Stops the robot now, from whatever thread, and holds it still: the
    /// control loop's motion commands go out as a stop from here on, while
    /// it runs its orderly stop. The first Ctrl-C or SIGTERM.
    fn halt(&self) -> Result<(), RobotError>;

    /// Stops the robot for a process about to exit, without waiting for
    /// the orderly stop: the second Ctrl-C or SIGTERM.
    fn stop_now(&self) -> Result<(), RobotError>;

    /// What [`stop_now`](EmergencyStop::stop_now) sends, for the operator:
    /// "STOP, ENABLE 0 and CLOSE".
    fn stop_now_sends(&self) -> String;
}
