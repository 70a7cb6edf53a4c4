//! The behaviour's phases as data: each variant carries what its phase
//! needs, so nothing of a finished phase lingers into the next.

use super::progress::ProgressWatch;

/// What the behaviour is doing, with what it needs to do it. Every phase
/// but the decision watches itself for progress, with a watch that starts
/// afresh when the phase does.
#[derive(Clone, Copy, Debug)]
pub(super) enum Phase {
    /// Choose the next heading now.
    Decide,
    /// Physical scan: turning to the left edge, then the right edge of the
    /// permitted headings (world angles), looking on the way; `from` is the
    /// heading before the sweep, which egomotion measures the chosen
    /// heading against.
    Scan { edges: [f64; 2], leg: usize, centre: f64, from: f64, watch: ProgressWatch },
    /// Turning on the spot to the chosen heading.
    Turn { heading: f64, watch: ProgressWatch },
    /// Driving one step along the heading, from where the step began.
    Step { heading: f64, from: (f64, f64), watch: ProgressWatch },
    /// The last stretch: steering at the goal every tick, as a go-to does,
    /// until it is reached. A fixed heading would pass a goal that odometry
    /// or a nudge from collision avoidance put off the line, and turning
    /// back to it on the spot beside a wall can be blocked both ways.
    Approach { watch: ProgressWatch },
}

impl Phase {
    /// A scan's first leg, towards `edges[0]`.
    pub(super) fn scan(edges: [f64; 2], centre: f64, from: f64) -> Phase {
        Phase::Scan { edges, leg: 0, centre, from, watch: ProgressWatch::new() }
    }

    /// A turn on the spot to `heading`.
    pub(super) fn turn(heading: f64) -> Phase {
        Phase::Turn { heading, watch: ProgressWatch::new() }
    }

    /// A step along `heading` from `from`.
    pub(super) fn step(heading: f64, from: (f64, f64)) -> Phase {
        Phase::Step { heading, from, watch: ProgressWatch::new() }
    }

    /// The last stretch.
    pub(super) fn approach() -> Phase {
        Phase::Approach { watch: ProgressWatch::new() }
    }

    /// Where the robot is headed: the heading of the turn or step under
    /// way, the goal's bearing `to_goal` on the last stretch, else where it
    /// faces (`facing`).
    pub(super) fn course(&self, to_goal: f64, facing: f64) -> f64 {
        match *self {
            Phase::Turn { heading, .. } | Phase::Step { heading, .. } => heading,
            Phase::Approach { .. } => to_goal,
            Phase::Decide | Phase::Scan { .. } => facing,
        }
    }
}
