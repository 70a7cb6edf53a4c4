//! The progress watch: how a phase of the behaviour notices that it is
//! getting nowhere.

/// Watches a phase for progress: the angle still to turn, or the share of
/// a step still to drive (a step counting as a radian). Beside another
/// behaviour that turns the other way (AvoidCollision facing a wall, say), a
/// command fusion can cancel a turn and leave the robot sitting still, and a
/// robot that turns on the spot before it translates can spend a whole step
/// turning to and fro between the two; a phase that gains less than a
/// degree (or a 57th of a step) in `STUCK_S` is stuck.
#[derive(Clone, Copy, Debug)]
pub(super) struct ProgressWatch {
    since: f64,
    best: f64,
    /// Going the long way round, after the short way stuck: the direction
    /// (+1 counter-clockwise), fixed when chosen. Recomputing it from the
    /// heading error each tick would flip it where the error wraps past
    /// ±180°, and the robot would rock there instead of turning.
    pub(super) long_way: Option<f64>,
}

/// Seconds without a degree of progress after which a phase is stuck.
pub(super) const STUCK_S: f64 = 5.0;

impl ProgressWatch {
    pub(super) fn new() -> Self {
        ProgressWatch { since: f64::NEG_INFINITY, best: f64::INFINITY, long_way: None }
    }

    /// Takes in the progress still to make at `now` (the angle still to
    /// turn, or the share of a step still to drive); whether the phase is
    /// stuck.
    pub(super) fn stuck(&mut self, now: f64, remaining: f64) -> bool {
        if remaining < self.best - 1f64.to_radians() || !self.since.is_finite() {
            self.best = remaining;
            self.since = now;
            return false;
        }
        if now - self.since > STUCK_S {
            self.since = now;
            self.best = f64::INFINITY;
            return true;
        }
        false
    }

    /// The angle still to turn to close a heading `error`: the short way,
    /// or on round the long way once that was chosen.
    pub(super) fn angle_left(&self, error: f64) -> f64 {
        match self.long_way {
            Some(direction) => (direction * error).rem_euclid(std::f64::consts::TAU),
            None => error.abs(),
        }
    }

    /// The rotation rate while going the long way round: full rate until
    /// the heading is the short way on in the same direction; `None` then,
    /// or when going the short way.
    pub(super) fn long_way_rate(&self, error: f64, max: f64) -> Option<f64> {
        self.long_way.filter(|direction| direction * error <= 0.0).map(|direction| direction * max)
    }
}
