//! # ubf-session: a behaviour tree driving a robot, and what it leaves
//!
//! One session loop ([`ubf_core::Session`]) serves every use; this crate
//! gives it its robots' files and its sinks:
//!
//! - [`scenario`]: the scenario file format and its loader, whose errors
//!   name the file, line and column; [`run`]: a scenario run headless on
//!   the simulator, and its [`report`];
//! - [`sweep`]: many runs in parallel, summarised, written through
//!   [`atomic`] so that a stopped sweep leaves no half-written file;
//! - [`frames`]: rendered stereo pairs recorded, and recordings replayed
//!   through the feature pipeline;
//! - [`drive`]: a robot file driving a real robot (ARCOS or ROS 2);
//! - [`simulate`]: the simulator served as a ROS 2 robot;
//! - the sinks: [`trajectory`] (CSV), [`mcap_log`] (JSON MCAP for
//!   Foxglove, read back by [`replay`]) and [`live`] (the same topics,
//!   [`json_topics`], served live to Foxglove), [`ros2_log`] (rosbag2),
//!   [`ros2_publish`] (live ROS 2, through [`ros2_view`]); [`plot`] draws a
//!   run;
//! - [`tree`]: a tree as a picture; [`watch`]: a tree edited while it
//!   runs (`--watch`).

#![warn(missing_docs)]

/// Says a line on stderr, as `eprintln!` does, but without panicking when
/// stderr cannot be written (a pipe whose reader went away): a drive must
/// still stop its robot, exit on a second interrupt and end with its own
/// status when its operator's output is gone. A sink that must notice
/// writes with `write!` and returns the error instead.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {{
        use ::std::io::Write as _;
        let _ = ::std::writeln!(::std::io::stderr(), $($arg)*);
    }};
}

pub mod atomic;
pub mod drive;
pub mod frames;
pub mod json_topics;
pub mod live;
pub mod mcap_log;
pub mod plot;
pub mod replay;
pub mod report;
pub mod ros2_log;
pub mod ros2_publish;
pub mod ros2_view;
pub mod run;
pub mod scenario;
pub mod sealed_file;
pub mod simulate;
pub mod sweep;
pub mod trajectory;
pub mod tree;
pub mod watch;

pub use ubf_core::Registry;

/// A registry holding `Composite` and every stock behaviour.
pub fn registry() -> Registry {
    let mut registry = Registry::new();
    ubf_behaviors::register(&mut registry);
    registry
}
