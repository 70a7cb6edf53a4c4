//! The sonar ring: each transducer ray-cast against walls, boxes and people.

use super::geometry::{Circle, Segment};
use crate::model::SonarUnit;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Deserialize;
use ubf_core::config::{non_negative, positive};
use ubf_core::{Pose2, RangeReading};

/// The sonar's settings, as written in a scenario file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SonarConfig {
    /// Whether the robot has its sonar on.
    pub enabled: bool,
    /// Farthest echo reported, m.
    #[serde(deserialize_with = "positive")]
    pub max_range: f64,
    /// Full width of each transducer's cone, °.
    #[serde(deserialize_with = "positive")]
    pub cone_deg: f64,
    /// Standard deviation of the range noise, m.
    #[serde(deserialize_with = "non_negative")]
    pub noise_m: f64,
    /// The transducers; by default the robot model's ring.
    #[serde(default)]
    pub units: Option<Vec<SonarUnit>>,
}

impl Default for SonarConfig {
    fn default() -> Self {
        SonarConfig { enabled: true, max_range: 5.0, cone_deg: 30.0, noise_m: 0.02, units: None }
    }
}

/// Rays per cone: the axis and two at ±40 % of the cone's width, enough to
/// see a wall at an angle without a ray per degree.
const RAY_OFFSETS: [f64; 3] = [0.0, -0.4, 0.4];

/// A sonar ring ready to sense.
#[derive(Clone, Debug)]
pub struct Sonar {
    config: SonarConfig,
    units: Vec<SonarUnit>,
    /// Indices of the segments near the robot this tick (reused).
    near: Vec<usize>,
}

impl Sonar {
    /// A ring of `units` with these settings.
    pub fn new(config: SonarConfig, units: Vec<SonarUnit>) -> Self {
        Sonar { config, units, near: Vec::new() }
    }

    /// Fills `out` with one reading per transducer for the robot at `pose`.
    /// `reach` is the robot's footprint radius: segments farther than that
    /// plus the maximum range cannot echo and are skipped.
    pub fn sense(
        &mut self,
        pose: &Pose2,
        reach: f64,
        segments: &[Segment],
        people: &[Circle],
        rng: &mut ChaCha8Rng,
        out: &mut Vec<RangeReading>,
    ) {
        out.clear();
        if !self.config.enabled {
            return;
        }
        let horizon = self.config.max_range + reach;
        self.near.clear();
        self.near.extend((0..segments.len()).filter(|&i| segments[i].distance_to((pose.x, pose.y)) <= horizon));
        let half_cone = self.config.cone_deg.to_radians() / 2.0;
        for unit in &self.units {
            let pose_robot_sensor = unit.pose();
            let sensor = pose.compose(&pose_robot_sensor);
            let mut nearest = f64::INFINITY;
            for offset in RAY_OFFSETS {
                let angle = sensor.theta + offset * 2.0 * half_cone;
                let dir = (angle.cos(), angle.sin());
                let origin = (sensor.x, sensor.y);
                for &i in &self.near {
                    if let Some(t) = segments[i].ray_hit(origin, dir) {
                        nearest = nearest.min(t);
                    }
                }
                for person in people {
                    if let Some(t) = person.ray_hit(origin, dir) {
                        nearest = nearest.min(t);
                    }
                }
            }
            let range = if nearest <= self.config.max_range {
                let noise: f64 = StandardNormal.sample(rng);
                Some((nearest + noise * self.config.noise_m).clamp(0.0, self.config.max_range))
            } else {
                None
            };
            out.push(RangeReading { pose_robot_sensor, range, max_range: self.config.max_range });
        }
    }
}
