//! The evaluative decision engine (thesis §3.5.2.2, eq. 38–48): which
//! heading puts the known landmarks where egomotion is least uncertain.

use ubf_perception::error_model::CvTable;

/// What the engine needs to know of the camera and the rules.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DecisionRules {
    /// Half the horizontal field of view, rad.
    pub half_fov: f64,
    /// The step the robot is projected ahead by, m (eq. 40–43).
    pub step_m: f64,
    /// A landmark nearer than this from the projected position means an
    /// obstacle: the heading is rejected, m.
    pub min_slant_m: f64,
    /// Landmarks farther than this are not seen, m.
    pub max_range_m: f64,
}

/// Bearing buckets over the full circle.
const BUCKETS: usize = 72;

/// The best heading among `candidates` (world angles) for a robot at
/// `position` among `landmarks` (world floor positions): the one whose fused
/// CV (eq. 6) over the landmarks in view after one projected step is least.
/// A heading with no landmark in view (egomotion would fail) or one nearer
/// than the slant limit is rejected. Ties go to the candidate listed first.
/// Returns the heading and its fused CV, or `None` if every heading is
/// rejected.
///
/// For speed, landmarks are bucketed by bearing once, and each candidate
/// looks only at the buckets its field of view can reach from the projected
/// position; landmarks within four steps, whose bearing the step can swing
/// far, are looked at by every candidate.
pub fn best_heading(
    table: &CvTable,
    rules: &DecisionRules,
    landmarks: &[(f64, f64)],
    position: (f64, f64),
    candidates: impl IntoIterator<Item = f64>,
) -> Option<(f64, f64)> {
    use std::f64::consts::TAU;
    let tan_half = rules.half_fov.tan();
    let (min_slant2, max_range2) = (rules.min_slant_m.powi(2), rules.max_range_m.powi(2));
    let near = 4.0 * rules.step_m;
    let bucket_of = |bearing: f64| ((bearing.rem_euclid(TAU) / TAU * BUCKETS as f64) as usize).min(BUCKETS - 1);
    // Counting sort of the far landmarks into bearing buckets.
    // Offsets from the robot, computed once: from the projected position a
    // landmark's depth is `d·u − step` and its lateral offset `d·n`.
    let mut counts = [0usize; BUCKETS + 1];
    let mut nearby: Vec<(f64, f64)> = Vec::new();
    let mut bearing_bucket = Vec::with_capacity(landmarks.len());
    for &(lx, ly) in landmarks {
        let (dx, dy) = (lx - position.0, ly - position.1);
        if dx.hypot(dy) < near {
            nearby.push((dx, dy));
            bearing_bucket.push(usize::MAX);
        } else {
            let b = bucket_of(dy.atan2(dx));
            counts[b + 1] += 1;
            bearing_bucket.push(b);
        }
    }
    for b in 0..BUCKETS {
        counts[b + 1] += counts[b];
    }
    let starts = counts;
    let mut fill = counts;
    let mut sorted = vec![(0.0, 0.0); landmarks.len() - nearby.len()];
    for (&(lx, ly), &b) in landmarks.iter().zip(&bearing_bucket) {
        if b != usize::MAX {
            sorted[fill[b]] = (lx - position.0, ly - position.1);
            fill[b] += 1;
        }
    }
    // From four steps out, one step moves a bearing by at most asin(1/4).
    let reach = rules.half_fov + (0.25f64).asin() + TAU / BUCKETS as f64;
    let span = (reach / TAU * BUCKETS as f64).ceil() as isize;

    let mut best: Option<(f64, f64)> = None;
    for heading in candidates {
        let (s, c) = heading.sin_cos();
        // Eq. 40–43: the robot projected one step ahead along the heading.
        let view = View { sin: s, cos: c, step: rules.step_m, tan_half, min_slant2, max_range2 };
        // The window of buckets is one run of `sorted`, or two where it
        // wraps round.
        let first = bucket_of(heading) as isize - span;
        let last = bucket_of(heading) as isize + span;
        let slices: [&[(f64, f64)]; 2] = if last - first + 1 >= BUCKETS as isize {
            [&sorted[..], &[]]
        } else {
            let lo = first.rem_euclid(BUCKETS as isize) as usize;
            let hi = last.rem_euclid(BUCKETS as isize) as usize;
            if lo <= hi {
                [&sorted[starts[lo]..starts[hi + 1]], &[]]
            } else {
                [&sorted[starts[lo]..], &sorted[..starts[hi + 1]]]
            }
        };
        let mut information = 0.0;
        let mut rejected = false;
        for slice in [&nearby[..], slices[0], slices[1]] {
            match view.information(table, slice) {
                Some(i) => information += i,
                None => {
                    rejected = true;
                    break;
                }
            }
        }
        if !rejected && information > 0.0 {
            let cv = 1.0 / information;
            if best.is_none_or(|(_, b)| cv < b) {
                best = Some((heading, cv));
            }
        }
    }
    best
}

/// One candidate heading's view from the projected position.
struct View {
    sin: f64,
    cos: f64,
    step: f64,
    tan_half: f64,
    min_slant2: f64,
    max_range2: f64,
}

