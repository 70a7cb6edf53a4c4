//! A sensor's recent readings with when each was taken, so that a stereo
//! frame is matched to the values of when its pair was taken, not of when
//! it reached the control loop: the feature pipeline takes a tick or more,
//! a head turning at 60°/s moves 6° in 0.1 s, and a robot driving at
//! 0.5 m/s moves 5 cm.

use std::collections::VecDeque;
use std::time::Instant;
use ubf_core::{angle_difference, wrap_angle, Aim, Pose2};

/// An instant readings are stamped with.
pub(crate) trait Stamp: Copy + PartialOrd {
    /// Seconds from `earlier` to `self`.
    fn seconds_since(self, earlier: Self) -> f64;
}

impl Stamp for Instant {
    fn seconds_since(self, earlier: Self) -> f64 {
        (self - earlier).as_secs_f64()
    }
}

/// Seconds on the controller's clock.
impl Stamp for f64 {
    fn seconds_since(self, earlier: Self) -> f64 {
        self - earlier
    }
}

/// A reading that can be taken `share` of the way from one to the next.
pub(crate) trait Between: Copy {
    /// The value `share` (0 to 1) of the way from `self` to `next`.
    fn towards(self, next: Self, share: f64) -> Self;
}

impl Between for Aim {
    fn towards(self, next: Self, share: f64) -> Self {
        let along = |x0: f64, x1: f64| x0 + (x1 - x0) * share;
        Aim { pan: along(self.pan, next.pan), tilt: along(self.tilt, next.tilt) }
    }
}

/// The heading the short way round, so that a pose crossing ±π does not
/// swing through zero.
impl Between for Pose2 {
    fn towards(self, next: Self, share: f64) -> Self {
        let along = |x0: f64, x1: f64| x0 + (x1 - x0) * share;
        let theta = wrap_angle(self.theta + angle_difference(next.theta, self.theta) * share);
        Pose2::new(along(self.x, next.x), along(self.y, next.y), theta)
    }
}

/// The last [`TimedReadings::KEPT`] readings, oldest first.
#[derive(Debug)]
pub(crate) struct TimedReadings<S, V> {
    readings: VecDeque<(S, V)>,
}

impl<S, V> Default for TimedReadings<S, V> {
    fn default() -> Self {
        TimedReadings { readings: VecDeque::new() }
    }
}

impl<S: Stamp, V: Between> TimedReadings<S, V> {
    /// Readings kept: at ten ticks a second, six seconds, far longer than a
    /// frame takes to arrive.
    const KEPT: usize = 64;

    /// Keeps `value`, read at `at`. A reading stamped as the last replaces
    /// it, the latest word on that instant: a head's poll read again, or
    /// the robot sensed again at the last tick's time (the controller's
    /// settled pose after a stop). One older than the last is out of order
    /// and dropped.
    pub(crate) fn push(&mut self, at: S, value: V) {
        match self.readings.back_mut() {
            Some((last, _)) if at < *last => return,
            Some((last, kept)) if at == *last => {
                *kept = value;
                return;
            }
            _ => {}
        }
        if self.readings.len() == Self::KEPT {
            self.readings.pop_front();
        }
        self.readings.push_back((at, value));
    }

    /// Every reading kept, made over by `remake`: readings put in a frame
    /// that has since moved.
    pub(crate) fn remake(&mut self, remake: impl Fn(V) -> V) {
        for (_, value) in &mut self.readings {
            *value = remake(*value);
        }
    }

    /// The value at `when`: between two readings, on the line through
    /// them; on a reading, or before the oldest or after the newest, that
    /// reading's exactly.
    pub(crate) fn at(&self, when: S) -> Option<V> {
        let after = self.readings.partition_point(|(at, _)| *at <= when);
        match (after.checked_sub(1).map(|i| self.readings[i]), self.readings.get(after)) {
            (Some((t0, v0)), Some(&(t1, v1))) if when > t0 => {
                Some(v0.towards(v1, when.seconds_since(t0) / t1.seconds_since(t0)))
            }
            (Some((_, value)), _) | (None, Some(&(_, value))) => Some(value),
            (None, None) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_time_between_readings_gets_the_angles_on_the_line_through_them() {
        let start = Instant::now();
        let mut head = TimedReadings::default();
        assert_eq!(head.at(start), None);
        let s = |secs: f64| start + Duration::from_secs_f64(secs);
        head.push(s(0.0), Aim { pan: 0.0, tilt: 0.1 });
        head.push(s(0.1), Aim { pan: 0.5, tilt: 0.1 });
        head.push(s(0.3), Aim { pan: 0.5, tilt: 0.3 });
        let close = |a: Aim, pan: f64, tilt: f64| (a.pan - pan).abs() < 1e-9 && (a.tilt - tilt).abs() < 1e-9;
        assert!(close(head.at(s(0.05)).unwrap(), 0.25, 0.1));
        assert!(close(head.at(s(0.2)).unwrap(), 0.5, 0.2));
        assert!(close(head.at(s(0.1)).unwrap(), 0.5, 0.1), "on a reading, that reading");
        assert!(close(head.at(s(1.0)).unwrap(), 0.5, 0.3), "after the newest, the newest");
        assert!(close(head.at(start).unwrap(), 0.0, 0.1));
        head.push(s(0.2), Aim { pan: 7.0, tilt: 7.0 });
        assert!(close(head.at(s(0.2)).unwrap(), 0.5, 0.2), "a reading older than the last is dropped");
        head.push(s(0.3), Aim { pan: 9.0, tilt: 9.0 });
        assert!(close(head.at(s(1.0)).unwrap(), 9.0, 9.0), "a reading at the last's instant replaces it");
        assert!(close(head.at(s(0.2)).unwrap(), 4.75, 4.55), "and is interpolated to as the one kept");
        for k in 0..100 {
            head.push(s(1.0 + f64::from(k)), Aim { pan: f64::from(k), tilt: 0.0 });
        }
        assert_eq!(head.readings.len(), TimedReadings::<Instant, Aim>::KEPT);
        let oldest = f64::from(100 - TimedReadings::<Instant, Aim>::KEPT as u32);
        assert!(close(head.at(s(0.0)).unwrap(), oldest, 0.0), "before the oldest kept, the oldest");
    }

    #[test]
    fn a_pose_between_readings_turns_the_short_way_and_a_reading_is_returned_exactly() {
        let mut odometry = TimedReadings::default();
        let (a, b) = (Pose2::new(1.0, 2.0, 3.1), Pose2::new(2.0, 0.0, -3.1));
        odometry.push(0.1, a);
        odometry.push(0.3, b);
        let half = odometry.at(0.2).unwrap();
        assert!((half.x - 1.5).abs() < 1e-12 && (half.y - 1.0).abs() < 1e-12, "{half:?}");
        // 3.1 to −3.1 is 0.083 rad the short way, across π: halfway is π.
        assert!(angle_difference(half.theta, std::f64::consts::PI).abs() < 1e-12, "{half:?}");
        // Bit for bit: a frame stamped at a tick takes that tick's reading.
        assert_eq!(odometry.at(0.3), Some(b));
        assert_eq!(odometry.at(0.1), Some(a));
    }
}
