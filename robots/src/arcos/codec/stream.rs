//! Framing: the header, the checksum, a body framed into a packet, and a
//! byte stream cut back into bodies.

/// The two header bytes.
pub const HEADER: [u8; 2] = [0xFA, 0xFB];
/// Longest body a packet may carry (ARCOS drops command packets whose count
/// exceeds 204; keep to 200 with the checksum).
pub const MAX_BODY: usize = 198;

/// The checksum of a packet body.
pub fn checksum(body: &[u8]) -> u16 {
    let mut sum: u16 = 0;
    let mut pairs = body.chunks_exact(2);
    for pair in &mut pairs {
        sum = sum.wrapping_add(u16::from(pair[0]) << 8 | u16::from(pair[1]));
    }
    if let [last] = pairs.remainder() {
        sum ^= u16::from(*last);
    }
    sum
}

/// Frames a body into a packet. Bodies longer than [`MAX_BODY`] are a
/// programming error in the caller and are cut to fit.
pub fn frame(body: &[u8]) -> Vec<u8> {
    let body = &body[..body.len().min(MAX_BODY)];
    let mut packet = Vec::with_capacity(body.len() + 5);
    packet.extend_from_slice(&HEADER);
    packet.push((body.len() + 2) as u8);
    packet.extend_from_slice(body);
    packet.extend_from_slice(&checksum(body).to_be_bytes());
    packet
}

/// Counts of what a [`StreamDecoder`] threw away.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DecoderStats {
    /// Whole packets delivered.
    pub packets: u64,
    /// Packets dropped for a wrong checksum.
    pub bad_checksums: u64,
    /// Bytes skipped while looking for a header.
    pub skipped_bytes: u64,
}

/// Cuts a byte stream into packet bodies: resynchronises after garbage,
/// drops packets with bad checksums (counting them), and never holds more
/// than one packet's worth of bytes beyond what was last pushed.
#[derive(Clone, Debug, Default)]
pub struct StreamDecoder {
    buffer: Vec<u8>,
    stats: DecoderStats,
}

impl StreamDecoder {
    /// An empty decoder.
    pub fn new() -> Self {
        Self::default()
    }

    /// What it has delivered and dropped so far.
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Adds bytes read from the link.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buffer.extend_from_slice(bytes);
    }

    /// The next whole, valid packet body, if the bytes so far hold one.
    pub fn next_body(&mut self) -> Option<Vec<u8>> {
        loop {
            // Find a header; everything before it is garbage.
            let start = self.buffer.windows(2).position(|w| w == HEADER);
            let Some(start) = start else {
                // Keep a trailing 0xFA: it may begin a header.
                let keep = usize::from(self.buffer.last() == Some(&HEADER[0]));
                let skipped = self.buffer.len() - keep;
                self.stats.skipped_bytes += skipped as u64;
                self.buffer.drain(..skipped);
                return None;
            };
            if start > 0 {
                self.stats.skipped_bytes += start as u64;
                self.buffer.drain(..start);
            }
            let &count = self.buffer.get(2)?;
            let count = usize::from(count);
            if count < 2 {
                // No room for a checksum: not a packet header after all.
                self.stats.skipped_bytes += 1;
                self.buffer.drain(..1);
                continue;
            }
            if self.buffer.len() < 3 + count {
                return None;
            }
            let body = &self.buffer[3..1 + count];
            let sent = u16::from_be_bytes([self.buffer[1 + count], self.buffer[2 + count]]);
            if checksum(body) == sent {
                let body = body.to_vec();
                self.buffer.drain(..3 + count);
                self.stats.packets += 1;
                return Some(body);
            }
            // A bad packet, or a false header inside garbage: drop one byte
            // and look again, so a real header within is not lost.
            self.stats.bad_checksums += 1;
            self.buffer.drain(..1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arcos::codec::{ClientCommand, ConfigPacket, Identity, Sip};
    use proptest::prelude::*;

    #[test]
    fn the_decoder_resynchronises_and_counts() {
        let mut d = StreamDecoder::new();
        let good = ClientCommand::Vel(300).packet();
        let mut corrupt = ClientCommand::Vel(100).packet();
        *corrupt.last_mut().unwrap() ^= 0xFF;
        let mut stream = vec![0x00, 0xFA, 0x13, 0xFA];
        stream.extend(&corrupt);
        stream.extend(&good);
        // Byte by byte, as a serial line delivers.
        let mut bodies = Vec::new();
        for b in stream {
            d.push(&[b]);
            while let Some(body) = d.next_body() {
                bodies.push(body);
            }
        }
        assert_eq!(bodies, [ClientCommand::Vel(300).body()]);
        assert_eq!(d.stats().packets, 1);
        assert_eq!(d.stats().bad_checksums, 1);
        assert!(d.stats().skipped_bytes >= 3);
    }

    /// Feeds `chunks` to a decoder and every parser: no panic, bounded memory.
    fn feed(chunks: &[Vec<u8>]) -> Result<(), proptest::test_runner::TestCaseError> {
        let mut d = StreamDecoder::new();
        for chunk in chunks {
            d.push(chunk);
            while let Some(body) = d.next_body() {
                let _ = Sip::parse(&body);
                let _ = ClientCommand::parse(&body);
                let _ = Identity::parse(&body);
                let _ = ConfigPacket::parse(&body);
            }
            prop_assert!(d.buffer.len() <= 3 + 255 + chunk.len());
        }
        Ok(())
    }

    /// The fuzz run: a million random streams through the decoder and every
    /// parser. `cargo test --release -p ubf-robots -- --ignored million`.
    #[test]
    #[ignore = "a million cases: run it on purpose, in release"]
    fn a_million_random_streams() {
        use proptest::test_runner::{Config, TestRunner};
        let mut runner = TestRunner::new(Config { cases: 1_000_000, failure_persistence: None, ..Config::default() });
        runner
            .run(&proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..64), 0..16), |chunks| {
                feed(&chunks)
            })
            .unwrap();
    }

    proptest! {
        #[test]
        fn arbitrary_bytes_never_panic_and_memory_stays_bounded(chunks in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..64), 0..64)) {
            feed(&chunks)?;
        }

        #[test]
        fn framed_bodies_come_back_whole_amid_garbage(body in proptest::collection::vec(any::<u8>(), 0..MAX_BODY), junk in proptest::collection::vec(any::<u8>(), 0..40)) {
            let mut d = StreamDecoder::new();
            d.push(&junk.iter().map(|b| if *b == 0xFA { 0 } else { *b }).collect::<Vec<_>>());
            d.push(&frame(&body));
            prop_assert_eq!(d.next_body(), Some(body));
        }
    }
}
