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

/// Bearing buckets over the full circle: one degree each.
const BUCKETS: usize = 360;
/// Landmarks nearer than this many steps are looked at by every candidate:
/// the step can swing their bearing too far.
const NEAR_STEPS: f64 = 4.0;
/// Farther landmarks fall into bands of distance, each twice as far out as
/// the one before, the last unbounded: the farther a landmark, the less one
/// step swings its bearing, so the narrower the window a candidate reads.
const BANDS: usize = 4;

/// The best heading among `candidates` (world angles) for a robot at
/// `position` among `landmarks` (world floor positions): the one whose fused
/// CV (eq. 6) over the landmarks in view after one projected step is least.
/// A heading with no landmark in view (egomotion would fail) or one nearer
/// than the slant limit is rejected. Ties go to the candidate listed first.
/// Returns the heading and its fused CV, or `None` if every heading is
/// rejected.
///
/// For speed, landmarks are sorted once by distance band and bearing, and
/// each candidate reads, in each band, only the bearings its field of view
/// can reach from the projected position (from `d` away, a step of `s`
/// moves a bearing by at most `asin(s/d)`).
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
    let bucket_width = TAU / BUCKETS as f64;
    // For an angle in [0, 2π].
    let bucket_of = |angle: f64| ((angle / bucket_width) as usize).min(BUCKETS - 1);
    // Keys: band × BUCKETS + bucket for far landmarks, then one key for the
    // near ones. Offsets from the robot are computed once: from the
    // projected position a landmark's depth is `d·u − step` and its lateral
    // offset `d·n`.
    const NEAR: usize = BANDS * BUCKETS;
    let near2 = (NEAR_STEPS * rules.step_m).powi(2);
    let key_of = |dx: f64, dy: f64| {
        let distance2 = dx * dx + dy * dy;
        if distance2 < near2 {
            return NEAR;
        }
        let mut band = 0;
        while band + 1 < BANDS && distance2 >= near2 * f64::from(4u32 << (2 * band)) {
            band += 1;
        }
        // In [−π, π]: one add instead of `rem_euclid`'s division.
        let bearing = fast_atan2(dy, dx);
        band * BUCKETS + bucket_of(if bearing < 0.0 { bearing + TAU } else { bearing })
    };
    // A counting sort by key.
    let mut starts = vec![0usize; NEAR + 2];
    let mut keys = Vec::with_capacity(landmarks.len());
    for &(lx, ly) in landmarks {
        let key = key_of(lx - position.0, ly - position.1);
        starts[key + 1] += 1;
        keys.push(key);
    }
    for k in 0..=NEAR {
        starts[k + 1] += starts[k];
    }
    let mut fill = starts.clone();
    let mut sorted = vec![(0.0, 0.0); landmarks.len()];
    for (&(lx, ly), &key) in landmarks.iter().zip(&keys) {
        sorted[fill[key]] = (lx - position.0, ly - position.1);
        fill[key] += 1;
    }
    let nearby = &sorted[starts[NEAR]..starts[NEAR + 1]];
    // Each band's half-window in buckets; one more for the quantisation of
    // the heading's and the landmark's bearings, and one for the error of
    // the fast arctangent, which can put a bearing in the next bucket.
    let spans: [usize; BANDS] = std::array::from_fn(|band| {
        let reach = rules.half_fov + (1.0 / (NEAR_STEPS * f64::from(1u32 << band))).asin();
        (reach / bucket_width).ceil() as usize + 2
    });

    let mut best: Option<(f64, f64)> = None;
    for heading in candidates {
        let (s, c) = heading.sin_cos();
        // Eq. 40–43: the robot projected one step ahead along the heading.
        let view = View { sin: s, cos: c, step: rules.step_m, tan_half, min_slant2, max_range2 };
        let centre = bucket_of(heading.rem_euclid(TAU));
        let mut information = view.information(table, nearby);
        for (band, &span) in spans.iter().enumerate() {
            let Some(sum) = information else { break };
            let within = |from: usize, to: usize| &sorted[starts[band * BUCKETS + from]..starts[band * BUCKETS + to]];
            // The window is one run of the band, or two where it wraps.
            let runs: [&[(f64, f64)]; 2] = if 2 * span + 1 >= BUCKETS {
                [within(0, BUCKETS), &[]]
            } else {
                let (lo, hi) = ((centre + BUCKETS - span) % BUCKETS, (centre + span) % BUCKETS);
                if lo <= hi {
                    [within(lo, hi + 1), &[]]
                } else {
                    [within(lo, BUCKETS), within(0, hi + 1)]
                }
            };
            information = runs.iter().try_fold(sum, |sum, run| Some(sum + view.information(table, run)?));
        }
        if let Some(information) = information.filter(|i| *i > 0.0) {
            let cv = 1.0 / information;
            if best.is_none_or(|(_, b)| cv < b) {
                best = Some((heading, cv));
            }
        }
    }
    best
}