impl View {
    /// The summed information (Σ 1/CV) of the landmarks in view, given as
    /// offsets from the robot's current position, or `None` if one is nearer
    /// than the slant limit (an obstacle).
    #[inline]
    fn information(&self, table: &CvTable, offsets: &[(f64, f64)]) -> Option<f64> {
        let mut sum = 0.0;
        for &(dx, dy) in offsets {
            // Eq. 44–48 without trigonometry: depth along the heading from
            // the projected position, lateral offset to the right.
            let depth = dx * self.cos + dy * self.sin - self.step;
            let lateral = dx * self.sin - dy * self.cos;
            if depth <= 0.0 || lateral.abs() > depth * self.tan_half {
                continue;
            }
            let range2 = depth * depth + lateral * lateral;
            if range2 < self.min_slant2 {
                return None;
            }
            if range2 <= self.max_range2 {
                sum += table.information(lateral, depth);
            }
        }
        Some(sum)
    }
}

/// The same evaluation without bucketing, every landmark for every heading:
/// the reference the fast version is tested against.
pub fn best_heading_exhaustive(
    table: &CvTable,
    rules: &DecisionRules,
    landmarks: &[(f64, f64)],
    position: (f64, f64),
    candidates: impl IntoIterator<Item = f64>,
) -> Option<(f64, f64)> {
    let offsets: Vec<(f64, f64)> = landmarks.iter().map(|&(x, y)| (x - position.0, y - position.1)).collect();
    let mut best: Option<(f64, f64)> = None;
    for heading in candidates {
        let (s, c) = heading.sin_cos();
        let view = View {
            sin: s,
            cos: c,
            step: rules.step_m,
            tan_half: rules.half_fov.tan(),
            min_slant2: rules.min_slant_m.powi(2),
            max_range2: rules.max_range_m.powi(2),
        };
        if let Some(information) = view.information(table, &offsets).filter(|i| *i > 0.0) {
            if best.is_none_or(|(_, b)| 1.0 / information < b) {
                best = Some((heading, 1.0 / information));
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use ubf_perception::error_model::ErrorModelKind;
    use ubf_perception::StereoCamera;

    fn rules() -> DecisionRules {
        DecisionRules { half_fov: 30f64.to_radians(), step_m: 0.25, min_slant_m: 0.5, max_range_m: 80.0 }
    }

    fn table() -> CvTable {
        CvTable::for_camera(ErrorModelKind::Geometric, &StereoCamera::default(), 1.0, 80.0)
    }

    fn headings() -> impl Iterator<Item = f64> {
        (-9..=9).map(|i| f64::from(i) * 5f64.to_radians())
    }

    #[test]
    fn prefers_putting_a_landmark_off_centre_and_near() {
        let t = table();
        // One landmark 10 m ahead, 2 m left: looking straight at it is the
        // worst choice; turning so it sits near the edge of the view is best.
        let (heading, cv) = best_heading(&t, &rules(), &[(10.0, 2.0)], (0.0, 0.0), headings()).unwrap();
        let straight_at = 2f64.atan2(10.0);
        assert!((heading - straight_at).abs() > 15f64.to_radians(), "{}", heading.to_degrees());
        assert!(cv < 1.0 / t.information(0.0, 10.0));
    }

    #[test]
    fn bucketing_changes_nothing() {
        use rand::{Rng, SeedableRng};
        let t = table();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        for _ in 0..50 {
            let landmarks: Vec<(f64, f64)> =
                (0..300).map(|_| (rng.random_range(-20.0..60.0), rng.random_range(-8.0..8.0))).collect();
            let at = (rng.random_range(0.0..40.0), rng.random_range(-2.0..2.0));
            let heads: Vec<f64> = (-36..=36).map(|k| f64::from(k) * 2.5f64.to_radians() + 0.3).collect();
            let fast = best_heading(&t, &rules(), &landmarks, at, heads.iter().copied());
            let slow = best_heading_exhaustive(&t, &rules(), &landmarks, at, heads.iter().copied());
            match (fast, slow) {
                (Some(a), Some(b)) => {
                    assert_eq!(a.0, b.0);
                    assert!((a.1 / b.1 - 1.0).abs() < 1e-9);
                }
                (a, b) => assert_eq!(a, b),
            }
        }
    }

    #[test]
    fn rejects_headings_without_landmarks_or_with_one_too_near() {
        let t = table();
        // Only landmark far to the left, out of view for right headings.
        let (heading, _) = best_heading(&t, &rules(), &[(5.0, 4.0)], (0.0, 0.0), headings()).unwrap();
        assert!(heading > 0.0);
        // A landmark right in front is an obstacle: straight ahead is out;
        // 34° left puts it out of view and a far landmark in.
        let landmarks = [(0.6, 0.0), (20.0, -5.0), (20.0, 5.0)];
        let (heading, _) = best_heading(&t, &rules(), &landmarks, (0.0, 0.0), [0.0, 0.6]).unwrap();
        assert_eq!(heading, 0.6);
        assert!(best_heading(&t, &rules(), &[], (0.0, 0.0), headings()).is_none());
    }
}
