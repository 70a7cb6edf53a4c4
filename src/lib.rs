//! # ubf: the command line of the Unified Behavior Framework
//!
//! [`cli`] is the `ubf` command; a user's crate can reuse it with its own
//! registry so that its behaviours work from scenario files by name. The
//! sessions it runs (runs, sweeps, drives, their logs) are
//! [`ubf_session`]'s, re-exported here; the research commands (`ubf
//! experiment`, `ubf model`) call into [`ubf_lab`].

#![warn(missing_docs)]

pub mod cli;

pub use ubf_core::Registry;
pub use ubf_session::{
    drive, frames, json_topics, live, mcap_log, plot, registry, replay, report, ros2_log, ros2_publish, ros2_view, run,
    scenario, sweep, trajectory, tree, watch,
};
