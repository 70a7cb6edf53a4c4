//! Which landmarks of two frames are the same: descriptor matching
//! (thesis eq. 8–11).

use serde::Deserialize;
use ubf_core::config::unit_interval;
use ubf_core::{Descriptor, LandmarkObservation};

/// Descriptor matching between frames (thesis eq. 8–11).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MatchConfig {
    /// Largest Hamming distance of a match, bits of 256.
    pub max_distance: u32,
    /// The best match must be nearer than this share of the second best.
    #[serde(deserialize_with = "unit_interval")]
    pub ratio: f64,
}

impl Default for MatchConfig {
    fn default() -> Self {
        MatchConfig { max_distance: 64, ratio: 0.8 }
    }
}

impl MatchConfig {
    /// The index of the descriptor in `candidates` nearest `query`, if it is
    /// within `max_distance` and clearly nearer than the second nearest
    /// (thesis eq. 11). `Err(true)` when two candidates are too alike to
    /// tell apart, `Err(false)` when none is near enough.
    pub fn best_match<'a>(
        &self,
        query: &Descriptor,
        candidates: impl IntoIterator<Item = &'a Descriptor>,
    ) -> Result<usize, bool> {
        let (mut best, mut second) = ((u32::MAX, usize::MAX), u32::MAX);
        for (i, candidate) in candidates.into_iter().enumerate() {
            let d = query.hamming(candidate);
            if d < best.0 {
                second = best.0;
                best = (d, i);
            } else if d < second {
                second = d;
            }
        }
        if best.0 > self.max_distance {
            return Err(false);
        }
        if second != u32::MAX && f64::from(best.0) >= self.ratio * f64::from(second) {
            return Err(true);
        }
        Ok(best.1)
    }
}

/// Pairs `(previous, current)` of observations of the same landmark, by
/// descriptor: nearest within `max_distance`, clearly nearer than the second
/// nearest, and each previous observation used once (the nearer pair wins).
pub fn match_frames(
    previous: &[LandmarkObservation],
    current: &[LandmarkObservation],
    config: &MatchConfig,
    out: &mut Vec<(usize, usize)>,
) {
    out.clear();
    for (j, cur) in current.iter().enumerate() {
        if let Ok(i) = config.best_match(&cur.descriptor, previous.iter().map(|p| &p.descriptor)) {
            out.push((i, j));
        }
    }
    // One current observation per previous one: keep the closest.
    out.sort_by_key(|&(i, j)| (i, current[j].descriptor.hamming(&previous[i].descriptor)));
    out.dedup_by_key(|&mut (i, _)| i);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::egomotion::testing::{frame, landmarks};
    use crate::stereo::StereoCamera;
    use ubf_core::Pose2;

    #[test]
    fn frames_match_by_descriptor() {
        let camera = StereoCamera::default();
        let a = frame(&landmarks(), Pose2::default(), &camera);
        let b = frame(&landmarks(), Pose2::new(0.3, 0.0, 0.0), &camera);
        let mut m = Vec::new();
        match_frames(&a, &b, &MatchConfig::default(), &mut m);
        assert_eq!(m.len(), a.len().min(b.len()));
        assert!(m.iter().all(|&(i, j)| a[i].source_id == b[j].source_id));
    }
}
