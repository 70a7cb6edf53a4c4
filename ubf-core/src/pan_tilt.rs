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
use std::time::Instant;

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

    /// The angles the encoders read last, and when they were read: a unit
    /// that polls its encoders on a thread of its own gives the poll's
    /// instant, which can be tens of milliseconds before now. By default,
    /// [`PanTilt::measured`] read now.
    fn measured_at(&mut self) -> Result<(Instant, Aim), RobotError> {
        let aim = self.measured()?;
        Ok((Instant::now(), aim))
    }

    /// The angles for the first frame, which anchors egomotion's map: the
    /// mean of [`ANCHOR_READINGS`] readings taken at once.
    ///
    /// Egomotion places its first keyframe's view by the robot's known
    /// start heading and the reading then, and chains later headings to
    /// that view, so an error in this one reading turns the whole map: the
    /// end point moves aside by the error times the distance driven. Over
    /// visual steps later readings' errors cancel (a keyframe keeps the
    /// reading it was placed with); a keyframe laid after an odometry bridge
    /// is placed by its own single reading. (Measured in the simulator, a
    /// steered camera in feature-poor layouts with 0.02° of noise a
    /// reading: 1.10× straight driving's end-point error with one reading,
    /// 1.01× with the mean of 64, 1.00× with the first reading exact.) A unit
    /// whose readings do not scatter, such as a stepper head reporting its
    /// step count, gives its one reading.
    fn anchor_reading(&mut self) -> Result<Aim, RobotError> {
        let first = self.measured()?;
        anchor_mean(first, || self.measured())
    }
}

/// The mean of `first` and [`ANCHOR_READINGS`] − 1 more readings from
/// `more`, summed as offsets from `first` so that equal readings give
/// `first` exactly.
pub fn anchor_mean(first: Aim, mut more: impl FnMut() -> Result<Aim, RobotError>) -> Result<Aim, RobotError> {
    let mut offset = Aim::default();
    for _ in 1..ANCHOR_READINGS {
        let aim = more()?;
        (offset.pan, offset.tilt) = (offset.pan + (aim.pan - first.pan), offset.tilt + (aim.tilt - first.tilt));
    }
    let n = ANCHOR_READINGS as f64;
    Ok(Aim { pan: first.pan + offset.pan / n, tilt: first.tilt + offset.tilt / n })
}

/// How many readings [`PanTilt::anchor_reading`] averages: noise that is
/// independent from reading to reading shrinks eightfold.
pub const ANCHOR_READINGS: usize = 64;
