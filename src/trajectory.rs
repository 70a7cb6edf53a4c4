//! `trajectory.csv`: one row per tick, written as the run goes so that a
//! failed run keeps everything up to the failure, and flushed at least once
//! a second so that a killed process loses at most that.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::time::{Duration, Instant};
use ubf_core::{EgomotionState, Hold, Pose2, TickRecord, TreeLayout};

/// Longest a written row waits in memory before it reaches the file.
const FLUSH_EVERY: Duration = Duration::from_secs(1);

/// Writes one CSV row per tick: time, true pose (where the robot has a
/// ground truth: a simulator's), odometric pose, the egomotion pose with its
/// failures and latest step CV, the stereo frame's number, the command, the
/// winning behaviour, and every node's vote.
pub struct TrajectoryWriter {
    out: BufWriter<File>,
    columns: Columns,
    flushed: Instant,
}

/// The optional columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Columns {
    /// `true_x,true_y,true_theta`: where the robot really was (a
    /// simulator's; a real robot has none to give).
    pub truth: bool,
    /// `hold`: why the safety guard held the robot still (`stale_data`,
    /// `contact`), empty when it did not.
    pub hold: bool,
}

/// What one row says beyond the tick's record.
#[derive(Clone, Copy, Debug)]
pub struct Row<'a> {
    /// The true pose, where there is one.
    pub truth: Option<&'a Pose2>,
    /// The robot's own estimate.
    pub odometry: &'a Pose2,
    /// The visual estimate.
    pub egomotion: &'a EgomotionState,
    /// The newest stereo frame's number.
    pub frame: u64,
    /// Why motion was held, if it was.
    pub hold: Option<Hold>,
}

impl TrajectoryWriter {
    /// Creates (or replaces) `path` and writes the header for the tree
    /// `layout`, with the true-pose columns.
    pub fn create(path: &Path, layout: &TreeLayout) -> io::Result<Self> {
        Self::new(File::create(path)?, layout, Columns { truth: true, hold: false })
    }

    /// Writes to `file` the header for the tree `layout`, with the optional
    /// `columns`.
    pub fn new(file: File, layout: &TreeLayout, columns: Columns) -> io::Result<Self> {
        let mut out = BufWriter::new(file);
        write!(out, "time_s,")?;
        if columns.truth {
            write!(out, "true_x,true_y,true_theta,")?;
        }
        write!(out, "odom_x,odom_y,odom_theta,ego_x,ego_y,ego_theta,ego_failures,ego_step_cv,frame,cmd_velocity,cmd_rot_velocity,winner")?;
        if columns.hold {
            write!(out, ",hold")?;
        }
        for node in layout.nodes.iter().skip(1) {
            write!(out, ",vote:{}", node.path)?;
        }
        writeln!(out)?;
        out.flush()?;
        Ok(TrajectoryWriter { out, columns, flushed: Instant::now() })
    }

    /// Appends the row of one tick; the egomotion columns are empty when the
    /// robot runs no estimator. The command is the tree's; where the hold
    /// column says so, the robot was sent STOP instead.
    pub fn write(&mut self, record: &TickRecord, layout: &TreeLayout, row: &Row) -> io::Result<()> {
        let Row { truth, odometry, egomotion, frame, hold } = *row;
        // A heading command has no rate yet; the robot picks one.
        let (v, w) = (record.command.velocity(), record.command.rot_velocity().unwrap_or(f64::NAN));
        let winner = layout.winning_leaf(record).map_or("", |i| layout.nodes[i].path.as_str());
        write!(self.out, "{:.3},", record.time)?;
        if self.columns.truth {
            match truth {
                Some(t) => write!(self.out, "{:.5},{:.5},{:.5},", t.x, t.y, t.theta)?,
                None => write!(self.out, ",,,")?,
            }
        }
        write!(self.out, "{:.5},{:.5},{:.5},", odometry.x, odometry.y, odometry.theta)?;
        match egomotion.pose {
            Some(p) => write!(self.out, "{:.5},{:.5},{:.5},{},", p.x, p.y, p.theta, egomotion.failures)?,
            None => write!(self.out, ",,,,")?,
        }
        match egomotion.last_step_cv {
            Some(cv) => write!(self.out, "{cv:.6},")?,
            None => write!(self.out, ",")?,
        }
        write!(self.out, "{frame},")?;
        write!(self.out, "{v:.4},{w:.4},{winner}")?;
        if self.columns.hold {
            match hold {
                Some(Hold::StaleData) => write!(self.out, ",stale_data")?,
                Some(Hold::Contact) => write!(self.out, ",contact")?,
                None => write!(self.out, ",")?,
            }
        }
        for node in record.nodes.iter().skip(1) {
            write!(self.out, ",{:.4}", node.action.effective_vote())?;
        }
        writeln!(self.out)?;
        if self.flushed.elapsed() >= FLUSH_EVERY {
            self.out.flush()?;
            self.flushed = Instant::now();
        }
        Ok(())
    }

    /// Flushes everything to disk.
    pub fn finish(mut self) -> io::Result<()> {
        self.out.flush()
    }
}
