//! The egomotion settings, as written in a scenario file: which estimator
//! and its settings, matching, the keyframe bank and the odometry checks.

use super::matching::MatchConfig;
use super::odometry::{OdometryFusion, OdometryGate};
use super::step::StepEstimator;
use crate::error_model::ErrorModelKind;
use serde::Deserialize;
use ubf_core::config::{non_negative, positive};

/// Settings of the thesis's simplified estimator.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Simple2dConfig {
    /// A range change above this means translation, m.
    #[serde(deserialize_with = "non_negative")]
    pub translation_threshold_m: f64,
    /// A bearing change above this means rotation, °.
    #[serde(deserialize_with = "non_negative")]
    pub rotation_threshold_deg: f64,
    /// Rotation compensation RC (eq. 60); the thesis left it at 1.
    #[serde(deserialize_with = "positive")]
    pub rc: f64,
    /// Translation compensation TC (eq. 61); the thesis left it at 1.
    #[serde(deserialize_with = "positive")]
    pub tc: f64,
    /// The fixes the estimator needs to survive a robot that turns: the
    /// motion type taken from the commanded phase (a turn on the spot, or a
    /// straight step) where it is known, a translation threshold scaled to
    /// each landmark's depth noise, weighted medians instead of means (one
    /// near-triangulated outlier cannot capture the estimate), and a
    /// range-consistency gate around the median. `false` is the estimator
    /// exactly as §4.4.7 describes it.
    pub robust: bool,
    /// Pixel noise assumed when scaling the threshold and the gate, px.
    #[serde(deserialize_with = "positive")]
    pub pixel_sigma: f64,
}

impl Default for Simple2dConfig {
    fn default() -> Self {
        Simple2dConfig {
            translation_threshold_m: 0.02,
            rotation_threshold_deg: 0.3,
            rc: 1.0,
            tc: 1.0,
            robust: true,
            pixel_sigma: 0.3,
        }
    }
}

/// Settings of the rigid estimator.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RigidConfig {
    /// RANSAC draws of two matches.
    pub iterations: u32,
    /// Pixel noise assumed when judging residuals, px.
    #[serde(deserialize_with = "positive")]
    pub pixel_sigma: f64,
}

impl Default for RigidConfig {
    fn default() -> Self {
        RigidConfig { iterations: 64, pixel_sigma: 0.3 }
    }
}

/// Whether egomotion estimates the stereo rig's disparity offset from the
/// frames themselves, and whether it corrects the landmarks by it.
///
/// A rectification that leaves every disparity off by a fraction of a
/// pixel δ inflates (or shrinks) each depth by about δ / d, so far
/// landmarks (small disparity d) by more than near ones: the steps come
/// out too long or too short, and by more the farther the landmarks. The
/// rigid estimator reads δ from each step as the offset that lets its near
/// and far landmarks agree on one motion; the readings are pooled over the
/// drive (a median weighed by each reading's precision, see
/// [`crate::egomotion::Tracker::disparity_offset`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
pub enum DisparityOffsetEstimate {
    /// No estimate: the calibration's offset is taken as it is.
    #[default]
    Off,
    /// Estimated and reported, the landmarks left as the calibration puts
    /// them: what a user reads off to put in `camera.ron`
    /// (`ubf pipeline --keep-disparity-offset`).
    Report,
    /// Estimated, reported, and each step's landmarks corrected by the
    /// estimate so far once it rests on enough steps (`ubf pipeline`'s
    /// default on recorded frames).
    Correct,
}

