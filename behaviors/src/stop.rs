//! Stop while a condition holds.

use serde::Deserialize;
use ubf_core::config::non_negative;
use ubf_core::{Action, Behavior, Condition, State};

/// Settings of [`Stop`], as written in a scenario file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StopConfig {
    /// When to stop. By default: at the goal, on a bumper, on a stall, on an
    /// emergency stop, or when sensor data is older than half a second.
    #[serde(deserialize_with = "ubf_core::config::checked")]
    pub when: Condition,
    /// The vote of the stop request.
    #[serde(deserialize_with = "non_negative")]
    pub vote: f64,
}

impl Default for StopConfig {
    fn default() -> Self {
        StopConfig {
            when: Condition::Any(vec![
                Condition::GoalReached,
                Condition::Bumped,
                Condition::Stalled,
                Condition::EStop,
                Condition::SensorsOlderThan { seconds: 0.5 },
            ]),
            vote: 1.0,
        }
    }
}

/// Requests a stop while its condition holds; silent otherwise. A stop from
/// any voting child wins every arbiter, so one `Stop` anywhere in a tree is
/// enough.
#[derive(Clone, Debug)]
pub struct Stop {
    config: StopConfig,
}

impl Stop {
    /// A stop behaviour with these settings.
    pub fn new(config: StopConfig) -> Self {
        Stop { config }
    }
}

impl Behavior for Stop {
    fn gen_action(&mut self, state: &State) -> Action {
        if self.config.when.holds(state) {
            Action::stop(self.config.vote)
        } else {
            Action::none()
        }
    }

    fn name(&self) -> &str {
        "Stop"
    }
}

impl ubf_core::Describe for StopConfig {
    fn fields() -> Vec<ubf_core::Field> {
        use ubf_core::Field;
        vec![
            Field::new(
                "when",
                "condition",
                "",
                "Any([GoalReached, Bumped, Stalled, EStop, SensorsOlderThan(seconds: 0.5)])",
                "",
                "the [condition](arbiters.md#conditions) under which it asks for a stop",
            ),
            Field::new("vote", "number", "", "1.0", "≥ 0", "vote of the stop request"),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ubf_core::Bumpers;

    #[test]
    fn default_stops_on_bumper_and_stale_sensors_only() {
        let mut stop = Stop::new(StopConfig::default());
        let mut state = State::default();
        assert!(!stop.gen_action(&state).is_voting());
        state.bumpers = Bumpers { front: true, rear: false };
        assert!(stop.gen_action(&state).stop);
        state.bumpers = Bumpers::default();
        state.sensor_age = 0.6;
        assert!(stop.gen_action(&state).stop);
    }
}
