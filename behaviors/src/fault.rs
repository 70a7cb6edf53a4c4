//! A behaviour that fails on purpose, for rehearsing what a failing
//! behaviour does to the robot before one fails for real: the controller
//! catches the panic, names the behaviour's path, stops the robot and ends
//! the run with its report (or carries on without it, if so configured).

use serde::Deserialize;
use ubf_core::config::non_negative;
use ubf_core::{Action, Behavior, State};

/// Settings of [`InjectFault`], as written in a scenario or robot file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InjectFaultConfig {
    /// Panic once the controller's clock reaches this many seconds.
    #[serde(deserialize_with = "non_negative")]
    pub after_s: f64,
    /// The panic's message.
    #[serde(default = "InjectFaultConfig::default_message")]
    pub message: String,
}

impl InjectFaultConfig {
    fn default_message() -> String {
        "injected fault".into()
    }
}

/// Silent until `after_s`, then panics every time it is asked.
#[derive(Clone, Debug)]
pub struct InjectFault {
    config: InjectFaultConfig,
}

impl InjectFault {
    /// A fault with these settings.
    pub fn new(config: InjectFaultConfig) -> Self {
        InjectFault { config }
    }
}

impl Behavior for InjectFault {
    fn gen_action(&mut self, state: &State) -> Action {
        if state.time >= self.config.after_s {
            panic!("{}", self.config.message);
        }
        Action::none()
    }

    fn name(&self) -> &str {
        "InjectFault"
    }
}

impl ubf_core::Describe for InjectFaultConfig {
    fn fields() -> Vec<ubf_core::Field> {
        use ubf_core::Field;
        vec![
            Field::new("after_s", "number", "s", "required", "≥ 0", "when it starts to panic"),
            Field::new("message", "text", "", "\"injected fault\"", "", "the panic's message"),
        ]
    }
}
