//! # ubf-robots: what the controller can drive
//!
//! - [`sim`]: a headless simulated robot, deterministic for a given seed.

#![warn(missing_docs)]

pub mod sim;
