//! The thesis's simplified 2D estimator (§4.4.7): each matched landmark
//! votes for a translation or a rotation.

use super::config::Simple2dConfig;
use super::step::{MotionPhase, Mounts, Pair, PlanarMotion, StepEstimator, StepInput, StepMotion};
use crate::fusion::{fuse_cv, weighted_mean, weighted_median};
use crate::stereo::StereoCamera;

/// The thesis's simplified 2D estimator (§4.4.7).
pub struct Simple2d;

impl Simple2d {
    /// The motion the pairs vote for and how many voted for it, or `None`
    /// when no landmark gives a usable vote. `max_step` is the longest
    /// translation possible; `phase` what the robot was commanded to do
    /// since the reference frame.
    pub(super) fn estimate(
        config: &Simple2dConfig,
        camera: &StereoCamera,
        pairs: &[Pair],
        max_step: f64,
        phase: MotionPhase,
    ) -> Option<(PlanarMotion, usize)> {
        // σ of a landmark's range change between two frames.
        let range_sigma = |r: f64| std::f64::consts::SQRT_2 * camera.depth_sigma(r, config.pixel_sigma);
        let mut translation: Vec<(f64, f64, f64)> = Vec::new();
        let mut rotation: Vec<(f64, f64)> = Vec::new();
        let mut stationary: Vec<f64> = Vec::new();
        for p in pairs {
            let ([x0, y0, _], [x1, y1, _]) = (p.before, p.after);
            let range = x0.hypot(y0);
            let range_change = (range - x1.hypot(y1)).abs();
            let threshold = if config.robust {
                config.translation_threshold_m.max(2.0 * range_sigma(range))
            } else {
                config.translation_threshold_m
            };
            if range_change > threshold {
                // Eq. 51, signed: a landmark ahead comes nearer as the robot
                // advances; negative or impossibly fast speeds are noise or
                // moving landmarks (§4.4.6).
                let t = y0 - y1;
                if t >= 0.0 && t <= max_step {
                    translation.push((t, p.cv, range_sigma(range)));
                }
            } else {
                // Eq. 52–54: bearings positive to the right.
                let turned = (x0 / y0).atan() - (x1 / y1).atan();
                if turned.abs() > config.rotation_threshold_deg.to_radians() {
                    rotation.push((turned, p.cv));
                } else if range_change <= config.translation_threshold_m {
                    stationary.push(p.cv);
                }
                // Else the range changed, but within its noise: the landmark
                // cannot tell a short step from standing still, so it
                // abstains.
            }
        }
        if config.robust {
            // Votes far from the median are not the robot's motion.
            if let Some(median) = weighted_median(translation.iter().map(|v| (v.0, v.1))) {
                translation.retain(|v| (v.0 - median).abs() <= 3.0 * v.2);
            }
        }
        let categories = [
            fuse_cv(translation.iter().map(|m| m.1)),
            fuse_cv(rotation.iter().map(|m| m.1)),
            fuse_cv(stationary.iter().copied()),
        ];
        // The commanded phase says which kind of motion it was; otherwise
        // the category with the smallest fused CV wins (eq. 55–58).
        let commanded = match (config.robust, phase) {
            (true, MotionPhase::Turning) => Some(1),
            (true, MotionPhase::Translating) => Some(0),
            _ => None,
        };
        let winner = match commanded.filter(|&k| categories[k].is_some()) {
            Some(k) => k,
            None => {
                categories
                    .iter()
                    .enumerate()
                    .filter_map(|(i, cv)| cv.map(|cv| (i, cv)))
                    .min_by(|a, b| a.1.total_cmp(&b.1))?
                    .0
            }
        };
        let voters = [translation.len(), rotation.len(), stationary.len()][winner];
        let average =
            |votes: Vec<(f64, f64)>| if config.robust { weighted_median(votes) } else { weighted_mean(votes) };
        let motion = match winner {
            0 => PlanarMotion {
                forward: config.tc * average(translation.iter().map(|v| (v.0, v.1)).collect())?,
                ..PlanarMotion::default()
            },
            // Eq. 59: the heading changes by minus the bearing change.
            1 => PlanarMotion { yaw: -config.rc * average(rotation)?, ..PlanarMotion::default() },
            _ => PlanarMotion::default(),
        };
        Some((motion, voters))
    }
}

