//! The ARCOS protocol spoken by MobileRobots Pioneer and Powerbot
//! controllers, over a serial line or TCP. Written from the public
//! operations manuals' description of the protocol.
//!
//! - [`codec`]: framing, checksum, commands, server information packets
//!   (SIPs) and the position unwrapping odometry needs. Pure: no I/O.

pub mod codec;
