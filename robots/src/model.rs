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
    #[serde(deserialize_with = "ubf_core::config::angle_deg")]
    pub heading_deg: f64,
}

impl SonarUnit {
    /// Position and direction in the robot frame.
    pub fn pose(&self) -> Pose2 {
        Pose2::new(self.x, self.y, self.heading_deg.to_radians())
    }
}

/// The controller's unit conversions (ARCOS), from the model's parameter
/// file.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArcosParams {
    /// Millimetres per position unit.
    #[serde(deserialize_with = "positive")]
    pub dist_conv_factor: f64,
    /// Radians per heading unit (2π/4096 on most models).
    #[serde(deserialize_with = "positive")]
    pub angle_conv_factor: f64,
    /// mm/s per wheel velocity unit.
    #[serde(deserialize_with = "positive")]
    pub vel_conv_factor: f64,
    /// Millimetres per sonar range unit.
    #[serde(deserialize_with = "positive")]
    pub range_conv_factor: f64,
    /// Ratio of angular velocity to wheel velocity difference.
    #[serde(deserialize_with = "positive")]
    pub diff_conv_factor: f64,
    /// Divisor of VEL2 wheel speeds.
    #[serde(deserialize_with = "positive")]
    pub vel2_divisor: f64,
    /// Baud rate to switch to after connecting at 9600, if any (0: stay).
    #[serde(default)]
    pub switch_to_baud: u32,
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
    #[serde(deserialize_with = "ubf_core::config::speed_m_s")]
    pub max_velocity: f64,
    /// Largest turn rate the robot can do, °/s.
    #[serde(deserialize_with = "ubf_core::config::rate_deg_s")]
    pub max_rot_velocity_deg: f64,
    /// The controller's unit conversions.
    pub arcos: ArcosParams,
    /// The sonar ring.
    pub sonar: Vec<SonarUnit>,
}

impl RobotModel {
    /// The MobileRobots Powerbot (`robots/models/powerbot.ron`).
    pub fn powerbot() -> RobotModel {
        RobotModel::from_ron(include_str!("../models/powerbot.ron")).expect("the shipped Powerbot model is valid")
    }

    /// The MobileRobots Pioneer 3-DX (`robots/models/p3dx.ron`).
    pub fn p3dx() -> RobotModel {
        RobotModel::from_ron(include_str!("../models/p3dx.ron")).expect("the shipped P3-DX model is valid")
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
        assert_eq!(m.arcos.dist_conv_factor, 0.5813);
        let p = RobotModel::p3dx();
        assert_eq!((p.subclass.as_str(), p.sonar.len()), ("p3dx", 16));
        assert_eq!(p.arcos.angle_conv_factor, 0.0018);
    }
}
