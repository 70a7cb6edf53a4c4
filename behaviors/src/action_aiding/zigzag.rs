//! The zig-zag technique's course: legs at a fixed angle off the path's
//! centre line, turning back at random offsets from it.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use ubf_core::Pose2;

/// Where the zig-zag is: the path it zig-zags along, the side the current
/// leg heads to and where that leg turns back.
pub(super) struct ZigZag {
    /// Draws each leg's turning point.
    rng: ChaCha8Rng,
    /// The path's start and direction (start to goal), fixed at the first
    /// leg.
    path: Option<((f64, f64), f64)>,
    /// The side of the centre line the current leg heads to: +1 left, −1
    /// right.
    side: f64,
    /// The offset from the centre line at which the current leg turns
    /// back, m; 0 before the first leg.
    limit: f64,
}

impl ZigZag {
    /// A zig-zag not yet begun, drawing its turning points from `rng`.
    pub(super) fn new(rng: ChaCha8Rng) -> Self {
        ZigZag { rng, path: None, side: 1.0, limit: 0.0 }
    }

    /// Starts the path afresh from where the robot is at the next leg; the
    /// current side and turning point are kept.
    pub(super) fn restart(&mut self) {
        self.path = None;
    }

    /// The heading of the leg for a robot at `pose` bound for `goal`:
    /// `angle` (rad) off the centre line, to the other side once the robot
    /// is as far off the line as the leg's turning point (a random 50–100 %
    /// of `max_offset`, m), or when `clear` says the leg is blocked.
    pub(super) fn heading(
        &mut self,
        pose: &Pose2,
        goal: (f64, f64),
        angle: f64,
        max_offset: f64,
        clear: impl Fn(f64) -> bool,
    ) -> f64 {
        let (start, direction) = *self.path.get_or_insert(((pose.x, pose.y), (goal.1 - pose.y).atan2(goal.0 - pose.x)));
        if self.limit == 0.0 {
            self.limit = max_offset * self.rng.random_range(0.5..=1.0);
        }
        let (s, c) = direction.sin_cos();
        let offset = -(pose.x - start.0) * s + (pose.y - start.1) * c;
        let leg = direction + self.side * angle;
        if offset * self.side >= self.limit || !clear(leg) {
            self.side = -self.side;
            self.limit = max_offset * self.rng.random_range(0.5..=1.0);
        }
        direction + self.side * angle
    }
}
