//! # ubf-robots: what the controller can drive
//!
//! - [`sim`]: a headless simulated robot, deterministic for a given seed.
//! - [`model`]: robot types (geometry, limits, sonar) read from RON files.
//! - [`egomotion`]: a wrapper running visual egomotion on any robot.

#![warn(missing_docs)]

pub mod egomotion;
pub mod model;
pub mod sim;
