//! How far the robot goes for each metre its odometry counts, as the
//! visual steps put it: a wheel-scale calibration made while driving, so
//! that odometry's forward motion can be fused without carrying a wheel
//! radius that is a percent off into every step.

/// Odometry's distances times `factor` are the distances driven, to within
/// `sigma` (a share of the distance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WheelScale {
    /// Metres driven per metre odometry counts.
    pub factor: f64,
    /// The factor's standard error.
    pub sigma: f64,
}

/// The weighted least-squares fit of `visual ≈ factor · odometric` over
/// the forward motions of the steps egomotion took.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct WheelScaleFit {
    /// Σ w·o·v, Σ w·o², Σ w·v² and the readings they sum.
    ov: f64,
    oo: f64,
    vv: f64,
    readings: usize,
    /// The keyframes the readings were measured from, counted each time
    /// the anchor changes, and the latest. Steps alternating between two
    /// keyframes count each switch; counting distinct keyframes instead
    /// settled the fit later and, on training layouts, left the route with
    /// a 20 m featureless stretch a quarter further off at its end (0.098
    /// against 0.124 m), and needing only three of them lost the synthetic
    /// test in `odometry.rs`, so the count stays as it is.
    anchors: usize,
    anchor: Option<u64>,
}

/// Keyframes the fit's readings must come from before it is used, so
/// that one keyframe's wrong depths do not set the scale.
const SETTLED_ANCHORS: usize = 5;

/// The smallest standard error the fit claims. The steps are measured
/// against keyframes they share, so their errors are not independent and
/// the fit's own figure is optimistic; half a percent is what a wheel's
/// load and tyre pressure move its radius by over a drive anyway.
const SIGMA_FLOOR: f64 = 0.005;

impl WheelScaleFit {
    /// Takes in one step from keyframe `anchor`: the visual forward motion
    /// `visual` m with variance `variance` m², against odometry's
    /// `odometric` m over the same stretch, whose own error has variance
    /// `odometric_variance`.
    pub(super) fn add(&mut self, anchor: u64, visual: f64, variance: f64, odometric: f64, odometric_variance: f64) {
        let weight = 1.0 / (variance + odometric_variance);
        if !weight.is_finite() || !visual.is_finite() {
            return;
        }
        if self.anchor.replace(anchor) != Some(anchor) {
            self.anchors += 1;
        }
        self.ov += weight * odometric * visual;
        self.oo += weight * odometric * odometric;
        self.vv += weight * visual * visual;
        self.readings += 1;
    }

    /// The scale so far, once it rests on enough keyframes; its error is
    /// widened by how much more the readings scatter than their variances
    /// say, and by how many readings share a keyframe (they share its
    /// landmarks' depth errors, so a keyframe's readings count as one).
    pub(super) fn scale(&self) -> Option<WheelScale> {
        if self.anchors < SETTLED_ANCHORS || self.readings < 2 || self.oo <= 0.0 {
            return None;
        }
        let factor = self.ov / self.oo;
        let chi2 = (self.vv - factor * self.ov).max(0.0);
        let dispersion = (chi2 / (self.readings - 1) as f64).max(1.0);
        let shared = self.readings as f64 / self.anchors as f64;
        Some(WheelScale { factor, sigma: (dispersion * shared / self.oo).sqrt().max(SIGMA_FLOOR) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn wheels_a_percent_long_are_found_from_noisy_steps() {
        // Odometry counts 1 % more than the robot drives; each visual step
        // of 1–5 m is off by 10 cm.
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut fit = WheelScaleFit::default();
        for i in 0..200u64 {
            let driven = rng.random_range(1.0..5.0);
            let noise: f64 = (0..12).map(|_| rng.random::<f64>()).sum::<f64>() - 6.0;
            fit.add(i, driven + 0.1 * noise, 0.01, driven * 1.01, 1e-4);
            if i + 1 < SETTLED_ANCHORS as u64 {
                assert!(fit.scale().is_none());
            }
        }
        let scale = fit.scale().unwrap();
        assert!((scale.factor - 1.0 / 1.01).abs() < 2.0 * scale.sigma, "{scale:?}");
        assert!(scale.sigma < 0.01, "{scale:?}");
        // Readings that scatter ten times more than they claim widen it.
        let mut wild = WheelScaleFit::default();
        for i in 0..200u64 {
            let driven = 1.0 + (i % 5) as f64;
            wild.add(i, driven * if i % 2 == 0 { 1.1 } else { 0.9 }, 1e-4, driven, 1e-6);
        }
        assert!(wild.scale().unwrap().sigma > 0.005, "{:?}", wild.scale());
    }
}
