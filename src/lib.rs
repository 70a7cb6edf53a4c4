//! # ubf: run behaviour trees on simulated and real robots
//!
//! This package turns scenario files into running controllers and reports:
//!
//! - [`registry`]: every stock behaviour, ready for a user's own additions;
//! - [`scenario`]: the scenario file format and its loader, whose errors
//!   name the file, line and column;
//! - [`run`]: a scenario run headless on the simulator;
//! - [`sweep`]: many runs in parallel, summarised;
//! - [`experiment`]: the thesis's experiments;
//! - [`cost_fit`]: egomotion's error coefficients, fitted from run logs;
//! - [`cost_forms`]: whether another form of that model predicts better;
//! - [`environment_map`]: where action aiding beats driving straight;
//! - [`cli`]: the `ubf` command line, which a user's crate can reuse with its
//!   own registry so that its behaviours work from scenario files by name.

#![warn(missing_docs)]

pub mod cli;
pub mod cost_fit;
pub mod cost_forms;
pub mod drive;
pub mod environment_map;
pub mod experiment;
pub mod frames;
pub mod mcap_log;
pub mod plot;
pub mod ros2_log;
pub mod ros2_publish;
pub mod ros2_view;
pub mod run;
pub mod scenario;
pub mod sweep;
pub mod trajectory;
pub mod tree;

pub use ubf_core::Registry;

/// A registry holding `Composite` and every stock behaviour.
pub fn registry() -> Registry {
    let mut registry = Registry::new();
    ubf_behaviors::register(&mut registry);
    registry
}
