//! `my-behaviours`: ubf's command line with this crate's behaviours registered, so
//! scenario files can use them by name:
//!
//! ```text
//! cargo run -- run my-behaviours.ron
//! cargo run -- behaviors --describe Cruise
//! ```

use serde::Deserialize;
use ubf_core::config::positive;
use ubf_core::{Action, Behavior, BuildContext, Describe, Field, State};

/// Settings of `Cruise(..)` in a scenario file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CruiseConfig {
    /// Forward speed in the open, m/s.
    #[serde(deserialize_with = "positive")]
    speed: f64,
    /// Below this range to anything ahead the speed falls linearly, to zero
    /// at `HALT_M`, m.
    #[serde(default = "default_clearance", deserialize_with = "positive")]
    clearance_m: f64,
}

fn default_clearance() -> f64 {
    1.5
}

/// What `ubf behaviors --describe Cruise` prints.
impl Describe for CruiseConfig {
    fn fields() -> Vec<Field> {
        vec![
            Field::new("speed", "number", "m/s", "required", "> 0", "forward speed in the open"),
            Field::new("clearance_m", "number", "m", "1.5", "> 0", "range below which it slows, to a halt 0.5 m short"),
        ]
    }
}

/// What Cruise leaves between the robot and anything ahead, m.
const HALT_M: f64 = 0.5;

/// Drives straight ahead, slowing as anything ahead comes closer.
struct Cruise {
    config: CruiseConfig,
}

impl Cruise {
    fn new(config: &CruiseConfig, _ctx: &BuildContext) -> Self {
        Cruise { config: config.clone() }
    }
}

impl Behavior for Cruise {
    fn gen_action(&mut self, state: &State) -> Action {
        // The nearest echo of the sonars facing within 30° of straight ahead
        // (those to the sides see walls it will only drive past).
        let room = state
            .ranges
            .iter()
            .filter(|r| r.pose_robot_sensor.theta.abs() < 30f64.to_radians())
            .filter_map(|r| r.range)
            .fold(f64::INFINITY, f64::min);
        let speed = self.config.speed * ((room - HALT_M) / self.config.clearance_m).clamp(0.0, 1.0);
        Action::with_vote(0.5).velocity(speed)
    }

    fn name(&self) -> &str {
        "Cruise"
    }
}

fn main() -> std::process::ExitCode {
    let mut registry = ubf::registry();
    registry.register("Cruise", Cruise::new);
    ubf::cli::main_with(registry)
}
