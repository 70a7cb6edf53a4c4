//! A pan-tilt unit carrying the cameras: the angles it is sent to, and the
//! angles its encoders read.
//!
//! A unit's encoders read its angles far more precisely than egomotion
//! estimates a turn of the robot, and it can move while the robot drives
//! straight: steering the camera instead of the robot keeps the robot's
//! heading, and the heading error a turn adds, out of the choice of view
//! (thesis §5.3.4).

use crate::RobotError;
use serde::{Deserialize, Serialize};

/// The angles of a pan-tilt unit, radians: pan counter-clockwise from the
/// robot's heading, tilt above the horizontal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Aim {
    /// Counter-clockwise from the robot's heading, rad.
    pub pan: f64,
    /// Above the horizontal, rad.
    pub tilt: f64,
}

/// A pan-tilt unit: the simulator's, or a real head on a serial line.
///
/// A real unit is driven the same way: [`PanTilt::command`] sends the
/// target angles (for a serial head such as a FLIR PTU, its absolute
/// position commands) and returns at once; [`PanTilt::measured`] reads the
/// encoders (its position queries). The robot that carries the unit calls
/// both from [`crate::Robot::aim_camera`] and [`crate::Robot::sense`], and
/// writes the measured angles into each frame's camera mount.
pub trait PanTilt: Send {
    /// Sends the unit towards `aim`, clamped to its limits; does not wait
    /// for it to get there.
    fn command(&mut self, aim: Aim) -> Result<(), RobotError>;

    /// The angles the encoders read now.
    fn measured(&mut self) -> Result<Aim, RobotError>;
}
