//! A pan-tilt head's recent readings, so that a frame is lifted by the
//! angles the head had when the pair was taken, not when the frame reached
//! the control loop: the feature pipeline takes a tick or more, and a head
//! turning at 60°/s moves 6° in 0.1 s.

use std::collections::VecDeque;
use std::time::Instant;
use ubf_core::Aim;

/// The last [`HeadReadings::KEPT`] readings, oldest first, and the very
/// first, which anchors egomotion's map.
#[derive(Debug, Default)]
pub(crate) struct HeadReadings {
    readings: VecDeque<(Instant, Aim)>,
    first: Option<Aim>,
}

impl HeadReadings {
    /// Readings kept: at ten ticks a second, six seconds, far longer than a
    /// frame takes to arrive.
    const KEPT: usize = 64;

    /// Keeps `aim`, read at `at`; a reading no newer than the last (a
    /// unit's poll read again) is the one already kept.
    pub(crate) fn push(&mut self, at: Instant, aim: Aim) {
        if self.readings.back().is_some_and(|(last, _)| at <= *last) {
            return;
        }
        if self.readings.len() == Self::KEPT {
            self.readings.pop_front();
        }
        self.first.get_or_insert(aim);
        self.readings.push_back((at, aim));
    }

    /// The first reading kept.
    pub(crate) fn first(&self) -> Option<Aim> {
        self.first
    }

    /// The angles at `when`: between two readings, on the line through
    /// them; before the oldest or after the newest, that reading's.
    pub(crate) fn at(&self, when: Instant) -> Option<Aim> {
        let after = self.readings.partition_point(|(at, _)| *at <= when);
        match (after.checked_sub(1).map(|i| self.readings[i]), self.readings.get(after)) {
            (Some((t0, a0)), Some(&(t1, a1))) => {
                let share = (when - t0).as_secs_f64() / (t1 - t0).as_secs_f64();
                let along = |x0: f64, x1: f64| x0 + (x1 - x0) * share;
                Some(Aim { pan: along(a0.pan, a1.pan), tilt: along(a0.tilt, a1.tilt) })
            }
            (Some((_, aim)), None) | (None, Some(&(_, aim))) => Some(aim),
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
        let mut head = HeadReadings::default();
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
        head.push(s(0.3), Aim { pan: 9.0, tilt: 9.0 });
        assert!(close(head.at(s(1.0)).unwrap(), 0.5, 0.3), "a reading read again is kept once");
        for k in 0..100 {
            head.push(s(1.0 + f64::from(k)), Aim { pan: f64::from(k), tilt: 0.0 });
        }
        assert_eq!(head.readings.len(), HeadReadings::KEPT);
        let oldest = f64::from(100 - HeadReadings::KEPT as u32);
        assert!(close(head.at(s(0.0)).unwrap(), oldest, 0.0), "before the oldest kept, the oldest");
        assert!(close(head.first().unwrap(), 0.0, 0.1), "the first is kept");
    }
}
