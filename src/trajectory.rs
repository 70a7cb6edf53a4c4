//! `trajectory.csv`: one row per tick, written as the run goes so that a
//! failed run keeps everything up to the failure.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use ubf_core::{Command, EgomotionState, Pose2, TickRecord, TreeLayout, Turn};

/// Writes one CSV row per tick: time, true and odometric pose, the
/// egomotion pose with its failures and latest step CV, the stereo frame's
/// number, the command, the winning behaviour, and every node's vote.
pub struct TrajectoryWriter {
    out: BufWriter<File>,
}

impl TrajectoryWriter {
    /// Creates `path` and writes the header for the tree `layout`.
    pub fn create(path: &Path, layout: &TreeLayout) -> io::Result<Self> {
        let mut out = BufWriter::new(File::create(path)?);
        write!(out, "time_s,true_x,true_y,true_theta,odom_x,odom_y,odom_theta,ego_x,ego_y,ego_theta,ego_failures,ego_step_cv,frame,cmd_velocity,cmd_rot_velocity,winner")?;
        for node in layout.nodes.iter().skip(1) {
            write!(out, ",vote:{}", node.path)?;
        }
        writeln!(out)?;
        Ok(TrajectoryWriter { out })
    }

    /// Appends the row of one tick; the egomotion columns are empty when the
    /// robot runs no estimator.
    pub fn write(
        &mut self,
        record: &TickRecord,
        layout: &TreeLayout,
        truth: &Pose2,
        odometry: &Pose2,
        egomotion: &EgomotionState,
        frame: u64,
    ) -> io::Result<()> {
        let (v, w) = match record.command {
            Command::Stop => (0.0, 0.0),
            Command::Drive { velocity, turn: Turn::Rate(rate) } => (velocity, rate),
            // A heading command has no rate yet; the robot picks one.
            Command::Drive { velocity, turn: Turn::Heading { .. } } => (velocity, f64::NAN),
        };
        let winner = layout.winning_leaf(record).map_or("", |i| layout.nodes[i].path.as_str());
        write!(
            self.out,
            "{:.3},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},",
            record.time, truth.x, truth.y, truth.theta, odometry.x, odometry.y, odometry.theta
        )?;
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
        for node in record.nodes.iter().skip(1) {
            write!(self.out, ",{:.4}", node.action.effective_vote())?;
        }
        writeln!(self.out)
    }

    /// Flushes everything to disk.
    pub fn finish(mut self) -> io::Result<()> {
        self.out.flush()
    }
}
