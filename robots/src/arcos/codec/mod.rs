//! ARCOS packets, pure: bytes in, values out, and back.
//!
//! A packet is `0xFA 0xFB N body… ck_hi ck_lo`, where `N` counts the body
//! and the two checksum bytes. The checksum adds the body as big-endian
//! 16-bit pairs modulo 2¹⁶ and XORs a leftover odd byte into the low byte.
//! Integers in bodies are little-endian.
//!
//! By job: `stream` (framing, the checksum and cutting a byte stream into
//! bodies), `command` (what the client sends), `sip` (what the controller
//! sends as it runs, and the handshake's reply), `config` (the CONFIG
//! packet and baud codes), `position` (the unwrapping odometry needs) and
//! `decode` (the field reader and its errors, shared by the readers).

mod command;
mod config;
mod decode;
mod position;
mod sip;
mod stream;

pub use command::ClientCommand;
pub use config::{baud_code, baud_of_code, ConfigPacket, ConfigSettings, CONFIG_TYPE};
pub use decode::DecodeError;
pub use position::Unwrapper;
pub use sip::{Identity, Sip, SipTail};
pub use stream::{checksum, frame, DecoderStats, StreamDecoder, HEADER, MAX_BODY};
