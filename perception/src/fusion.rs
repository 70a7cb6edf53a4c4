//! Combining uncertain measurements (thesis §2.2).

/// The CV of the weighted average of measurements with these CVs (eq. 6
/// applied repeatedly): `1/CV_T = Σ 1/CV_i`. More landmarks never make it
/// worse. `None` without any finite, positive CV: no measurement at all.
pub fn fuse_cv(cvs: impl IntoIterator<Item = f64>) -> Option<f64> {
    let inverse: f64 = cvs.into_iter().filter(|cv| cv.is_finite() && *cv > 0.0).map(|cv| 1.0 / cv).sum();
    (inverse > 0.0).then(|| 1.0 / inverse)
}

/// The weighted average of measurements `(value, cv)` (eq. 5 applied
/// repeatedly): each weighs `1/CV`. `None` without a usable measurement.
pub fn weighted_mean(measurements: impl IntoIterator<Item = (f64, f64)>) -> Option<f64> {
    let (sum, weight) = measurements
        .into_iter()
        .filter(|(v, cv)| v.is_finite() && cv.is_finite() && *cv > 0.0)
        .fold((0.0, 0.0), |(s, w), (v, cv)| (s + v / cv, w + 1.0 / cv));
    (weight > 0.0).then(|| sum / weight)
}

/// The weighted median of `(value, CV)` measurements, weights 1/CV: half the
/// weight lies on either side. Unlike the mean, a few wild measurements
/// cannot move it far.
pub fn weighted_median(measurements: impl IntoIterator<Item = (f64, f64)>) -> Option<f64> {
    let mut votes: Vec<(f64, f64)> = measurements
        .into_iter()
        .filter(|(v, cv)| v.is_finite() && cv.is_finite() && *cv > 0.0)
        .map(|(v, cv)| (v, 1.0 / cv))
        .collect();
    votes.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = votes.iter().map(|v| v.1).sum();
    let mut below = 0.0;
    for (value, weight) in &votes {
        below += weight;
        if below >= total / 2.0 {
            return Some(*value);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_weighted_median_ignores_a_wild_vote() {
        // Four votes near 0.25 m and one at 7.9 m from a near landmark whose
        // small CV weighs more than any other (thesis Table 2's −7.90): the
        // mean is dragged metres off, the median is not.
        let votes = [(0.24, 1.0), (0.26, 1.0), (0.25, 1.0), (0.27, 1.0), (7.9, 0.4)];
        assert!(weighted_mean(votes).unwrap() > 3.0);
        assert_eq!(weighted_median(votes), Some(0.27));
        assert_eq!(weighted_median([]), None);
    }

    #[test]
    fn two_measurements_follow_equations_5_and_6() {
        let (cv1, cv2, z1, z2) = (2.0, 3.0, 10.0, 20.0);
        assert!((fuse_cv([cv1, cv2]).unwrap() - cv1 * cv2 / (cv1 + cv2)).abs() < 1e-12);
        let eq5 = cv2 / (cv1 + cv2) * z1 + cv1 / (cv1 + cv2) * z2;
        assert!((weighted_mean([(z1, cv1), (z2, cv2)]).unwrap() - eq5).abs() < 1e-12);
    }

    #[test]
    fn more_landmarks_never_hurt_and_none_is_none() {
        let one = fuse_cv([1.0]).unwrap();
        assert!(fuse_cv([1.0, 100.0]).unwrap() < one);
        assert_eq!(fuse_cv([]), None);
        assert_eq!(fuse_cv([f64::INFINITY, f64::NAN]), None);
    }
}
