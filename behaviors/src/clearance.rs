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

    #[test]
    fn strip_geometry() {
        let points = [(2.0, 0.3), (0.2, -2.0)];
        assert_eq!(free_distance(&points, 0.0, 0.5), 2.0);
        assert_eq!(free_distance(&points, 0.0, 0.2), f64::INFINITY);
        let d = free_distance(&points, -std::f64::consts::FRAC_PI_2, 0.5);
        assert!((d - 2.0).abs() < 1e-12);
    }
}
