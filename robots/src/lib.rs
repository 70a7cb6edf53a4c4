//! # ubf-robots: what the controller can drive
//!
//! - [`sim`]: a headless simulated robot, deterministic for a given seed.
//! - [`model`]: robot types (geometry, limits, sonar) read from RON files.
//! - [`egomotion`]: a wrapper running visual egomotion on any robot.
//! - [`wall_compass`]: a wrapper holding odometry's heading by the walls
//!   the side sonars run along.
//! - [`camera`]: a wrapper giving any robot a stereo camera: pairs from a
//!   source through the feature pipeline on a thread of their own.
//! - [`arcos`]: the Pioneer/Powerbot controller protocol.
//! - [`ros2`]: any ROS 2 robot, through `/cmd_vel`, `/odom` and `/scan`.
//! - [`emergency`]: stopping a real robot from a signal handler.
//! - [`ptu`]: a real pan-tilt head for the cameras (a FLIR PTU's serial
//!   protocol), and an emulator of it.

#![warn(missing_docs)]

pub mod arcos;
pub mod camera;
pub mod egomotion;
pub mod emergency;
pub mod model;
mod printable;
pub mod ptu;
pub mod ros2;
pub mod sim;
mod timed_readings;
pub mod wall_compass;
