//! # ubf-perception: what stereo vision tells the robot
//!
//! - [`stereo`]: the stereo camera: projection, triangulation (thesis eq.
//!   12–14), frames and mounting.
//!
//! Shared by the simulated and the real robot, so that both feed the same
//! landmark observations to the behaviours.

#![warn(missing_docs)]

pub mod stereo;

pub use stereo::{CameraMount, StereoCamera};
