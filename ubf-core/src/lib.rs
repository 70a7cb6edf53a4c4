//! # ubf-core: the Unified Behavior Framework
//!
//! Behaviours look at the robot's [`State`] and answer with an [`Action`]: the
//! command channels they want (each optional) and a vote saying how much.
//! A [`Composite`] asks its children and lets an [`Arbiter`] combine their
//! actions; a composite is itself a behaviour, so trees nest to any depth. A
//! [`Controller`] runs the tree against a [`Robot`] once per tick of its
//! [`Clock`], and every tick leaves a [`TickRecord`].
//!
//! A complete behaviour, registered by name and driven from RON:
//!
//! ```
//! use serde::Deserialize;
//! use ubf_core::{Action, Behavior, BehaviorSpec, BuildContext, Describe, Field, Registry, State};
//!
//! /// Drives forward, turning away from anything closer than `clearance`.
//! struct Shy { speed: f64, clearance: f64 }
//!
//! impl Behavior for Shy {
//!     fn gen_action(&mut self, state: &State) -> Action {
//!         match state.nearest_range() {
//!             Some(r) if r < self.clearance => Action::with_vote(1.0).velocity(0.0).rot_velocity(0.5),
//!             _ => Action::with_vote(0.5).velocity(self.speed),
//!         }
//!     }
//! }
//!
//! #[derive(Deserialize)]
//! #[serde(deny_unknown_fields)]
//! struct ShyConfig { speed: f64, clearance: f64 }
//!
//! // What `ubf behaviors --describe` prints for it.
//! impl Describe for ShyConfig {
//!     fn fields() -> Vec<Field> {
//!         vec![
//!             Field::new("speed", "number", "m/s", "required", "", "forward speed"),
//!             Field::new("clearance", "number", "m", "required", "", "turns away from anything nearer"),
//!         ]
//!     }
//! }
//!
//! let mut registry = Registry::new();
//! registry.register("Shy", |c: &ShyConfig, _: &BuildContext| Shy { speed: c.speed, clearance: c.clearance });
//! let spec: BehaviorSpec = registry.from_ron("Shy(speed: 0.4, clearance: 0.5)").unwrap();
//! let mut shy = spec.build(&BuildContext::new(7));
//! assert_eq!(shy.gen_action(&State::default()).motion.velocity, Some(0.4));
//! assert_eq!(registry.fields("Shy").unwrap()[1].unit, "m");
//! ```
//!
//! Units are SI throughout (metres, seconds, radians); angles are
//! counter-clockwise positive. Randomness comes from [`BuildContext::rng`],
//! seeded from the run's seed, so a run is exactly repeatable.

#![warn(missing_docs)]

mod action;
pub mod arbiter;
mod behavior;
mod clock;
mod command;
mod composite;
mod condition;
pub mod config;
mod controller;
mod describe;
mod geometry;
mod landmark;
mod pan_tilt;
mod progress;
mod record;
mod registry;
mod robot;
mod robot_error;
mod safety;
pub mod seeds;
mod session;
mod sink;
mod state;
pub mod stereo;

pub use action::{Action, Channel, Motion};
pub use arbiter::{Arbiter, ArbiterSpec, Arbitration, Bid};
pub use behavior::{catch_reported, from_fn, panic_is_reported, panic_message, Behavior, BehaviorPanic, FnBehavior};
pub use clock::{Clock, PacedClock, SimClock, Stopwatch, WallClock};
pub use command::{Command, Limits, Turn};
pub use composite::Composite;
pub use condition::Condition;
pub use controller::{Controller, ControllerError, OnBehaviorPanic};
pub use describe::{markdown_table, Describe, Field};
pub use geometry::{angle_difference, wrap_angle, Pose2};
pub use landmark::{Descriptor, LandmarkObservation, StereoFrame, StereoImages, StereoPixels};
pub use pan_tilt::{anchor_mean, Aim, PanTilt, ANCHOR_READINGS};
pub use progress::{ProgressCheck, ProgressWatch};
pub use record::{NodeInfo, NodeOutcome, TickRecord, TreeLayout};
pub use registry::{BehaviorSpec, BuildContext, Registry};
pub use robot::{GroundTruth, NullRobot, Robot, RobotWrapper, VelocityLimiter, Wraps};
pub use robot_error::{LinkLoss, RobotError};
pub use safety::{Hold, SafetyGuard, SafetyPolicy};
pub use session::{Ends, Session, SessionEnd, TreeSource};
pub use sink::{BackgroundSink, TickSink, TracingSink};
pub use state::{Bumpers, EgomotionState, Goal, HeadingFix, RangeReading, State, WheelScale};
pub use stereo::{CameraMount, PrincipalPoint, StereoCamera};
/// The random-number crates [`BuildContext::rng`] is made of: a behaviour
/// in another crate draws from it with `ubf_core::rand::Rng`, at the very
/// version ubf was built with.
pub use {rand, rand_chacha};
