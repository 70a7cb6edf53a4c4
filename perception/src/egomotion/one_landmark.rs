//! A step on one landmark: with `Sideways` fusion, odometry's position over
//! the stretch (as the fusion takes it) and the landmark's line of sight
//! for the turn.
//!
//! The rigid estimator needs two landmarks to fix a motion (three without
//! fusion). Where a short
//! detection range or walls seen only obliquely leave one in view at a
//! time, those frames were bridged on odometry, turn and all, and its
//! heading slip went into the pose unmeasured. Odometry's position fixes
//! the translation well over a few metres; one landmark's bearing then
//! fixes the turn, and the fit leaves one dimension (its depth along the
//! line against odometry's distance) to test the match by.

use super::odometry::{OdometryGate, Stretch};
use super::rigid::{residual_information, Pixels, Rigid, PAIR_GATE};
use super::step::{Pair, PlanarMotion};
use super::wheel_calibration::WheelScale;
use crate::stereo::StereoCamera;
use nalgebra::{Matrix3, Vector2, Vector3};
use ubf_core::angle_difference;

/// χ² with 1 degree of freedom at 99.9 %: the turn against odometry's, one
/// consistent step in a thousand rejected, as the gate's own threshold.
const TURN_GATE: f64 = 10.83;

/// The motion over `stretch` that best fits `pair` (a landmark seen before
/// and after, in the robot frame) and what `Sideways` fusion takes of
/// odometry, its covariance, and the share of odometry's forward and
/// sideways distance in it; `None` if the landmark's line of sight does
/// not fit odometry's position, or the turn it gives odometry's turn,
/// within their errors (a wrong match, a stereo mismatch), or if `gate`
/// has no noise model to fuse by.
pub(super) fn step(
    camera: &StereoCamera,
    pixel_sigma: f64,
    pair: &Pair,
    gate: &OdometryGate,
    stretch: &Stretch,
    wheel_scale: Option<WheelScale>,
) -> Option<(PlanarMotion, Matrix3<f64>, Vector2<f64>)> {
    let noise = gate.noise.as_ref()?;
    let odometry = noise.sideways_measure(stretch, wheel_scale);
    let odometry_info = odometry.information();
    let counted = odometry.motion;
    // The later line of sight is laid by odometry's turn, as the rigid
    // estimator lays it.
    let pairs = [*pair];
    let info = [residual_information(camera, Pixels(pixel_sigma), pair.before, pair.after, counted.theta)];
    // The information, gradient and cost of the landmark's residual and
    // odometry's measure together at `motion`.
    let evaluate = |motion: &PlanarMotion| {
        let (h, g, landmark_cost) =
            Rigid::normal_equations(&pairs, &info, motion.yaw, Vector2::new(motion.forward, motion.left));
        let residual = odometry.residual(motion);
        let cost = landmark_cost + (residual.transpose() * odometry.precision * residual)[0];
        (h + odometry_info, g + odometry.measures.transpose() * odometry.precision * residual, cost)
    };
    // Gauss–Newton from odometry's motion.
    let mut motion = PlanarMotion { forward: counted.x, left: counted.y, yaw: counted.theta };
    for _ in 0..8 {
        let (information, gradient, _) = evaluate(&motion);
        let step: Vector3<f64> = information.lu().solve(&(-gradient))?;
        motion =
            PlanarMotion { forward: motion.forward + step[0], left: motion.left + step[1], yaw: motion.yaw + step[2] };
        if step.norm() < 1e-9 {
            break;
        }
    }
    let (information, _, cost) = evaluate(&motion);
    if !(cost <= PAIR_GATE && motion.yaw.is_finite() && gate.within_bounds(&motion, stretch)) {
        return None;
    }
    let covariance = information.try_inverse()?;
    // The turn is the landmark's alone: it must agree with odometry's as
    // far as odometry's heading errs over the stretch.
    let turn = angle_difference(motion.yaw, counted.theta);
    let turn_variance = covariance[(2, 2)] + noise.covariance(stretch.driven())[(2, 2)];
    if turn * turn > TURN_GATE * turn_variance {
        return None;
    }
    let gain = covariance * odometry_info;
    Some((motion, covariance, Vector2::new(gain[(0, 0)], gain[(1, 1)])))
}

