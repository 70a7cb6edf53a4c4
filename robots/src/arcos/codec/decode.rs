//! Reading bodies: what was wrong with a malformed one, and the reader of
//! little-endian fields the packet readers share.

/// What was wrong with a packet.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// The body ended before a field.
    #[error("{what}: needed {needed} more bytes, got {got}")]
    Truncated {
        /// The field.
        what: &'static str,
        /// Bytes needed.
        needed: usize,
        /// Bytes there.
        got: usize,
    },
    /// Not a packet type this codec reads.
    #[error("packet type {0:#04x} is not a SIP")]
    NotASip(u8),
    /// A packet of another type than the one asked for.
    #[error("expected packet type {expected:#04x}, got {got:#04x}")]
    UnexpectedPacket {
        /// The type asked for.
        expected: u8,
        /// The type there.
        got: u8,
    },
    /// An unknown command number.
    #[error("unknown command {0}")]
    UnknownCommand(u8),
    /// An argument type byte other than 0x3B, 0x1B or 0x2B.
    #[error("command {command}: argument type {kind:#04x}")]
    BadArgument {
        /// The command.
        command: u8,
        /// The type byte.
        kind: u8,
    },
}

/// Reads little-endian fields off a body, failing cleanly at its end.
pub(super) struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// A reader at the start of `bytes`.
    pub(super) fn new(bytes: &'a [u8]) -> Self {
        Reader { bytes, at: 0 }
    }

    pub(super) fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], DecodeError> {
        let rest = &self.bytes[self.at.min(self.bytes.len())..];
        if rest.len() < n {
            return Err(DecodeError::Truncated { what, needed: n, got: rest.len() });
        }
        self.at += n;
        Ok(&rest[..n])
    }
    pub(super) fn u8(&mut self, what: &'static str) -> Result<u8, DecodeError> {
        Ok(self.take(1, what)?[0])
    }
    pub(super) fn u16(&mut self, what: &'static str) -> Result<u16, DecodeError> {
        let b = self.take(2, what)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }
    pub(super) fn i16(&mut self, what: &'static str) -> Result<i16, DecodeError> {
        Ok(self.u16(what)? as i16)
    }
    /// A NUL-terminated string, as [`text`] reads it.
    pub(super) fn string(&mut self, what: &'static str) -> Result<String, DecodeError> {
        let rest = &self.bytes[self.at.min(self.bytes.len())..];
        let end = rest.iter().position(|&b| b == 0).ok_or(DecodeError::Truncated { what, needed: 1, got: 0 })?;
        self.at += end + 1;
        Ok(crate::printable::text(&rest[..end]))
    }
    pub(super) fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.at)
    }
    /// An optional trailing field: present only if the body still has it.
    pub(super) fn maybe<T>(
        &mut self,
        size: usize,
        read: impl FnOnce(&mut Self) -> Result<T, DecodeError>,
    ) -> Option<T> {
        if self.remaining() >= size {
            read(self).ok()
        } else {
            None
        }
    }
}
