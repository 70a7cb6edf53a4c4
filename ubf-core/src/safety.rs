//! The controller's safety policy as a robot wrapper: whatever the tree
//! asks, no motion command goes out on stale data, a lost link is declared
//! at a stated time, and a stall or a bumper latches a stop.
//!
//! It is timed by the controller's clock (the state's `time` and
//! `sensor_age`), not by the wall, so the same policy runs, and is tested,
//! on the simulator's clock and on a real robot's.

use crate::{Command, LinkLoss, Pose2, Robot, RobotError, RobotWrapper, State, Wraps};
use serde::Deserialize;

/// When to hold the robot still, whatever the behaviours want.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SafetyPolicy {
    /// Sensor data older than this, s, sends STOP instead of any motion
    /// command (ARCOS sends a SIP every 0.1 s: the default allows two
    /// missed cycles and a little jitter).
    #[serde(deserialize_with = "stale_after_s")]
    pub stale_after_s: f64,
    /// Sensor data older than this, s, is a lost link: the robot reports
    /// a disconnection. Counted from the first tick until data first comes.
    #[serde(deserialize_with = "link_lost_after_s")]
    pub link_lost_after_s: f64,
    /// After a stall or a bumper, hold still until the condition has been
    /// clear this long, s; `None` holds until the operator restarts.
    #[serde(deserialize_with = "crate::config::optional_duration_s")]
    pub resume_after_s: Option<f64>,
}

/// Stale after 1 ms to 10 s: beyond that the guard would not guard.
fn stale_after_s<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    crate::config::number_in(d, 0.001..=10.0, "from 0.001 to 10 s")
}

/// A link lost after 1 ms to 60 s.
fn link_lost_after_s<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    crate::config::number_in(d, 0.001..=60.0, "from 0.001 to 60 s")
}

impl crate::config::Check for SafetyPolicy {
    fn check(&self) -> Result<(), String> {
        if self.stale_after_s > self.link_lost_after_s {
            return Err(format!(
                "stale_after_s ({} s) must not exceed link_lost_after_s ({} s): data is stale before the link is lost",
                self.stale_after_s, self.link_lost_after_s
            ));
        }
        Ok(())
    }
}

impl Default for SafetyPolicy {
    /// Stop after 0.25 s without data, declare the link lost after 1.3 s,
    /// resume 2 s after a stall or bump clears.
    fn default() -> Self {
        SafetyPolicy { stale_after_s: 0.25, link_lost_after_s: 1.3, resume_after_s: Some(2.0) }
    }
}

/// Why the guard is holding the robot still.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hold {
    /// The sensor data is older than the policy allows.
    StaleData,
    /// A wheel stalled or a bumper was pressed, and motion is not allowed
    /// again yet.
    Contact,
}

/// A robot behind a [`SafetyPolicy`].
#[derive(Clone, Debug)]
pub struct SafetyGuard<R: Robot> {
    inner: R,
    policy: SafetyPolicy,
    /// When the first tick sensed, s.
    started: Option<f64>,
    /// Why motion is held this tick, if it is.
    hold: Option<Hold>,
    /// A stall or bump latched: when the condition was last seen clear
    /// (`None` while it persists).
    contact: Option<Option<f64>>,
    /// The latest contact, latched or released: not to be driven into
    /// again until the robot has moved away from it.
    touched: Option<Contact>,
    /// The pose sensed this tick.
    pose: Pose2,
    /// The translational speed last commanded, m/s: which way the robot
    /// was pushing when a wheel stalled.
    last_velocity: f64,
}

/// Where the robot touched something, and which way it was pushing.
#[derive(Clone, Copy, Debug)]
struct Contact {
    at: Pose2,
    /// 1 pushing forward, −1 backing.
    pushing: f64,
}

/// Within this angle of the way it pushed when it touched, a motion drives
/// into the same contact again, rad (60°).
const INTO_CONTACT: f64 = std::f64::consts::FRAC_PI_3;
/// Once this far from where it touched, m, the robot is clear of it.
const CLEAR_OF_CONTACT_M: f64 = 0.5;

impl Contact {
    /// Whether moving at `velocity` from `pose` drives back into it.
    fn is_ahead(&self, pose: &Pose2, velocity: f64) -> bool {
        let way = |heading: f64, sign: f64| if sign < 0.0 { heading + std::f64::consts::PI } else { heading };
        velocity != 0.0
            && crate::wrap_angle(way(pose.theta, velocity) - way(self.at.theta, self.pushing)).abs() < INTO_CONTACT
    }
}

impl<R: Robot> SafetyGuard<R> {
    /// `inner` under `policy`.
    pub fn new(inner: R, policy: SafetyPolicy) -> Self {
        SafetyGuard {
            inner,
            policy,
            started: None,
            hold: None,
            contact: None,
            touched: None,
            pose: Pose2::default(),
            last_velocity: 0.0,
        }
    }

