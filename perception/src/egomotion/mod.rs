//! Egomotion: how the robot moved between two stereo frames, from the
//! landmarks seen in both (thesis §2.3.5, §4.4.6–4.4.9).
//!
//! Two estimators:
//! - [`Simple2d`], the thesis's simplified estimator (§4.4.7): each matched
//!   landmark says "translated by the change in its depth" if its range
//!   changed, else "rotated by the change in its bearing"; the category with
//!   the smallest fused CV wins and its CV-weighted mean is the motion. It
//!   assumes rotate-stop-translate motion.
//! - [`Rigid`], the full estimator the thesis recommends (§5.3.2): the rigid
//!   planar transform (x, y, yaw) that best aligns the two frames'
//!   triangulated landmarks, inside a seeded RANSAC of two-landmark samples
//!   that rejects wrong matches and moving landmarks. Weighted Kabsch
//!   (weights 1/CV, through nalgebra's SVD) gives the first solution;
//!   Gauss–Newton then weighs each landmark by its real, elongated stereo
//!   uncertainty (bearing precise, range not), without which a far wall's
//!   depth noise tilts the solution into metres of false sideways motion.
//!   It needs three consistent landmarks; two with odometry fused in
//!   (`Tracker` decides, from the settings). With `Sideways` fusion one
//!   landmark alone still fixes the turn against odometry's position
//!   (`one_landmark`).
//!
//! The files, by job: `config` (the settings a scenario file gives),
//! `matching` (which landmarks of two frames are the same), `step` (what
//! the estimators share), `simple2d` and `rigid` (the estimators),
//! `odometry` (the odometry gate and fusion), `one_landmark` (a step on
//! one landmark and odometry), `wheel_calibration` (the
//! wheels' scale and veer the steps measure) and `tracker` (the keyframe
//! bank that integrates the steps over a run).

mod config;
mod matching;
mod odometry;
mod offset;
mod one_landmark;
mod rigid;
mod simple2d;
mod step;
mod tracker;
mod wheel_calibration;

pub use config::{DisparityOffsetEstimate, EgomotionConfig, EstimatorKind, RigidConfig, Simple2dConfig};
pub use matching::{match_frames, MatchConfig};
pub use odometry::{OdometryFusion, OdometryGate, OdometryNoise};
pub use rigid::Rigid;
pub use simple2d::Simple2d;
pub use step::{MotionPhase, PlanarMotion};
pub use tracker::{OffsetEstimate, Tracker};
pub use wheel_calibration::{Veer, WheelScale};

#[cfg(test)]
mod testing;
