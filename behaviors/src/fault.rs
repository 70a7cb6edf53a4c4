//! A behaviour that fails on purpose, for rehearsing what a failing
//! behaviour does to the robot before one fails for real: the controller
//! catches the panic, names the behaviour's path, stops the robot and ends
//! the run with its report (or carries on without it, if so configured).
//! Or it first hangs for a while, as a behaviour stuck in a loop would,
//! which no controller can catch: that rehearses what stops the robot from
//! outside the loop (Ctrl-C or SIGTERM, the service's watchdog).

use serde::Deserialize;
use ubf_core::config::{non_negative, number_in};
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
    /// Before the first panic, hang for this long, s (wall clock): the
    /// control loop stalls.
    #[serde(default, deserialize_with = "hang_s")]
    pub hang_s: f64,
}

/// A hang, s: from 0 to 600 (long enough for any watchdog; a hang without
/// end would leave a headless run to hang too).
fn hang_s<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_in(d, 0.0..=600.0, "from 0 to 600 s")
}

impl InjectFaultConfig {
    fn default_message() -> String {
        "injected fault".into()
    }
}

/// Silent until `after_s`, then panics every time it is asked, the first
/// time after hanging for `hang_s`.
#[derive(Clone, Debug)]
pub struct InjectFault {
    config: InjectFaultConfig,
    hung: bool,
}

impl InjectFault {
    /// A fault with these settings.
    pub fn new(config: InjectFaultConfig) -> Self {
        InjectFault { config, hung: false }
    }
}

impl Behavior for InjectFault {
    fn gen_action(&mut self, state: &State) -> Action {
        if state.time >= self.config.after_s {
            if !self.hung {
                self.hung = true;
                std::thread::sleep(std::time::Duration::from_secs_f64(self.config.hang_s));
            }
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
            Field::new(
                "hang_s",
                "number",
                "s",
                "0.0",
                "0 to 600",
                "before the first panic, hang this long: the loop stalls",
            ),
        ]
    }
}
