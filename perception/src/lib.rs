//! # ubf-perception: what stereo vision tells the robot
//!
//! - [`stereo`]: the stereo camera: projection, triangulation (thesis eq.
//!   12–14), frames and mounting.
//! - [`error_model`]: the landmark egomotion error model (eq. 16–24), its
//!   fit and its look-up table.
//! - [`fusion`]: combining CVs (eq. 5–7).
//! - [`egomotion`]: frame matching and the two egomotion estimators.
//! - [`features`]: landmarks from a pair of real images: corners,
//!   descriptors, stereo matching, triangulation.
//! - [`perturb`]: misalignment, blur and low contrast applied to stereo
//!   pairs, to test the pipeline on what real cameras do.
//! - [`source`]: where stereo pairs come from: a directory of images, the
//!   simulator's renderer, and with the `v4l` feature two Video4Linux
//!   cameras (`v4l_source`).
//!
//! Shared by the simulated and the real robot, so that both feed the same
//! landmark observations to the behaviours.

#![warn(missing_docs)]

pub mod egomotion;
pub mod error_model;
pub mod features;
pub mod fusion;
pub mod kitti;
pub mod perturb;
pub mod rectify;
pub mod source;
/// The stereo camera's geometry, which lives in `ubf-core` (frames carry
/// the camera that took them).
pub use ubf_core::stereo;
#[cfg(feature = "v4l")]
pub mod v4l_source;

/// The median of `values` (the upper of the middle two for an even count),
/// sorting them in place; NaN for none.
pub fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

pub use stereo::{CameraMount, PrincipalPoint, StereoCamera};