    /// Updates the contact latch, and the contact remembered, from this
    /// tick's state.
    fn latch_contact(&mut self, state: &State) {
        let touching = state.stalled || state.bumpers.any();
        if let Some(contact) = self.touched.filter(|_| self.contact.is_none()) {
            if (state.pose.x - contact.at.x).hypot(state.pose.y - contact.at.y) > CLEAR_OF_CONTACT_M {
                tracing::info!("clear of the contact at ({:.2}, {:.2})", contact.at.x, contact.at.y);
                self.touched = None;
            }
        }
        match (&mut self.contact, touching) {
            (latch, true) => {
                if latch.is_none() {
                    tracing::warn!(stalled = state.stalled, bumpers = ?state.bumpers, "contact: holding the robot still");
                    let pushing = if state.bumpers.front {
                        1.0
                    } else if state.bumpers.rear {
                        -1.0
                    } else if self.last_velocity != 0.0 {
                        self.last_velocity.signum()
                    } else {
                        state.velocity.signum()
                    };
                    self.touched = Some(Contact { at: state.pose, pushing });
                }
                *latch = Some(None);
            }
            (Some(clear_since), false) => {
                let since = *clear_since.get_or_insert(state.time);
                if self.policy.resume_after_s.is_some_and(|hold| state.time - since >= hold) {
                    tracing::info!(
                        "contact clear for {:.1} s: motion allowed again, except back into it",
                        state.time - since
                    );
                    self.contact = None;
                }
            }
            (None, false) => {}
        }
    }
}

impl<R: Robot> Wraps for SafetyGuard<R> {
    type Inner = R;
    fn inner(&self) -> &R {
        &self.inner
    }
    fn inner_mut(&mut self) -> &mut R {
        &mut self.inner
    }
}

impl<R: Robot> RobotWrapper for SafetyGuard<R> {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        let started = *self.started.get_or_insert(state.time);
        self.inner.sense(state)?;
        let age = state.sensor_age.min(state.time - started);
        if age > self.policy.link_lost_after_s {
            self.hold = Some(Hold::StaleData);
            return Err(RobotError::from(if state.sensor_age.is_finite() {
                LinkLoss::NoSensorData { for_s: state.sensor_age }
            } else {
                LinkLoss::NoSensorDataYet { within_s: state.time - started }
            }));
        }
        self.pose = state.pose;
        self.latch_contact(state);
        self.hold = if state.sensor_age > self.policy.stale_after_s {
            Some(Hold::StaleData)
        } else if self.contact.is_some() {
            Some(Hold::Contact)
        } else {
            None
        };
        Ok(())
    }

    /// Sends the command unless motion is held; a released contact still
    /// holds motion back into it (the robot may turn, or move away).
    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        if self.hold.is_some() {
            return self.inner.act(&Command::Stop);
        }
        match *command {
            Command::Drive { velocity, turn } if self.touched.is_some_and(|c| c.is_ahead(&self.pose, velocity)) => {
                if self.hold.replace(Hold::Contact).is_none() && self.last_velocity != 0.0 {
                    tracing::warn!("not driving back into the contact at ({:.2}, {:.2})", self.pose.x, self.pose.y);
                }
                self.last_velocity = 0.0;
                self.inner.act(&Command::Drive { velocity: 0.0, turn })
            }
            Command::Drive { velocity, .. } => {
                self.last_velocity = velocity;
                self.inner.act(command)
            }
            Command::Stop => {
                self.last_velocity = 0.0;
                self.inner.act(command)
            }
        }
    }

    /// Why motion is held, as of the latest tick.
    fn hold(&self) -> Option<Hold> {
        self.hold
    }
}

#[cfg(test)]
mod tests {
    // Not `super::*`: with `RobotWrapper` in scope as well as `Robot`, a
    // guard's `sense` would be ambiguous.
    use super::{Hold, SafetyGuard, SafetyPolicy};
    use crate::{Command, LinkLoss, NullRobot, Robot, RobotError, State, Turn, Wraps};

    const GO: Command = Command::Drive { velocity: 0.5, turn: Turn::Rate(0.0) };

    /// One tick at `time` with data `age` seconds old; the command sent.
    fn tick(guard: &mut SafetyGuard<NullRobot>, time: f64, age: f64) -> Result<Command, RobotError> {
        guard.inner_mut().reported.sensor_age = age;
        let mut state = State { time, ..State::default() };
        guard.sense(&mut state)?;
        guard.act(&GO)?;
        Ok(guard.inner().last_command)
    }

