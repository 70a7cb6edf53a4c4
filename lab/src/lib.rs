//! # ubf-lab: the research behind the action-aiding results
//!
//! What made the thesis's figures and `docs/results.md`, kept apart from
//! the product (it depends on the product, never the other way):
//!
//! - [`experiment`]: the thesis's experiments;
//! - [`environment_map`]: where action aiding beats driving straight;
//! - [`cost_fit`]: the decision's error coefficients, fitted from run logs;
//! - [`cost_forms`]: whether another form of that model predicts better;
//! - [`figures`]: the error model's heat map and the environment map.

#![warn(missing_docs)]

pub mod cost_fit;
pub mod cost_forms;
pub mod environment_map;
pub mod experiment;
pub mod figures;
