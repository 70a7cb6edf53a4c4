//! The simulated descriptor model: how a landmark's 256-bit descriptor
//! drifts as the view on it turns, and a cache of each landmark's threshold
//! angles so that a frame does not derive them again.

use super::hash::splitmix;
use super::world::WorldLandmark;
use std::collections::HashMap;
use ubf_core::Descriptor;

/// Bits in a descriptor.
const BITS: usize = 256;

/// The view, °, past which bit `bit` of landmark `id` flips: spread evenly at
/// random over ±90°, the same for the landmark in every run.
fn threshold_deg(id: u32, bit: u64) -> f64 {
    let h = splitmix(u64::from(id) << 8 | bit);
    (h >> 11) as f64 / (1u64 << 53) as f64 * 180.0 - 90.0
}

/// Whether a view `view_deg` flips the bit whose threshold is `threshold`:
/// a positive threshold is passed turning one way, a negative one the other.
fn flips(threshold: f64, view_deg: f64) -> bool {
    if threshold >= 0.0 {
        view_deg > threshold
    } else {
        view_deg < threshold
    }
}

/// The view angle in degrees, as the thresholds are written.
fn view_deg(view: f64) -> f64 {
    view.to_degrees().clamp(-90.0, 90.0)
}

/// The descriptor of `landmark` seen from `view` radians off its reference
/// direction, without image noise.
///
/// Each of the 256 bits has its own threshold angle, spread evenly at random
/// over ±90°; a bit flips once the view passes its threshold. Two views
/// `Δ` apart then differ in about `256·Δ/180°` bits, whatever the views: 28
/// bits at 20°, 43 at 30°. Descriptors change smoothly with viewpoint, as
/// real ones do (the thesis's figure 3).
///
/// This derives all 256 thresholds on every call; the simulated camera keeps
/// them per landmark instead, with the same result.
pub fn descriptor_from(landmark: &WorldLandmark, view: f64) -> Descriptor {
    derive(&landmark.descriptor, landmark.id, view_deg(view))
}

/// The descriptor `head_on` of landmark `id` seen from `view_deg`, each
/// bit's threshold derived afresh.
fn derive(head_on: &Descriptor, id: u32, view_deg: f64) -> Descriptor {
    let mut words = head_on.0;
    for bit in 0..BITS as u64 {
        if flips(threshold_deg(id, bit), view_deg) {
            words[(bit / 64) as usize] ^= 1 << (bit % 64);
        }
    }
    Descriptor(words)
}

/// One landmark's thresholds, arranged so that the bits a view flips are
/// found by a search rather than by testing all 256.
///
/// A view `v ≥ 0` flips exactly the bits whose thresholds lie in `[0, v)`,
/// and a view `v < 0` those in `(v, 0)`. With the thresholds sorted, either
/// set is a run of them that ends at zero, and the bits of every such run
/// are kept ready as a mask.
#[derive(Clone)]
struct Thresholds {
    /// All 256 thresholds, ascending.
    sorted: [f64; BITS],
    /// Where the thresholds `≥ 0` start in `sorted`.
    zero: usize,
    /// `masks[i]`: the bits of `sorted[zero..i]` for `i ≥ zero`, of
    /// `sorted[i..zero]` for `i ≤ zero`.
    masks: [[u64; 4]; BITS + 1],
}

impl Thresholds {
    fn of(id: u32) -> Box<Thresholds> {
        let mut by_angle = [(0.0, 0u8); BITS];
        for (bit, entry) in by_angle.iter_mut().enumerate() {
            *entry = (threshold_deg(id, bit as u64), bit as u8);
        }
        by_angle.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut table = Box::new(Thresholds {
            sorted: by_angle.map(|(t, _)| t),
            zero: by_angle.partition_point(|&(t, _)| t < 0.0),
            masks: [[0; 4]; BITS + 1],
        });
        let zero = table.zero;
        let with = |mut mask: [u64; 4], bit: u8| {
            mask[usize::from(bit / 64)] |= 1 << (bit % 64);
            mask
        };
        for (i, &(_, bit)) in by_angle.iter().enumerate().skip(zero) {
            table.masks[i + 1] = with(table.masks[i], bit);
        }
        for (i, &(_, bit)) in by_angle.iter().enumerate().take(zero).rev() {
            table.masks[i] = with(table.masks[i + 1], bit);
        }
        table
    }

    /// The descriptor `head_on` seen from `view_deg`: what [`derive`] gives.
    fn apply(&self, head_on: &Descriptor, view_deg: f64) -> Descriptor {
        let end = if view_deg >= 0.0 {
            // Past every threshold in [0, view).
            self.zero + self.sorted[self.zero..].partition_point(|&t| t < view_deg)
        } else if view_deg < 0.0 {
            // Past every threshold in (view, 0).
            self.sorted[..self.zero].partition_point(|&t| t <= view_deg)
        } else {
            // A view that is not a number passes no threshold.
            self.zero
        };
        let mut words = head_on.0;
        for (word, mask) in words.iter_mut().zip(self.masks[end]) {
            *word ^= mask;
        }
        Descriptor(words)
    }
}

