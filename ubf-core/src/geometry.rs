//! Planar poses and angle arithmetic.
//!
//! Angles are radians, counter-clockwise positive, and wrapped to (−π, π]
//! wherever a direction (not an accumulated turn) is meant.

use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// A position and heading on the plane: `pose_world_robot` is the robot's pose
/// in the world frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pose2 {
    /// Metres along the world x axis.
    pub x: f64,
    /// Metres along the world y axis.
    pub y: f64,
    /// Heading in radians from the x axis, counter-clockwise.
    pub theta: f64,
}

impl Pose2 {
    /// A pose at `(x, y)` facing `theta`.
    pub const fn new(x: f64, y: f64, theta: f64) -> Self {
        Self { x, y, theta }
    }

    /// Distance from this pose's position to the point `(x, y)`.
    pub fn distance_to(&self, x: f64, y: f64) -> f64 {
        (x - self.x).hypot(y - self.y)
    }

    /// Bearing of the point `(x, y)` seen from this pose, relative to its
    /// heading, in (−π, π].
    pub fn bearing_to(&self, x: f64, y: f64) -> f64 {
        wrap_angle((y - self.y).atan2(x - self.x) - self.theta)
    }

    /// Expresses a point given in this pose's frame in the parent frame.
    pub fn transform_point(&self, x: f64, y: f64) -> (f64, f64) {
        self.transform_point_with(self.theta.sin_cos(), x, y)
    }

    /// [`Pose2::transform_point`] given `theta.sin_cos()`, for a caller that
    /// keeps them from one point or tick to the next (a sensor's fixed
    /// mounting angle, a heading that has not changed): the same bits
    /// without the sine and cosine.
    pub fn transform_point_with(&self, (s, c): (f64, f64), x: f64, y: f64) -> (f64, f64) {
        (self.x + c * x - s * y, self.y + s * x + c * y)
    }

    /// Composes `self ∘ other`: `other` is expressed in `self`'s frame.
    pub fn compose(&self, other: &Pose2) -> Pose2 {
        let (x, y) = self.transform_point(other.x, other.y);
        Pose2::new(x, y, wrap_angle(self.theta + other.theta))
    }

    /// The pose `p` with `from ∘ p = self`: this pose seen from `from`'s
    /// frame (the motion from `from` to here).
    pub fn relative_to(&self, from: &Pose2) -> Pose2 {
        let (s, c) = from.theta.sin_cos();
        let (dx, dy) = (self.x - from.x, self.y - from.y);
        Pose2::new(c * dx + s * dy, -s * dx + c * dy, wrap_angle(self.theta - from.theta))
    }
}

/// Wraps an angle to (−π, π].
pub fn wrap_angle(angle: f64) -> f64 {
    if !angle.is_finite() {
        return angle;
    }
    let wrapped = (angle + PI).rem_euclid(TAU) - PI;
    // rem_euclid gives [−π, π); the thesis's and ARCOS's convention is (−π, π].
    if wrapped <= -PI {
        wrapped + TAU
    } else {
        wrapped
    }
}

/// Signed smallest rotation that takes direction `from` to direction `to`.
pub fn angle_difference(to: f64, from: f64) -> f64 {
    wrap_angle(to - from)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_angle_lands_in_half_open_interval() {
        assert_eq!(wrap_angle(0.0), 0.0);
        assert!((wrap_angle(PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(2.5 * PI) - 0.5 * PI).abs() < 1e-12);
        assert!((wrap_angle(-2.5 * PI) + 0.5 * PI).abs() < 1e-12);
    }

    #[test]
    fn relative_to_undoes_compose() {
        let from = Pose2::new(1.0, -2.0, 2.5);
        let motion = Pose2::new(0.7, 0.3, -1.1);
        let back = from.compose(&motion).relative_to(&from);
        assert!((back.x - motion.x).abs() < 1e-12 && (back.y - motion.y).abs() < 1e-12);
        assert!((back.theta - motion.theta).abs() < 1e-12);
    }

    #[test]
    fn bearing_is_relative_to_heading() {
        let pose = Pose2::new(1.0, 1.0, PI / 2.0);
        assert!(pose.bearing_to(1.0, 2.0).abs() < 1e-12);
        assert!((pose.bearing_to(0.0, 1.0) - PI / 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_kept_sine_and_cosine_transform_as_the_heading_does() {
        for theta in [0.0, -0.0, 0.3, -2.0, PI, -PI / 2.0] {
            let pose = Pose2::new(1.5, -0.25, theta);
            for (x, y) in [(0.0, 0.0), (2.0, -0.0), (-0.7, 0.3)] {
                let (a, b) = pose.transform_point(x, y);
                let (c, d) = pose.transform_point_with(theta.sin_cos(), x, y);
                assert_eq!((a.to_bits(), b.to_bits()), (c.to_bits(), d.to_bits()));
            }
        }
    }

    #[test]
    fn compose_then_transform_agree() {
        let a = Pose2::new(1.0, 2.0, 0.3);
        let b = Pose2::new(-0.5, 0.25, -1.0);
        let ab = a.compose(&b);
        let (x, y) = a.transform_point(b.x, b.y);
        assert!((ab.x - x).abs() < 1e-12 && (ab.y - y).abs() < 1e-12);
        assert!((ab.theta - wrap_angle(0.3 - 1.0)).abs() < 1e-12);
    }
}
