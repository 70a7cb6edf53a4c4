//! Where a run's randomness comes from: one seed, split into streams.
//!
//! Every source of randomness draws from a stream of its own of the run's
//! seed (ChaCha8's 64-bit stream number), so adding draws to one source
//! never shifts another's: a change to the sonar model leaves the world's
//! layout and the camera's noise as they were. This is the one place the
//! streams are numbered.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// A source of randomness in a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream<'a> {
    /// Visual egomotion's sampling (RANSAC).
    Egomotion,
    /// The simulated world: random landmarks.
    World,
    /// The simulated robot's motion and odometry errors.
    Motion,
    /// The simulated sonar's noise.
    Sonar,
    /// The simulated camera's pixel noise and mismatches.
    Camera,
    /// The simulated pan-tilt unit's encoder noise.
    PanTilt,
    /// The same noise in the extra readings that anchor egomotion's map at
    /// the start ([`crate::PanTilt::anchor_reading`]), so that taking them
    /// leaves every later reading as a single first reading would.
    PanTiltAnchor,
    /// A behaviour, by its path in the tree (`root/aid/scan`), so that
    /// adding a behaviour elsewhere in the tree does not change this one's
    /// draws.
    Behavior(&'a str),
}

impl Stream<'_> {
    /// The stream's number. The fixed sources have small numbers; a
    /// behaviour's is a stable hash of its path.
    pub fn number(self) -> u64 {
        match self {
            Stream::Egomotion => 0,
            Stream::World => 1,
            Stream::Motion => 2,
            Stream::Sonar => 3,
            Stream::Camera => 4,
            Stream::PanTilt => 5,
            Stream::PanTiltAnchor => 6,
            Stream::Behavior(path) => fnv1a(path.as_bytes()),
        }
    }
}

/// The generator for `stream` of a run seeded with `seed`.
pub fn rng(seed: u64, stream: Stream) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream.number());
    rng
}

/// FNV-1a: a stable hash (std's hashers may change between releases).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    #[test]
    fn streams_of_one_seed_differ_and_the_egomotion_stream_is_the_plain_seed() {
        let draw = |stream| rng(7, stream).random::<u64>();
        let all = [
            Stream::Egomotion,
            Stream::World,
            Stream::Motion,
            Stream::Sonar,
            Stream::Camera,
            Stream::PanTilt,
            Stream::PanTiltAnchor,
        ];
        for (i, a) in all.iter().enumerate() {
            for b in &all[i + 1..] {
                assert_ne!(draw(*a), draw(*b), "{a:?} and {b:?}");
            }
        }
        assert_ne!(draw(Stream::Behavior("root/a")), draw(Stream::Behavior("root/b")));
        // Logs and results made before the streams were gathered here stay
        // reproducible: stream 0 is what `seed_from_u64` alone gives.
        assert_eq!(draw(Stream::Egomotion), ChaCha8Rng::seed_from_u64(7).random::<u64>());
    }
}
