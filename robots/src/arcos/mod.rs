//! The ARCOS protocol spoken by MobileRobots Pioneer and Powerbot
//! controllers, over a serial line or TCP. Written from the public
//! operations manuals' description of the protocol.
//!
//! - [`codec`]: framing, checksum, commands, server information packets
//!   (SIPs) and the position unwrapping odometry needs. Pure: no I/O.
//! - [`link`]: serial ports and TCP behind one trait.
//! - [`client`]: the handshake and a [`ubf_core::Robot`] over any link.
//! - [`emulator`]: the robot's side, for tests and for trying things out.

pub mod client;
pub mod codec;
pub mod emulator;
pub mod link;
