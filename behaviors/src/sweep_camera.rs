//! Sweep a camera on a pan-tilt unit from side to side.

use serde::Deserialize;
use ubf_core::config::{non_negative, positive};
use ubf_core::{Action, Behavior, State};

/// Settings of [`SweepCamera`], as written in a scenario file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SweepCameraConfig {
    /// How far either side of the heading the sweep goes, °.
    #[serde(deserialize_with = "non_negative")]
    pub amplitude_deg: f64,
    /// Seconds for one sweep left, right and back.
    #[serde(deserialize_with = "positive")]
    pub period_s: f64,
    /// The vote on the camera's direction.
    #[serde(deserialize_with = "non_negative")]
    pub vote: f64,
}

impl Default for SweepCameraConfig {
    fn default() -> Self {
        SweepCameraConfig { amplitude_deg: 60.0, period_s: 8.0, vote: 1.0 }
    }
}

/// Points the camera `amplitude_deg` either side of the heading and back,
/// on a sine of `period_s`, and asks nothing of the wheels: beside a
/// driving behaviour it looks around while the robot goes where it goes.
/// A robot with a fixed camera ignores it.
#[derive(Clone, Debug)]
pub struct SweepCamera {
    config: SweepCameraConfig,
}

impl SweepCamera {
    /// A sweep with these settings.
    pub fn new(config: SweepCameraConfig) -> Self {
        SweepCamera { config }
    }
}

impl Behavior for SweepCamera {
    fn gen_action(&mut self, state: &State) -> Action {
        let c = &self.config;
        let phase = state.time * std::f64::consts::TAU / c.period_s;
        Action::with_vote(c.vote).camera_pan(c.amplitude_deg.to_radians() * phase.sin())
    }

    fn name(&self) -> &str {
        "SweepCamera"
    }
}

impl ubf_core::Describe for SweepCameraConfig {
    fn fields() -> Vec<ubf_core::Field> {
        use ubf_core::Field;
        vec![
            Field::new("amplitude_deg", "number", "°", "60.0", "≥ 0", "how far either side of the heading it looks"),
            Field::new("period_s", "number", "s", "8.0", "> 0", "one sweep left, right and back"),
            Field::new("vote", "number", "", "1.0", "≥ 0", "vote on the camera's direction"),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn it_sweeps_the_camera_and_leaves_the_wheels_alone() {
        let mut sweep = SweepCamera::new(SweepCameraConfig::default());
        let at = |sweep: &mut SweepCamera, time: f64| sweep.gen_action(&State { time, ..State::default() });
        let quarter = at(&mut sweep, 2.0);
        assert!((quarter.motion.camera_pan.unwrap() - 60f64.to_radians()).abs() < 1e-12);
        assert!((at(&mut sweep, 6.0).motion.camera_pan.unwrap() + 60f64.to_radians()).abs() < 1e-12);
        assert_eq!((quarter.motion.velocity, quarter.motion.rot_velocity, quarter.motion.heading), (None, None, None));
    }
}
