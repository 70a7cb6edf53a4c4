//! The live state on stderr while a drive runs.

use std::io::Write;
use std::time::{Duration, Instant};
use ubf_core::{TickRecord, TickSink, TreeLayout};

/// How `ubf drive` shows its live state on stderr.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Not at all (stderr is not a terminal and nobody asked).
    Off,
    /// One line, rewritten twice a second (a terminal).
    Line,
    /// A line a second (asked for, stderr not a terminal).
    Lines,
}

impl Status {
    /// How often the state is shown.
    fn every(self) -> Duration {
        match self {
            Status::Line => Duration::from_millis(500),
            Status::Off | Status::Lines => Duration::from_secs(1),
        }
    }
}

/// Shows the live state on stderr as the ticks go by: link, pose, speeds,
/// winning behaviour, hold.
pub(super) struct StatusLine {
    status: Status,
    layout: TreeLayout,
    shown: Instant,
}

impl StatusLine {
    pub(super) fn new(status: Status) -> Self {
        StatusLine { status, layout: TreeLayout::default(), shown: Instant::now() }
    }

    fn line(&self, record: &TickRecord) -> String {
        let state = &record.state;
        let layout = &self.layout;
        let winner = layout.winning_path(record).unwrap_or("-");
        let hold = match record.hold {
            Some(ubf_core::Hold::StaleData) => "stale data",
            Some(ubf_core::Hold::Contact) => "contact",
            None => "-",
        };
        format!(
            "t {:.1} s | data {:.2} s old | pose ({:.2}, {:.2}) m {:.0}° | {:.2} m/s {:.0}°/s | winner {winner} | hold \
             {hold}",
            state.time,
            state.sensor_age,
            state.pose.x,
            state.pose.y,
            state.pose.theta.to_degrees(),
            state.velocity,
            state.rot_velocity.to_degrees()
        )
    }
}

impl TickSink for StatusLine {
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.layout = layout.clone();
        Ok(())
    }

    fn tree_changed(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.start(layout)
    }

    /// Shows the tick. Output that cannot be written (the operator's
    /// terminal gone) is the sink's error, which stops the drive with the
    /// robot: no operator is watching it any more.
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        if self.shown.elapsed() >= self.status.every() {
            self.shown = Instant::now();
            let mut stderr = std::io::stderr();
            match self.status {
                Status::Line => write!(stderr, "\r{}\x1b[K", self.line(record))?,
                Status::Lines | Status::Off => writeln!(stderr, "{}", self.line(record))?,
            }
        }
        Ok(())
    }

    fn finish(&mut self) -> std::io::Result<()> {
        if self.status == Status::Line {
            writeln!(std::io::stderr())?;
        }
        Ok(())
    }
}
