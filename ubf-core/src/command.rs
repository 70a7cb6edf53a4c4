//! Commands: what the robot is told to do, after limits.

use crate::Action;
use serde::{Deserialize, Serialize};

/// How a drive command turns.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Turn {
    /// Turn at this rate, rad/s, counter-clockwise positive.
    Rate(f64),
    /// Turn to this absolute heading (rad, the frame of the state's pose),
    /// at no more than `max_rate` rad/s.
    Heading {
        /// Target heading, rad.
        heading: f64,
        /// Largest turn rate allowed, rad/s.
        max_rate: f64,
    },
}

/// A command for a [`crate::Robot`]: every value already within limits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum Command {
    /// Stop now.
    #[default]
    Stop,
    /// Drive at a forward velocity while turning.
    Drive {
        /// Forward velocity, m/s.
        velocity: f64,
        /// How to turn.
        turn: Turn,
    },
}

/// The robot's own speed limits, which every command respects.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Limits {
    /// Largest forward speed, m/s.
    pub max_velocity: f64,
    /// Largest rotational speed, rad/s.
    pub max_rot_velocity: f64,
}

impl Limits {
    /// Limits of `max_velocity` m/s and `max_rot_velocity` rad/s.
    pub const fn new(max_velocity: f64, max_rot_velocity: f64) -> Self {
        Limits { max_velocity, max_rot_velocity }
    }
}

/// A limit as the most restrictive of the robot's and the action's; a
/// negative limit means "do not move on this axis", a NaN one is ignored.
fn effective_limit(robot: f64, action: Option<f64>) -> f64 {
    let limit = match action {
        Some(l) if !l.is_nan() => robot.min(l),
        _ => robot,
    };
    limit.max(0.0)
}

fn clamp_finite(value: Option<f64>, limit: f64) -> f64 {
    match value {
        Some(v) if v.is_finite() => v.clamp(-limit, limit),
        _ => 0.0,
    }
}

impl Command {
    /// Turns the root behaviour's action into a command.
    ///
    /// Nobody voting, or a stop request, gives [`Command::Stop`]: a robot
    /// with no opinion to follow stands still. Unset velocity channels mean
    /// zero; a heading, where set, is preferred over a turn rate.
    pub fn from_action(action: &Action, limits: &Limits) -> Command {
        if action.stop || !action.is_voting() {
            return Command::Stop;
        }
        let motion = &action.motion;
        let max_velocity = effective_limit(limits.max_velocity, motion.max_velocity);
        let max_rate = effective_limit(limits.max_rot_velocity, motion.max_rot_velocity);
        let velocity = clamp_finite(motion.velocity, max_velocity);
        let turn = match motion.heading.filter(|h| h.is_finite()) {
            Some(heading) => Turn::Heading { heading, max_rate },
            None => Turn::Rate(clamp_finite(motion.rot_velocity, max_rate)),
        };
        Command::Drive { velocity, turn }
    }

    /// The forward velocity commanded, m/s (0 for a stop).
    pub fn velocity(&self) -> f64 {
        match self {
            Command::Stop => 0.0,
            Command::Drive { velocity, .. } => *velocity,
        }
    }

    /// The turn rate commanded, rad/s (0 for a stop); `None` for a heading
    /// command, whose rate the robot chooses.
    pub fn rot_velocity(&self) -> Option<f64> {
        match self {
            Command::Stop => Some(0.0),
            Command::Drive { turn: Turn::Rate(rate), .. } => Some(*rate),
            Command::Drive { turn: Turn::Heading { .. }, .. } => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: Limits = Limits::new(1.0, 2.0);

    #[test]
    fn silence_and_stop_requests_stop() {
        assert_eq!(Command::from_action(&Action::none(), &LIMITS), Command::Stop);
        assert_eq!(Command::from_action(&Action::stop(1.0).velocity(1.0), &LIMITS), Command::Stop);
    }

    #[test]
    fn limits_clamp_and_the_tighter_one_wins() {
        let a = Action::with_vote(1.0).velocity(5.0).rot_velocity(-5.0).max_velocity(0.3);
        assert_eq!(Command::from_action(&a, &LIMITS), Command::Drive { velocity: 0.3, turn: Turn::Rate(-2.0) });
    }

    #[test]
    fn heading_wins_over_rate_and_nan_is_zero() {
        let a = Action::with_vote(1.0).velocity(f64::NAN).rot_velocity(1.0).heading(0.5);
        assert_eq!(
            Command::from_action(&a, &LIMITS),
            Command::Drive { velocity: 0.0, turn: Turn::Heading { heading: 0.5, max_rate: 2.0 } }
        );
    }

    #[test]
    fn negative_limit_freezes_the_axis() {
        let a = Action::with_vote(1.0).velocity(0.5).max_velocity(-1.0);
        assert_eq!(Command::from_action(&a, &LIMITS).velocity(), 0.0);
    }
}