/// The threshold angles of every landmark seen so far, by landmark id.
///
/// Deriving a landmark's 256 thresholds (a hash and a division per bit) was
/// a quarter of a corridor sweep's time when done afresh for every
/// observation; they depend on the landmark alone, so each is derived once,
/// the first time the landmark is seen. Only landmarks that are seen take
/// room (about 10 KiB each), so a world with many landmarks out of sight costs
/// nothing.
#[derive(Clone, Default)]
pub(crate) struct DescriptorCache {
    by_id: HashMap<u32, Box<Thresholds>>,
}

impl DescriptorCache {
    /// The descriptor of `landmark` seen from `view` radians off its
    /// reference direction, without image noise: the same bits as
    /// [`descriptor_from`].
    pub(crate) fn descriptor(&mut self, landmark: &WorldLandmark, view: f64) -> Descriptor {
        let thresholds = self.by_id.entry(landmark.id).or_insert_with(|| Thresholds::of(landmark.id));
        thresholds.apply(&landmark.descriptor, view_deg(view))
    }
}

impl std::fmt::Debug for DescriptorCache {
    /// How many landmarks are cached, rather than 256 numbers for each.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DescriptorCache").field("landmarks", &self.by_id.len()).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::world::Anchor;

    fn landmark(id: u32, words: [u64; 4]) -> WorldLandmark {
        WorldLandmark {
            id,
            anchor: Anchor::Fixed { position: [0.0, 0.0, 0.0], normal: None },
            descriptor: Descriptor(words),
        }
    }

    #[test]
    fn descriptors_drift_with_viewpoint() {
        let lm = landmark(0, [1, 2, 3, 4]);
        let d0 = descriptor_from(&lm, 0.0);
        let d20 = descriptor_from(&lm, 20f64.to_radians());
        let d40 = descriptor_from(&lm, 40f64.to_radians());
        let d60 = descriptor_from(&lm, 60f64.to_radians());
        assert!(d0.hamming(&d20) < d0.hamming(&d40));
        assert!(d0.hamming(&d40) < d0.hamming(&d60));
        // Differences depend on the angle between the views, not on where
        // they are: 20° apart is about 256·20/180 ≈ 28 bits either way.
        assert!((15..45).contains(&d20.hamming(&d40)), "{}", d20.hamming(&d40));
        assert!((15..45).contains(&d40.hamming(&d60)), "{}", d40.hamming(&d60));
    }

    #[test]
    fn cached_descriptors_are_the_derived_ones() {
        let mut cache = DescriptorCache::default();
        let ids = [0, 1, 2, 15, 255, 256, 1_000_000, u32::MAX];
        // Views across and beyond ±90°, on and near thresholds and zero,
        // and both signs of zero.
        let mut views: Vec<f64> = (-200..=200).map(|d| f64::from(d).to_radians()).collect();
        views.extend([0.0, -0.0, 1e-12, -1e-12, f64::NAN, f64::INFINITY, f64::NEG_INFINITY]);
        for &id in &ids {
            views.extend((0..BITS as u64).map(|bit| threshold_deg(id, bit).to_radians()));
        }
        for (k, &id) in ids.iter().enumerate() {
            let k = k as u64;
            let lm = landmark(id, [splitmix(k), splitmix(k + 10), splitmix(k + 20), splitmix(k + 30)]);
            for &view in &views {
                // Twice: the first call fills the cache, the second reads it.
                for _ in 0..2 {
                    assert_eq!(cache.descriptor(&lm, view), descriptor_from(&lm, view), "id {id}, view {view}");
                }
            }
        }
        assert_eq!(cache.by_id.len(), ids.len());
    }

    #[test]
    fn views_on_and_either_side_of_a_threshold_flip_the_same_bits() {
        let head_on = Descriptor([1, 2, 3, 4]);
        for id in [0, 9, 4_000_000_000] {
            let thresholds = Thresholds::of(id);
            for bit in 0..BITS as u64 {
                let t = threshold_deg(id, bit);
                for view in [t.next_down(), t, t.next_up(), 0.0, -0.0, 90.0, -90.0] {
                    assert_eq!(thresholds.apply(&head_on, view), derive(&head_on, id, view), "id {id}, view {view}°");
                }
            }
        }
    }

    #[test]
    fn a_cache_keys_on_the_landmark_not_on_the_order_seen() {
        // Two landmarks with the same head-on descriptor but different ids
        // drift differently, whichever is seen first.
        let (a, b) = (landmark(3, [7; 4]), landmark(4, [7; 4]));
        let view = 40f64.to_radians();
        let mut cache = DescriptorCache::default();
        let (first_b, then_a) = (cache.descriptor(&b, view), cache.descriptor(&a, view));
        assert_eq!(then_a, descriptor_from(&a, view));
        assert_eq!(first_b, descriptor_from(&b, view));
        assert_ne!(then_a, first_b);
    }
}