/// Which estimator, as written in a scenario file.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum EstimatorKind {
    /// The thesis's simplified 2D estimator.
    Simple2d(#[serde(default)] Simple2dConfig),
    /// Weighted Kabsch inside RANSAC.
    Rigid(#[serde(default)] RigidConfig),
}

impl EstimatorKind {
    /// The estimator these settings choose.
    pub(super) fn estimator(&self) -> &dyn StepEstimator {
        match self {
            EstimatorKind::Simple2d(config) => config,
            EstimatorKind::Rigid(config) => config,
        }
    }
}

impl Default for EstimatorKind {
    fn default() -> Self {
        EstimatorKind::Rigid(RigidConfig::default())
    }
}

/// The egomotion settings, as written in a scenario file.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EgomotionConfig {
    /// The estimator.
    pub estimator: EstimatorKind,
    /// The error model weighting landmarks and giving step CVs.
    pub model: ErrorModelKind,
    /// Descriptor matching between frames.
    pub matching: MatchConfig,
    /// Reference frames (keyframes) kept from distinct viewpoints, each a
    /// frame new ones can be matched against.
    #[serde(deserialize_with = "at_least_one")]
    pub keyframes: usize,
    /// A frame becomes a keyframe when the robot is at least this far from
    /// every keyframe, m…
    #[serde(deserialize_with = "positive")]
    pub keyframe_spacing_m: f64,
    /// …or turned at least this far from every keyframe's heading, °.
    #[serde(deserialize_with = "positive")]
    pub keyframe_spacing_deg: f64,
    /// A keyframe is retired once the robot has driven this far from it:
    /// little of what it saw is still in view, m.
    #[serde(deserialize_with = "positive")]
    pub keyframe_range_m: f64,
    /// A match to a keyframe is trusted outright with at least this many
    /// consistent landmarks; with fewer (but enough for the estimator) the
    /// next keyframe is tried and the best match kept.
    #[serde(deserialize_with = "at_least_one")]
    pub good_match_landmarks: usize,
    /// A step resting on fewer consistent landmarks than this is not
    /// trusted at its estimator's word: it is reported as starving
    /// ([`crate::egomotion::Tracker::starving`]) and its covariance is
    /// scaled up by this over the landmarks it has in the pose's
    /// uncertainty ([`crate::egomotion::Tracker::pose_covariance`]). A step
    /// on one landmark with `Sideways` fusion, whose translation is
    /// odometry's and whose turn is as sure as that allows, is reported as
    /// starving but not widened.
    #[serde(deserialize_with = "at_least_one")]
    pub trusted_landmarks: usize,
    /// The robot's top speed: motions faster than this are impossible and
    /// rejected (thesis §4.4.6), m/s.
    #[serde(deserialize_with = "positive")]
    pub max_speed: f64,
    /// Rejects a visual motion that disagrees with odometry's by more than
    /// odometry can err over the same stretch: a wrong consensus of far
    /// landmarks. `None` turns the check off (pure egomotion).
    pub odometry_gate: Option<OdometryGate>,
    /// The robot's top turn rate: turns faster than this, or wider than
    /// the field of view, are impossible between frames that share
    /// landmarks and rejected, °/s.
    #[serde(deserialize_with = "positive")]
    pub max_turn_rate_deg: f64,
    /// Whether each visual motion that passes the odometry gate is
    /// combined with odometry's over the same stretch, weighed by the
    /// estimator's covariance and the gate's `noise` model (the rigid
    /// estimator only; without a gate or its `noise` nothing is combined).
    /// `Sideways` by default; `Off` keeps egomotion purely visual.
    pub odometry_fusion: OdometryFusion,
    /// Navigate by egomotion: the robot's pose that behaviours steer by
    /// becomes egomotion's pose at the newest frame, carried on by what
    /// odometry says the robot did since, combined with odometry's own by
    /// their covariances ([`crate::egomotion::Tracker::navigation_pose`]),
    /// instead of odometry alone. On by default, so that behaviours steer
    /// by the best estimate there is; the thesis's robot navigated by
    /// odometry (`false`), and a veer odometry does not see then walks the
    /// robot off its line.
    pub navigate: bool,
    /// Whether the rig's disparity offset is estimated from the frames
    /// (the rigid estimator only), and whether the landmarks are corrected
    /// by the estimate. `Off` by default: the simulated camera has no
    /// offset, and reading it costs a sweep about a tenth of its time; a
    /// real rig's is read (and corrected) on its recorded frames by
    /// `ubf pipeline`.
    pub disparity_offset: DisparityOffsetEstimate,
}

fn at_least_one<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<usize, D::Error> {
    let n = usize::deserialize(deserializer)?;
    if n == 0 {
        return Err(serde::de::Error::custom("must be at least 1"));
    }
    Ok(n)
}

impl EgomotionConfig {
    /// Whether the steps really take odometry's motion in: `odometry_fusion`
    /// not `Off`, with the rigid estimator and a gate that has a `noise`
    /// model (without them nothing is combined, whatever the setting).
    pub fn fuses_odometry(&self) -> bool {
        self.odometry_fusion != OdometryFusion::Off
            && matches!(self.estimator, EstimatorKind::Rigid(_))
            && self.odometry_gate.as_ref().is_some_and(|g| g.noise.is_some())
    }

    /// Whether the steps take odometry's sideways motion (and distance)
    /// in and leave vision the turn: `Sideways` fusion, really combined.
    /// Only then are the wheels' scale and veer measured.
    pub fn fuses_sideways(&self) -> bool {
        self.odometry_fusion == OdometryFusion::Sideways && self.fuses_odometry()
    }
}

impl Default for EgomotionConfig {
    fn default() -> Self {
        EgomotionConfig {
            estimator: EstimatorKind::default(),
            model: ErrorModelKind::default(),
            matching: MatchConfig::default(),
            keyframes: 10,
            keyframe_spacing_m: 1.0,
            keyframe_spacing_deg: 15.0,
            keyframe_range_m: 10.0,
            good_match_landmarks: 6,
            trusted_landmarks: 20,
            max_speed: 0.6,
            max_turn_rate_deg: 100.0,
            odometry_gate: Some(OdometryGate::default()),
            odometry_fusion: OdometryFusion::Sideways,
            navigate: true,
            disparity_offset: DisparityOffsetEstimate::Off,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odometry_is_fused_only_where_the_steps_can_combine_it() {
        let default = EgomotionConfig::default();
        assert!(default.fuses_odometry());
        let off = EgomotionConfig { odometry_fusion: OdometryFusion::Off, ..default };
        let simple = EgomotionConfig { estimator: EstimatorKind::Simple2d(Simple2dConfig::default()), ..default };
        let no_gate = EgomotionConfig { odometry_gate: None, ..default };
        let gate_without_noise = OdometryGate { noise: None, ..OdometryGate::default() };
        let no_noise = EgomotionConfig { odometry_gate: Some(gate_without_noise), ..default };
        for (name, config) in [("Off", off), ("Simple2d", simple), ("no gate", no_gate), ("no noise", no_noise)] {
            assert!(!config.fuses_odometry(), "{name}");
        }
    }
}
