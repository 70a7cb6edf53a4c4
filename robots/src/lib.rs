//! # ubf-robots: what the controller can drive
//!
//! - [`sim`]: a headless simulated robot, deterministic for a given seed.
//! - [`model`]: robot types (geometry, limits, sonar) read from RON files.
//! - [`egomotion`]: a wrapper running visual egomotion on any robot.
//! - [`arcos`]: the Pioneer/Powerbot controller protocol.

#![warn(missing_docs)]

pub mod arcos;
pub mod egomotion;
pub mod model;
pub mod sim;
