//! What a behaviour wants, channel by channel, and how much it wants it.

/// The command channels of an [`Action`]. Every channel is optional: `None`
/// means "no opinion on this channel", which is not the same as `Some(0.0)`
/// ("hold this at zero").
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Motion {
    /// Forward velocity, m/s (negative drives backwards).
    pub velocity: Option<f64>,
    /// Rotational velocity, rad/s, counter-clockwise positive.
    pub rot_velocity: Option<f64>,
    /// Absolute heading to turn to, radians in the world frame of
    /// [`crate::State::pose`]. Where set, it takes precedence over
    /// `rot_velocity` when the action becomes a command.
    pub heading: Option<f64>,
    /// Limit: the largest forward speed allowed, m/s. Limits from several
    /// behaviours combine "most restrictive wins".
    pub max_velocity: Option<f64>,
    /// Limit: the largest rotational speed allowed, rad/s.
    pub max_rot_velocity: Option<f64>,
    /// Where to point a camera on a pan-tilt unit, radians counter-clockwise
    /// from the robot's heading. Robots with a fixed camera ignore it.
    pub camera_pan: Option<f64>,
}

/// One fusable command channel of a [`Motion`]. Limits are not channels: they
/// are never averaged, only combined by taking the minimum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    /// [`Motion::velocity`].
    Velocity,
    /// [`Motion::rot_velocity`].
    RotVelocity,
    /// [`Motion::heading`].
    Heading,
    /// [`Motion::camera_pan`].
    CameraPan,
}

impl Channel {
    /// Every command channel, in a fixed order.
    pub const ALL: [Channel; 4] = [Channel::Velocity, Channel::RotVelocity, Channel::Heading, Channel::CameraPan];

    /// Whether the channel is a direction, to be combined on the circle.
    pub fn is_direction(self) -> bool {
        matches!(self, Channel::Heading | Channel::CameraPan)
    }
}

impl Motion {
    /// The value of one channel.
    pub fn get(&self, channel: Channel) -> Option<f64> {
        match channel {
            Channel::Velocity => self.velocity,
            Channel::RotVelocity => self.rot_velocity,
            Channel::Heading => self.heading,
            Channel::CameraPan => self.camera_pan,
        }
    }

    /// Sets one channel.
    pub fn set(&mut self, channel: Channel, value: Option<f64>) {
        match channel {
            Channel::Velocity => self.velocity = value,
            Channel::RotVelocity => self.rot_velocity = value,
            Channel::Heading => self.heading = value,
            Channel::CameraPan => self.camera_pan = value,
        }
    }

    /// Tightens this motion's limits with another's: the minimum of the
    /// limits that are set.
    pub fn restrict_to(&mut self, other: &Motion) {
        self.max_velocity = min_limit(self.max_velocity, other.max_velocity);
        self.max_rot_velocity = min_limit(self.max_rot_velocity, other.max_rot_velocity);
    }
}

fn min_limit(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, None) => a,
        (None, b) => b,
    }
}

/// What a behaviour wants this tick: motion channels, a stop request, and a
/// vote (≥ 0) saying how much it wants them.
///
/// A vote of zero means "no opinion": arbiters ignore such an action, whatever
/// its channels say. A vote that is negative or not a number also counts as
/// no opinion.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Action {
    /// How strongly the behaviour wants this action, ≥ 0.
    pub vote: f64,
    /// The requested channels.
    pub motion: Motion,
    /// A request to stop now. A stop from any voting child wins arbitration.
    pub stop: bool,
}

impl Action {
    /// "No opinion": vote 0, nothing set.
    pub const fn none() -> Self {
        Action {
            vote: 0.0,
            motion: Motion {
                velocity: None,
                rot_velocity: None,
                heading: None,
                max_velocity: None,
                max_rot_velocity: None,
                camera_pan: None,
            },
            stop: false,
        }
    }

    /// An action with the given vote and no channel set yet; chain the
    /// setters: `Action::with_vote(1.0).velocity(0.3).rot_velocity(0.0)`.
    pub const fn with_vote(vote: f64) -> Self {
        let mut action = Action::none();
        action.vote = vote;
        action
    }

    /// A stop request with the given vote.
    pub const fn stop(vote: f64) -> Self {
        let mut action = Action::with_vote(vote);
        action.stop = true;
        action
    }

    /// Whether arbiters should take this action into account: its vote is a
    /// positive number.
    pub fn is_voting(&self) -> bool {
        self.vote > 0.0 && self.vote.is_finite()
    }

    /// The vote if the action is voting, else 0.
    pub fn effective_vote(&self) -> f64 {
        if self.is_voting() {
            self.vote
        } else {
            0.0
        }
    }

    /// Sets the forward velocity, m/s.
    pub const fn velocity(mut self, velocity: f64) -> Self {
        self.motion.velocity = Some(velocity);
        self
    }

    /// Sets the rotational velocity, rad/s.
    pub const fn rot_velocity(mut self, rot_velocity: f64) -> Self {
        self.motion.rot_velocity = Some(rot_velocity);
        self
    }

    /// Sets the absolute heading, rad.
    pub const fn heading(mut self, heading: f64) -> Self {
        self.motion.heading = Some(heading);
        self
    }

    /// Sets where to point the camera, rad from the heading.
    pub const fn camera_pan(mut self, pan: f64) -> Self {
        self.motion.camera_pan = Some(pan);
        self
    }

    /// Sets the forward speed limit, m/s.
    pub const fn max_velocity(mut self, limit: f64) -> Self {
        self.motion.max_velocity = Some(limit);
        self
    }

    /// Sets the rotational speed limit, rad/s.
    pub const fn max_rot_velocity(mut self, limit: f64) -> Self {
        self.motion.max_rot_velocity = Some(limit);
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_is_not_unset() {
        let a = Action::with_vote(1.0).velocity(0.0);
        assert_eq!(a.motion.velocity, Some(0.0));
        assert_eq!(a.motion.rot_velocity, None);
    }

    #[test]
    fn bad_votes_do_not_vote() {
        for vote in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(!Action::with_vote(vote).is_voting(), "{vote}");
        }
        assert!(Action::with_vote(0.1).is_voting());
    }

    #[test]
    fn limits_take_the_minimum_of_those_set() {
        let mut m = Motion { max_velocity: Some(0.5), ..Motion::default() };
        m.restrict_to(&Motion { max_velocity: Some(0.2), max_rot_velocity: Some(1.0), ..Motion::default() });
        assert_eq!(m.max_velocity, Some(0.2));
        assert_eq!(m.max_rot_velocity, Some(1.0));
        m.restrict_to(&Motion::default());
        assert_eq!(m.max_velocity, Some(0.2));
    }
}
