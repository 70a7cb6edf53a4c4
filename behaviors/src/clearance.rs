//! How far the robot can drive along a heading before its swept strip meets
//! an echo: shared by collision avoidance and action aiding.

use ubf_core::State;

/// The range sensors' echoes as points in the robot frame (x forward, y
/// left), written into `out`.
pub fn echo_points(state: &State, out: &mut Vec<(f64, f64)>) {
    out.clear();
    out.extend(
        state.ranges.iter().filter_map(|r| r.range.map(|range| r.pose_robot_sensor.transform_point(range, 0.0))),
    );
}

/// The range sensors' echoes as points in the robot frame, tick after tick:
/// the points [`echo_points`] gives, bit for bit.
///
/// A sensor's pointing angle on the robot is fixed, yet placing its echo
/// took a sine and cosine of it every tick, for every sensor: most of
/// collision avoidance's time in a simulated sweep. They are kept here, by
/// reading, and worked out again only if a reading's angle changes.
#[derive(Clone, Debug, Default)]
pub struct EchoPoints {
    points: Vec<(f64, f64)>,
    /// For each reading: its sensor's angle (as bits) and that angle's sine
    /// and cosine, once the reading has had an echo.
    bearings: Vec<Option<(u64, (f64, f64))>>,
}

impl EchoPoints {
    /// Places the echoes of `state`'s range readings.
    pub fn update(&mut self, state: &State) {
        self.points.clear();
        self.bearings.resize(state.ranges.len(), None);
        for (reading, bearing) in state.ranges.iter().zip(&mut self.bearings) {
            let Some(range) = reading.range else { continue };
            let sensor = &reading.pose_robot_sensor;
            let angle = sensor.theta.to_bits();
            let sin_cos = match *bearing {
                Some((kept, sin_cos)) if kept == angle => sin_cos,
                _ => bearing.insert((angle, sensor.theta.sin_cos())).1,
            };
            self.points.push(sensor.transform_point_with(sin_cos, range, 0.0));
        }
    }

    /// The echoes placed by the last [`EchoPoints::update`].
    pub fn points(&self) -> &[(f64, f64)] {
        &self.points
    }
}

/// How far along `heading` (robot frame, rad) the strip `half_width` either
/// side of the robot's path is free of `points`, measured from the robot's
/// centre; infinite if nothing is in the way.
pub fn free_distance(points: &[(f64, f64)], heading: f64, half_width: f64) -> f64 {
    let (s, c) = heading.sin_cos();
    points
        .iter()
        .filter_map(|&(x, y)| {
            let along = x * c + y * s;
            let lateral = -x * s + y * c;
            (along > 0.0 && lateral.abs() <= half_width).then_some(along)
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ubf_core::{Pose2, RangeReading};

    #[test]
    fn kept_bearings_place_echoes_as_worked_out_afresh() {
        let reading = |x: f64, y: f64, deg: f64, range: Option<f64>| RangeReading {
            pose_robot_sensor: Pose2::new(x, y, f64::to_radians(deg)),
            range,
            max_range: 5.0,
        };
        let mut kept = EchoPoints::default();
        let mut afresh = Vec::new();
        let rings = [
            vec![
                reading(0.2, 0.1, 30.0, Some(1.25)),
                reading(0.2, -0.1, -30.0, None),
                reading(-0.3, 0.0, 180.0, Some(0.5)),
            ],
            // The same sensors, other echoes.
            vec![
                reading(0.2, 0.1, 30.0, None),
                reading(0.2, -0.1, -30.0, Some(2.0)),
                reading(-0.3, 0.0, 180.0, Some(4.75)),
            ],
            // A sensor turned, and one reading more.
            vec![
                reading(0.2, 0.1, 45.0, Some(1.25)),
                reading(0.2, -0.1, -30.0, Some(2.0)),
                reading(-0.3, 0.0, 180.0, Some(4.75)),
                reading(0.0, 0.3, 90.0, Some(3.0)),
            ],
            // One fewer.
            vec![reading(0.2, 0.1, 45.0, Some(0.75)), reading(0.2, -0.1, -30.0, Some(2.5))],
        ];
        for ranges in rings {
            let state = State { ranges, ..State::default() };
            kept.update(&state);
            echo_points(&state, &mut afresh);
            let bits =
                |points: &[(f64, f64)]| points.iter().map(|p| (p.0.to_bits(), p.1.to_bits())).collect::<Vec<_>>();
            assert_eq!(bits(kept.points()), bits(&afresh), "{:?}", state.ranges);
        }
    }

    #[test]
    fn strip_geometry() {
        let points = [(2.0, 0.3), (0.2, -2.0)];
        assert_eq!(free_distance(&points, 0.0, 0.5), 2.0);
        assert_eq!(free_distance(&points, 0.0, 0.2), f64::INFINITY);
        let d = free_distance(&points, -std::f64::consts::FRAC_PI_2, 0.5);
        assert!((d - 2.0).abs() < 1e-12);
    }
}
