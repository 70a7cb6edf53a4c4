//! # ubf-perception: what stereo vision tells the robot
//!
//! Stereo triangulation, the landmark egomotion error model, CV fusion and
//! the egomotion estimators live here, shared by the simulated and the real
//! robot. This crate is filled in by the action-aiding work; it exists now so
//! that the dependency direction `behaviors`/`robots` → `perception` →
//! `ubf-core` is fixed from the start.