#[cfg(test)]
mod tests {
    use super::*;
    use ubf_core::Pose2;

    /// A landmark at `point` (robot frame at the stretch's start) as seen
    /// from `pose` there.
    fn seen_from(point: [f64; 3], pose: Pose2) -> [f64; 3] {
        let (s, c) = pose.theta.sin_cos();
        let (dx, dy) = (point[0] - pose.x, point[1] - pose.y);
        [c * dx + s * dy, -s * dx + c * dy, point[2]]
    }

    /// One metre driven while the heading drifted by `drift` (rad) unseen:
    /// the true end, and odometry's stretch, which counted it straight.
    fn drifting(drift: f64) -> (Pose2, Stretch) {
        let truth = Pose2::new(1.0, 0.5 * drift, drift);
        let stretch = Stretch { motion: Pose2::new(1.0, 0.0, 0.0), drift_lever: Vector2::new(0.0, 0.5) };
        (truth, stretch)
    }

    fn step_on(pair: &Pair, stretch: &Stretch) -> Option<(PlanarMotion, Matrix3<f64>, Vector2<f64>)> {
        let gate = OdometryGate::default();
        step(&StereoCamera::default(), 0.3, pair, &gate, stretch, None)
    }

    const LANDMARK: [f64; 3] = [6.0, 2.0, 1.0];

    #[test]
    fn one_landmark_gives_the_turn_odometry_missed() {
        let drift = 0.6f64.to_radians();
        let (truth, stretch) = drifting(drift);
        let pair = Pair::new(LANDMARK, seen_from(LANDMARK, truth), 1.0);
        let (motion, covariance, gain) = step_on(&pair, &stretch).expect("a true match fits");
        assert!((motion.yaw - drift).abs() < 0.01f64.to_radians(), "{}°", motion.yaw.to_degrees());
        assert!((motion.forward - truth.x).hypot(motion.left - truth.y) < 1e-3, "{motion:?}");
        // The turn is as sure as odometry's position across the landmark's
        // line of sight over its range: 3 cm at 5.5 m, about 0.3°.
        let across = 0.03 / (LANDMARK[0] - truth.x).hypot(LANDMARK[1] - truth.y);
        let sigma = covariance[(2, 2)].sqrt();
        assert!(
            (0.8 * across..1.2 * across).contains(&sigma),
            "{}° against {}°",
            sigma.to_degrees(),
            across.to_degrees()
        );
        // The distance is mostly odometry's.
        assert!(gain[0] > 0.5, "{gain}");
    }

    #[test]
    fn a_landmark_that_does_not_fit_odometry_is_no_step() {
        let (truth, stretch) = drifting(0.3f64.to_radians());
        // Another landmark, a metre further on (a wrong match).
        let other = Pair::new(LANDMARK, seen_from([7.0, 2.0, 1.0], truth), 1.0);
        assert!(step_on(&other, &stretch).is_none());
        // The same one triangulated half as far again (a stereo mismatch).
        let [x, y, z] = seen_from(LANDMARK, truth);
        let mismatched = Pair::new(LANDMARK, [1.5 * x, 1.5 * y, z], 1.0);
        assert!(step_on(&mismatched, &stretch).is_none());
    }

    #[test]
    fn a_turn_odometry_could_not_have_missed_is_no_step() {
        // Over one metre odometry's heading errs by about 0.28°: 0.6° fits,
        // 2° does not (a landmark that moved, or a wrong match whose
        // bearing alone differs).
        for (drift_deg, fits) in [(0.6, true), (2.0, false)] {
            let (truth, stretch) = drifting(f64::to_radians(drift_deg));
            let pair = Pair::new(LANDMARK, seen_from(LANDMARK, truth), 1.0);
            assert_eq!(step_on(&pair, &stretch).is_some(), fits, "{drift_deg}°");
        }
    }
}