    #[test]
    fn no_motion_before_the_first_data_nor_on_stale_data() {
        let mut guard = SafetyGuard::new(NullRobot::default(), SafetyPolicy::default());
        assert_eq!(tick(&mut guard, 0.0, f64::INFINITY).unwrap(), Command::Stop, "before the first data");
        assert_eq!(tick(&mut guard, 0.5, 0.0).unwrap(), GO);
        assert_eq!(tick(&mut guard, 0.6, 0.2).unwrap(), GO, "within the allowance");
        assert_eq!(tick(&mut guard, 0.7, 0.3).unwrap(), Command::Stop, "stale");
        assert_eq!(guard.hold(), Some(Hold::StaleData));
        assert_eq!(tick(&mut guard, 0.8, 0.0).unwrap(), GO, "fresh again");
        let lost = tick(&mut guard, 2.2, 1.31).unwrap_err();
        assert!(matches!(lost, RobotError::Disconnected { reason: LinkLoss::NoSensorData { .. } }), "{lost}");
    }

    #[test]
    fn a_robot_that_never_answers_is_lost_at_the_stated_time() {
        let mut guard = SafetyGuard::new(NullRobot::default(), SafetyPolicy::default());
        assert!(tick(&mut guard, 10.0, f64::INFINITY).is_ok());
        assert!(tick(&mut guard, 11.29, f64::INFINITY).is_ok());
        let never = tick(&mut guard, 11.31, f64::INFINITY).unwrap_err();
        assert!(matches!(never, RobotError::Disconnected { reason: LinkLoss::NoSensorDataYet { .. } }), "{never}");
        assert_eq!(never.to_string(), "robot disconnected: no sensor data in the first 1.31 s");
    }

    #[test]
    fn a_stall_latches_a_stop_until_clear_for_the_hold_time() {
        let mut guard = SafetyGuard::new(NullRobot::default(), SafetyPolicy::default());
        assert_eq!(tick(&mut guard, 0.0, 0.0).unwrap(), GO);
        guard.inner_mut().reported.stalled = true;
        assert_eq!(tick(&mut guard, 0.1, 0.0).unwrap(), Command::Stop);
        // The stall is gone as soon as the wheels stop pushing: still held.
        guard.inner_mut().reported.stalled = false;
        assert_eq!(tick(&mut guard, 0.2, 0.0).unwrap(), Command::Stop);
        assert_eq!(tick(&mut guard, 2.1, 0.0).unwrap(), Command::Stop);
        assert_eq!(guard.hold(), Some(Hold::Contact));
        // Clear for 2 s: released, though not forward, into the contact
        // (see below).
        assert_eq!(tick(&mut guard, 2.2, 0.0).unwrap(), Command::Drive { velocity: 0.0, turn: Turn::Rate(0.0) });
        // A bumper, with no hold time: held for good.
        let forever = SafetyPolicy { resume_after_s: None, ..SafetyPolicy::default() };
        let mut guard = SafetyGuard::new(NullRobot::default(), forever);
        guard.inner_mut().reported.bumpers.front = true;
        assert_eq!(tick(&mut guard, 0.0, 0.0).unwrap(), Command::Stop);
        guard.inner_mut().reported.bumpers.front = false;
        assert_eq!(tick(&mut guard, 1000.0, 0.0).unwrap(), Command::Stop);
    }

    #[test]
    fn a_released_contact_is_not_driven_into_again() {
        let mut guard = SafetyGuard::new(NullRobot::default(), SafetyPolicy::default());
        assert_eq!(tick(&mut guard, 0.0, 0.0).unwrap(), GO);
        guard.inner_mut().reported.stalled = true;
        assert_eq!(tick(&mut guard, 0.1, 0.0).unwrap(), Command::Stop);
        guard.inner_mut().reported.stalled = false;
        assert_eq!(tick(&mut guard, 0.2, 0.0).unwrap(), Command::Stop);
        // Released, but forward is where the wall is: it may only turn.
        let turn_only = Command::Drive { velocity: 0.0, turn: Turn::Rate(0.0) };
        assert_eq!(tick(&mut guard, 2.3, 0.0).unwrap(), turn_only);
        assert_eq!(guard.hold(), Some(Hold::Contact));
        let backing = Command::Drive { velocity: -0.2, turn: Turn::Rate(0.0) };
        let mut state = State { time: 2.35, ..State::default() };
        guard.sense(&mut state).unwrap();
        guard.act(&backing).unwrap();
        assert_eq!(guard.inner().last_command, backing, "backing away is allowed");
        // Turned 90°: forward no longer points at the contact.
        guard.inner_mut().reported.pose.theta = std::f64::consts::FRAC_PI_2;
        assert_eq!(tick(&mut guard, 2.4, 0.0).unwrap(), GO);
        // Turned back, but half a metre away: clear of it.
        guard.inner_mut().reported.pose = crate::Pose2::new(-0.6, 0.0, 0.0);
        assert_eq!(tick(&mut guard, 2.5, 0.0).unwrap(), GO);
    }
}
