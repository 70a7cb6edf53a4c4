//! The sonar ring: each transducer ray-cast against walls, boxes and people.

use super::geometry::{Circle, Segment};
use crate::model::SonarUnit;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Deserialize;
use ubf_core::config::{non_negative, positive};
use ubf_core::{wrap_angle, Pose2, RangeReading};

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
    /// Each transducer's pose on the robot.
    mounts: Vec<Pose2>,
    /// The directions of each transducer's rays on the floor, and the sine
    /// and cosine of the robot's heading, for the heading they were worked
    /// out at (reused).
    aim: Aim,
    /// Indices of the segments near the robot this tick (reused).
    near: Vec<usize>,
}

/// The trigonometry of a sonar sweep, which depends on the robot's heading
/// alone. A robot driving straight or standing still keeps its heading bit
/// for bit from one tick to the next, and then the sweep needs no sine or
/// cosine at all; before, they were most of the sonar's time.
#[derive(Clone, Debug, Default)]
struct Aim {
    /// The heading (its bits) this was worked out for; `None` before the
    /// first sweep.
    heading: Option<u64>,
    /// Sine and cosine of the heading.
    sin_cos: (f64, f64),
    /// Unit directions of every transducer's rays, `RAY_OFFSETS` in order.
    rays: Vec<[(f64, f64); RAY_OFFSETS.len()]>,
}

impl Aim {
    /// Brings the directions up to date for a robot heading `heading`,
    /// computed term for term as composing the robot's pose with the
    /// transducer's gives them, so that readings keep their bits.
    fn update(&mut self, heading: f64, mounts: &[Pose2], half_cone: f64) {
        if self.heading == Some(heading.to_bits()) {
            return;
        }
        self.heading = Some(heading.to_bits());
        self.sin_cos = heading.sin_cos();
        self.rays.clear();
        self.rays.extend(mounts.iter().map(|mount| {
            let axis = wrap_angle(heading + mount.theta);
            RAY_OFFSETS.map(|offset| {
                let angle = axis + offset * 2.0 * half_cone;
                (angle.cos(), angle.sin())
            })
        }));
    }

    /// Where a transducer at `mount` is on the floor with the robot at
    /// `pose`, with this heading's sine and cosine.
    fn origin(&self, pose: &Pose2, mount: &Pose2) -> (f64, f64) {
        pose.transform_point_with(self.sin_cos, mount.x, mount.y)
    }
}

impl Sonar {
    /// A ring of `units` with these settings.
    pub fn new(config: SonarConfig, units: Vec<SonarUnit>) -> Self {
        let mounts = units.iter().map(SonarUnit::pose).collect();
        Sonar { config, mounts, aim: Aim::default(), near: Vec::new() }
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
        self.aim.update(pose.theta, &self.mounts, half_cone);
        for (mount, rays) in self.mounts.iter().zip(&self.aim.rays) {
            let origin = self.aim.origin(pose, mount);
            let mut nearest = f64::INFINITY;
            for &dir in rays {
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
            out.push(RangeReading { pose_robot_sensor: *mount, range, max_range: self.config.max_range });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::RobotModel;
    use rand::{Rng, SeedableRng};

    /// The readings as the sonar once worked them out: every ray's direction
    /// from the sensor's pose composed afresh, tick by tick.
    fn cast_afresh(
        config: &SonarConfig,
        units: &[SonarUnit],
        pose: &Pose2,
        segments: &[Segment],
        people: &[Circle],
        rng: &mut ChaCha8Rng,
    ) -> Vec<RangeReading> {
        let half_cone = config.cone_deg.to_radians() / 2.0;
        let mut out = Vec::new();
        for unit in units {
            let sensor = pose.compose(&unit.pose());
            let mut nearest = f64::INFINITY;
            for offset in RAY_OFFSETS {
                let angle = sensor.theta + offset * 2.0 * half_cone;
                let dir = (angle.cos(), angle.sin());
                let hits = segments.iter().filter_map(|s| s.ray_hit((sensor.x, sensor.y), dir));
                let hits = hits.chain(people.iter().filter_map(|p| p.ray_hit((sensor.x, sensor.y), dir)));
                nearest = hits.fold(nearest, f64::min);
            }
            let range = (nearest <= config.max_range).then(|| {
                let noise: f64 = StandardNormal.sample(rng);
                (nearest + noise * config.noise_m).clamp(0.0, config.max_range)
            });
            out.push(RangeReading { pose_robot_sensor: unit.pose(), range, max_range: config.max_range });
        }
        out
    }

    #[test]
    fn kept_directions_give_the_readings_of_rays_cast_afresh() {
        let config = SonarConfig::default();
        let units = RobotModel::powerbot().sonar;
        let segments = [
            Segment::new((0.0, -3.0), (60.0, -3.0)),
            Segment::new((60.0, -3.0), (60.0, 3.0)),
            Segment::new((60.0, 3.0), (0.0, 3.0)),
            Segment::new((0.0, 3.0), (0.0, -3.0)),
            Segment::new((4.0, -0.5), (4.5, 0.5)),
        ];
        let people = [Circle { c: (2.0, 1.5), r: 0.25 }];
        let mut sonar = Sonar::new(config.clone(), units.clone());
        let (mut kept_rng, mut afresh_rng) = (ChaCha8Rng::seed_from_u64(1), ChaCha8Rng::seed_from_u64(1));
        let mut poses = ChaCha8Rng::seed_from_u64(2);
        let mut pose = Pose2::new(1.0, 0.0, 0.0);
        let mut readings = Vec::new();
        for tick in 0..2000 {
            // Runs of ticks at one heading (driving straight), turns, and
            // headings either side of ±π.
            pose.x = poses.random_range(0.5..6.0);
            pose.y = poses.random_range(-2.5..2.5);
            if tick % 7 == 0 {
                pose.theta = wrap_angle(poses.random_range(-4.0..4.0));
            }
            sonar.sense(&pose, 0.5, &segments, &people, &mut kept_rng, &mut readings);
            let afresh = cast_afresh(&config, &units, &pose, &segments, &people, &mut afresh_rng);
            assert_eq!(readings.len(), afresh.len());
            for (kept, fresh) in readings.iter().zip(&afresh) {
                assert_eq!(kept.range.map(f64::to_bits), fresh.range.map(f64::to_bits), "tick {tick}, {pose:?}");
                assert_eq!(kept.pose_robot_sensor, fresh.pose_robot_sensor);
            }
        }
    }
}
