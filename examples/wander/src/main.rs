//! A behaviour written in a user's own crate, usable from scenario files by
//! name, with the whole `ubf` command line:
//!
//! ```text
//! cargo run -p ubf-example-wander -- run examples/wander/wander.ron
//! ```

use serde::Deserialize;
use ubf_core::config::positive;
use ubf_core::rand::Rng;
use ubf_core::rand_chacha::ChaCha8Rng;
use ubf_core::{Action, Behavior, BuildContext, Describe, Field, State};

/// Settings of `Wander(..)` in a scenario file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct WanderConfig {
    /// Forward speed, m/s.
    #[serde(deserialize_with = "positive")]
    speed: f64,
    /// Seconds between changes of mind.
    #[serde(default = "default_every", deserialize_with = "positive")]
    every_s: f64,
    /// Largest turn rate chosen, °/s.
    #[serde(default = "default_turn", deserialize_with = "positive")]
    max_turn_deg: f64,
}

/// What `ubf behaviors --describe` prints for `Wander`.
impl Describe for WanderConfig {
    fn fields() -> Vec<Field> {
        vec![
            Field::new("speed", "number", "m/s", "required", "> 0", "forward speed"),
            Field::new("every_s", "number", "s", "2.0", "> 0", "time between changes of mind"),
            Field::new("max_turn_deg", "number", "°/s", "30", "> 0", "largest turn rate chosen"),
        ]
    }
}

fn default_every() -> f64 {
    2.0
}
fn default_turn() -> f64 {
    30.0
}

/// Drives at a steady speed, picking a new random turn rate now and then.
struct Wander {
    config: WanderConfig,
    rng: ChaCha8Rng,
    turn: f64,
    next_change: f64,
}

impl Wander {
    fn new(config: &WanderConfig, ctx: &BuildContext) -> Self {
        // The context's generator is seeded from the run's seed: same seed,
        // same wander.
        Wander { config: config.clone(), rng: ctx.rng(), turn: 0.0, next_change: 0.0 }
    }
}

impl Behavior for Wander {
    fn gen_action(&mut self, state: &State) -> Action {
        if state.time >= self.next_change {
            let max = self.config.max_turn_deg.to_radians();
            self.turn = self.rng.random_range(-max..=max);
            self.next_change = state.time + self.config.every_s;
        }
        Action::with_vote(0.5).velocity(self.config.speed).rot_velocity(self.turn)
    }

    fn name(&self) -> &str {
        "Wander"
    }
}

fn main() -> std::process::ExitCode {
    let mut registry = ubf::registry();
    registry.register("Wander", Wander::new);
    ubf::cli::main_with(registry)
}
