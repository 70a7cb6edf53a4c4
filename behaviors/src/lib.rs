//! # ubf-behaviors: the stock behaviours
//!
//! | name in a file | behaviour |
//! | --- | --- |
//! | `GoTo` | [`GoTo`]: drive to the state's goal, or to a waypoint once |
//! | `Stop` | [`Stop`]: stop while a condition holds |
//! | `AvoidCollision` | [`AvoidCollision`]: keep clear of what the sonar sees |
//! | `ActionAiding` | [`ActionAiding`]: steer for the least uncertain egomotion (thesis ch. 3) |
//! | `InjectFault` | [`InjectFault`]: panic on purpose, to rehearse a failing behaviour |
//! | `SweepCamera` | [`SweepCamera`]: sweep a camera on a pan-tilt unit from side to side |
//!
//! [`register`] adds them all to a [`Registry`].

#![warn(missing_docs)]

mod action_aiding;
mod avoid;
pub mod clearance;
pub mod decision;
mod fault;
mod go_to;
mod stop;
mod sweep_camera;
pub mod tracking;

pub use action_aiding::{ActionAiding, ActionAidingConfig, DecisionObjective, PredictionCheck, Steer, Technique};
pub use avoid::{AvoidCollision, AvoidCollisionConfig};
pub use fault::{InjectFault, InjectFaultConfig};
pub use go_to::{GoTo, GoToConfig};
pub use stop::{Stop, StopConfig};
pub use sweep_camera::{SweepCamera, SweepCameraConfig};

use ubf_core::config::Checked;
use ubf_core::Registry;

/// Registers every stock behaviour under its file name.
pub fn register(registry: &mut Registry) -> &mut Registry {
    registry
        .register("GoTo", |c: &GoToConfig, _| GoTo::new(c.clone()))
        .register("Stop", |c: &StopConfig, _| Stop::new(c.clone()))
        .register("AvoidCollision", |c: &Checked<AvoidCollisionConfig>, _| AvoidCollision::new(c.0.clone()))
        .register("ActionAiding", |c: &ActionAidingConfig, ctx| ActionAiding::new(c.clone(), ctx))
        .register("InjectFault", |c: &InjectFaultConfig, _| InjectFault::new(c.clone()))
        .register("SweepCamera", |c: &SweepCameraConfig, _| SweepCamera::new(c.clone()))
}
