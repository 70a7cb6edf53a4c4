//! Robot models: geometry, limits and sensors of a robot type, kept in RON
//! files rather than in code (`robots/models/*.ron`).

use serde::Deserialize;
use ubf_core::config::{finite, positive, RonError};
use ubf_core::Pose2;

/// The robot's outline around its centre of rotation.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Footprint {
    /// Metres from the centre of rotation to the front.
    #[serde(deserialize_with = "positive")]
    pub front: f64,
    /// Metres from the centre of rotation to the rear.
    #[serde(deserialize_with = "positive")]
    pub rear: f64,
    /// Width, m.
    #[serde(deserialize_with = "positive")]
    pub width: f64,
}

impl Footprint {
    /// The four corners in the robot frame, counter-clockwise from front left.
    pub fn corners(&self) -> [(f64, f64); 4] {
        let h = self.width / 2.0;
        [(self.front, h), (-self.rear, h), (-self.rear, -h), (self.front, -h)]
    }

    /// Radius of the circle around the centre of rotation that holds the
    /// footprint.
    pub fn radius(&self) -> f64 {
        self.front.max(self.rear).hypot(self.width / 2.0)
    }
}

/// One sonar transducer.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SonarUnit {
    /// The controller's channel number.
    pub index: u8,
    /// Metres forward of the centre of rotation.
    #[serde(deserialize_with = "finite")]
    pub x: f64,
    /// Metres to the left.
    #[serde(deserialize_with = "finite")]
    pub y: f64,
    /// Pointing direction, degrees counter-clockwise from forward.
    #[serde(deserialize_with = "finite")]
    pub heading_deg: f64,
}

impl SonarUnit {
    /// Position and direction in the robot frame.
    pub fn pose(&self) -> Pose2 {
        Pose2::new(self.x, self.y, self.heading_deg.to_radians())
    }
}

/// A robot type: what a robot model file holds.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotModel {
    /// Human name.
    pub name: String,
    /// The controller's reported class (ARCOS), e.g. `Pioneer`.
    pub class: String,
    /// The controller's reported subclass, e.g. `powerbot`.
    pub subclass: String,
    /// The outline.
    pub footprint: Footprint,
    /// Distance between the drive wheels' contact points, m.
    #[serde(deserialize_with = "positive")]
    pub track_width: f64,
    /// Largest forward speed the robot can do, m/s.
    #[serde(deserialize_with = "positive")]
    pub max_velocity: f64,
    /// Largest turn rate the robot can do, °/s.
    #[serde(deserialize_with = "positive")]
    pub max_rot_velocity_deg: f64,
    /// The sonar ring.
    pub sonar: Vec<SonarUnit>,
}

impl RobotModel {
    /// The MobileRobots Powerbot (`robots/models/powerbot.ron`).
    pub fn powerbot() -> RobotModel {
        RobotModel::from_ron(include_str!("../models/powerbot.ron")).expect("the shipped Powerbot model is valid")
    }

    /// Reads a model from RON text.
    pub fn from_ron(text: &str) -> Result<RobotModel, RonError> {
        ubf_core::config::from_ron(text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn powerbot_model_loads() {
        let m = RobotModel::powerbot();
        assert_eq!((m.class.as_str(), m.subclass.as_str()), ("Pioneer", "powerbot"));
        assert_eq!(m.sonar.len(), 28);
        assert!((m.footprint.front + m.footprint.rear - 0.911).abs() < 1e-9);
    }
}