/// `atan2(y, x)` within 2e-5 rad, several times faster than the exact one:
/// the polynomial of Abramowitz and Stegun 4.4.49 on `[0, 1]`, extended by
/// symmetry. Good enough to pick a one-degree bucket give or take one.
fn fast_atan2(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    let (ax, ay) = (x.abs(), y.abs());
    if ax == 0.0 && ay == 0.0 {
        return 0.0;
    }
    let z = ax.min(ay) / ax.max(ay);
    let z2 = z * z;
    let atan = z * (0.999_866_0 + z2 * (-0.330_299_5 + z2 * (0.180_141_0 + z2 * (-0.085_133_0 + z2 * 0.020_835_1))));
    let first_octant_folded = if ay > ax { FRAC_PI_2 - atan } else { atan };
    let half_plane = if x < 0.0 { PI - first_octant_folded } else { first_octant_folded };
    if y < 0.0 {
        -half_plane
    } else {
        half_plane
    }
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
    fn fast_arctangent_is_within_its_bound() {
        let mut worst: f64 = 0.0;
        for k in 0..100_000 {
            let angle = f64::from(k) * 1e-4 - 5.0;
            for r in [1e-3, 1.0, 70.0] {
                let (y, x) = (r * angle.sin(), r * angle.cos());
                worst = worst.max((fast_atan2(y, x) - y.atan2(x)).abs());
            }
        }
        assert!(worst < 2e-5, "{worst}");
        assert_eq!(fast_atan2(0.0, 0.0), 0.0);
        assert!((fast_atan2(0.0, -1.0) - std::f64::consts::PI).abs() < 1e-5);
    }

    #[test]
    fn indexing_changes_nothing() {
        // Every heading on its own, so a landmark missed by any window would
        // show: corridors of many landmarks, and sparse landmarks all round
        // at every distance band with headings all round the circle.
        use rand::{Rng, SeedableRng};
        let t = table();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        for round in 0..100 {
            let (count, radius) = if round % 2 == 0 { (300, 0.0) } else { (rng.random_range(1..12), 30.0) };
            let landmarks: Vec<(f64, f64)> = (0..count)
                .map(|_| match radius {
                    0.0 => (rng.random_range(-20.0..60.0), rng.random_range(-8.0..8.0)),
                    r => {
                        let (d, a) = (rng.random_range(0.3f64..r), rng.random_range(-4.0f64..4.0));
                        (d * a.cos(), d * a.sin())
                    }
                })
                .collect();
            let at = (rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
            for k in -80..=80 {
                let heading = [f64::from(k) * 2.5f64.to_radians() + rng.random_range(-0.02..0.02)];
                let fast = best_heading(&t, &rules(), &landmarks, at, heading);
                let slow = best_heading_exhaustive(&t, &rules(), &landmarks, at, heading);
                match (fast, slow) {
                    (Some(a), Some(b)) => assert!((a.1 / b.1 - 1.0).abs() < 1e-9, "{round} {k}"),
                    (a, b) => assert_eq!(a, b, "{round} {k}"),
                }
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
