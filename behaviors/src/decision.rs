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

/// The best heading among `candidates` (world angles) for a robot at
/// `position` among `landmarks` (world floor positions): the one whose fused
/// CV (eq. 6) over the landmarks in view after one projected step is least.
/// A heading with no landmark in view (egomotion would fail) or one nearer
/// than the slant limit is rejected. Ties go to the candidate listed first.
/// Returns the heading and its fused CV, or `None` if every heading is
/// rejected.
pub fn best_heading(
    table: &CvTable,
    rules: &DecisionRules,
    landmarks: &[(f64, f64)],
    position: (f64, f64),
    candidates: impl IntoIterator<Item = f64>,
) -> Option<(f64, f64)> {
    let tan_half = rules.half_fov.tan();
    let (min_slant2, max_range2) = (rules.min_slant_m.powi(2), rules.max_range_m.powi(2));
    let mut best: Option<(f64, f64)> = None;
    'candidates: for heading in candidates {
        let (s, c) = heading.sin_cos();
        // Eq. 40–43: the robot projected one step ahead.
        let (px, py) = (position.0 + rules.step_m * c, position.1 + rules.step_m * s);
        let mut information = 0.0;
        for &(lx, ly) in landmarks {
            let (dx, dy) = (lx - px, ly - py);
            // Eq. 44–48 without trigonometry: depth along the heading,
            // lateral offset to the right.
            let depth = dx * c + dy * s;
            let lateral = dx * s - dy * c;
            if depth <= 0.0 || lateral.abs() > depth * tan_half {
                continue;
            }
            let range2 = depth * depth + lateral * lateral;
            if range2 < min_slant2 {
                continue 'candidates;
            }
            if range2 <= max_range2 {
                information += table.information(lateral, depth);
            }
        }
        if information > 0.0 {
            let cv = 1.0 / information;
            if best.is_none_or(|(_, b)| cv < b) {
                best = Some((heading, cv));
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