/// The settings are all the simplified estimator's state, so they carry
/// the trait.
impl StepEstimator for Simple2dConfig {
    /// It reads each step as either a turn or a translation (thesis
    /// §4.4.7), so it is given the newest keyframe first and every matched
    /// frame becomes one; the bank still bridges failed frames without
    /// losing motion.
    fn frame_to_frame(&self) -> bool {
        true
    }

    /// It reads motion in the frame of a camera looking straight ahead.
    fn pair(&self, before: [f64; 3], after: [f64; 3], mounts: &Mounts, cv: f64) -> Pair {
        if mounts.before.looks_ahead() && mounts.after.looks_ahead() {
            return Pair::new(before, after, cv);
        }
        Pair::new(
            mounts.ahead.robot_to_cam(mounts.before.cam_to_robot(before)),
            mounts.ahead.robot_to_cam(mounts.after.cam_to_robot(after)),
            cv,
        )
    }

    fn estimate(&self, pairs: &[Pair], input: StepInput<'_>) -> Option<StepMotion> {
        Simple2d::estimate(self, input.camera, pairs, input.max_step_m, input.phase)
            .map(|(motion, landmarks)| StepMotion { motion, landmarks, covariance: None, inliers: Vec::new() })
    }
}

#[cfg(test)]
mod tests {
    use crate::egomotion::testing::{at, frame, landmarks};
    use crate::egomotion::{EgomotionConfig, EstimatorKind, Simple2dConfig, Tracker};
    use crate::stereo::StereoCamera;
    use ubf_core::{Command, Pose2, Turn};

    #[test]
    fn simple_estimator_follows_rotate_stop_translate_motion() {
        // Translate 0.25 m per frame, then turn 5° per frame, then translate.
        let mut poses = vec![Pose2::default()];
        for _ in 0..4 {
            let p = *poses.last().unwrap();
            poses.push(p.compose(&Pose2::new(0.25, 0.0, 0.0)));
        }
        for _ in 0..3 {
            let p = *poses.last().unwrap();
            poses.push(p.compose(&Pose2::new(0.0, 0.0, 5f64.to_radians())));
        }
        for _ in 0..4 {
            let p = *poses.last().unwrap();
            poses.push(p.compose(&Pose2::new(0.25, 0.0, 0.0)));
        }
        // The robot tells the tracker what it was commanded (as the robot
        // wrapper does), so each step is read as the motion it was.
        let camera = StereoCamera::default();
        let estimator = EstimatorKind::Simple2d(Simple2dConfig::default());
        let mut tracker =
            Tracker::new(EgomotionConfig { estimator, ..EgomotionConfig::default() }, camera, poses[0], 1);
        for (n, pose) in poses.iter().enumerate() {
            let turning = n > 0 && (pose.theta - poses[n - 1].theta).abs() > 1e-9;
            let rate = if turning { 0.17 } else { 0.0 };
            let velocity = if turning || n == 0 { 0.0 } else { 0.5 };
            tracker.commanded(&Command::Drive { velocity, turn: Turn::Rate(rate) });
            tracker.update(&at(n as u64 + 1, n as f64 * 0.5, frame(&landmarks(), *pose, &camera)), pose);
        }
        let (end, truth) = (tracker.state().pose.unwrap(), *poses.last().unwrap());
        assert!(end.distance_to(truth.x, truth.y) < 1e-6, "{end:?} vs {truth:?}");
        assert!((end.theta - truth.theta).abs() < 1e-6, "{end:?} vs {truth:?}");
    }
}
