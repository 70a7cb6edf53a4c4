//! Named predicates on the state, for the Conditional arbiter and the Stop
//! behaviour.

use crate::State;
use serde::{Deserialize, Serialize};

/// A predicate on the [`State`], as written in a scenario file:
/// `Any([Bumped, Stalled, ObstacleWithin(range: 0.3)])`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Condition {
    /// Always true.
    Always,
    /// Any bumper segment is pressed.
    Bumped,
    /// A drive wheel is stalled.
    Stalled,
    /// The emergency stop is engaged.
    EStop,
    /// The estimated pose is within the goal's tolerance.
    GoalReached,
    /// Some range sensor reports an echo closer than `range` metres.
    ObstacleWithin {
        /// Metres.
        range: f64,
    },
    /// The sensor data is older than `seconds` (a lost sensor stream).
    SensorsOlderThan {
        /// Seconds.
        seconds: f64,
    },
    /// The inner condition does not hold.
    Not(Box<Condition>),
    /// At least one of the conditions holds.
    Any(Vec<Condition>),
    /// Every condition holds.
    All(Vec<Condition>),
}

impl Condition {
    /// Whether the condition holds in `state`.
    pub fn holds(&self, state: &State) -> bool {
        match self {
            Condition::Always => true,
            Condition::Bumped => state.bumpers.any(),
            Condition::Stalled => state.stalled,
            Condition::EStop => state.estop,
            Condition::GoalReached => state.goal_reached(),
            Condition::ObstacleWithin { range } => state.nearest_range().is_some_and(|r| r < *range),
            Condition::SensorsOlderThan { seconds } => state.sensor_age > *seconds,
            Condition::Not(inner) => !inner.holds(state),
            Condition::Any(all) => all.iter().any(|c| c.holds(state)),
            Condition::All(all) => all.iter().all(|c| c.holds(state)),
        }
    }
}

impl crate::config::Check for Condition {
    /// Distances and times must be finite and non-negative.
    fn check(&self) -> Result<(), String> {
        match self {
            Condition::ObstacleWithin { range: v } | Condition::SensorsOlderThan { seconds: v }
                if !(v.is_finite() && *v >= 0.0) =>
            {
                Err(format!("condition {self:?}: the number must be finite and ≥ 0"))
            }
            Condition::Not(inner) => inner.check(),
            Condition::Any(all) | Condition::All(all) => all.iter().try_for_each(Condition::check),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Check;
    use crate::{Bumpers, Goal, RangeReading};

    #[test]
    fn combinators() {
        let mut state = State::default();
        let c = Condition::Any(vec![Condition::Bumped, Condition::ObstacleWithin { range: 0.5 }]);
        assert!(!c.holds(&state));
        state.ranges.push(RangeReading { range: Some(0.4), max_range: 5.0, ..RangeReading::default() });
        assert!(c.holds(&state));
        state.ranges.clear();
        state.bumpers = Bumpers { front: false, rear: true };
        assert!(c.holds(&state));
        assert!(!Condition::Not(Box::new(c)).holds(&state));
        state.goal = Some(Goal { x: 0.1, y: 0.0, tolerance: 0.2 });
        assert!(Condition::All(vec![Condition::GoalReached, Condition::Bumped]).holds(&state));
    }

    #[test]
    fn check_rejects_negative_and_nan() {
        assert!(Condition::ObstacleWithin { range: -1.0 }.check().is_err());
        assert!(Condition::Not(Box::new(Condition::SensorsOlderThan { seconds: f64::NAN })).check().is_err());
        assert!(Condition::Any(vec![Condition::ObstacleWithin { range: 0.3 }]).check().is_ok());
    }
}
