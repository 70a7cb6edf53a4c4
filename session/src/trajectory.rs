//! `trajectory.csv`: one row per tick, written as the run goes so that a
//! failed run keeps everything up to the failure, and flushed at least once
//! a second so that a killed process loses at most that.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use ubf_core::{Hold, TickRecord, TickSink, TreeLayout};

/// Longest a written row waits in memory before it reaches the file.
const FLUSH_EVERY: Duration = Duration::from_secs(1);

/// A [`TickSink`] writing one CSV row per tick: time, true pose (where the
/// robot has a ground truth: a simulator's), the pose the robot steered by
/// (`pose_*`), the wheels' own odometric pose (`odom_*`: the two differ
/// where the wall compass or egomotion corrects odometry), the egomotion
/// pose with its failures and latest step CV, the stereo frame's number,
/// the command, the winning behaviour, and every node's vote.
pub struct TrajectoryWriter {
    out: BufWriter<File>,
    path: PathBuf,
    columns: Columns,
    layout: TreeLayout,
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
    /// `camera_pan_cmd,camera_pan`: where the tree pointed a camera on a
    /// pan-tilt unit and where the unit's encoders read it, rad from the
    /// heading (empty when not set).
    pub camera_pan: bool,
}

impl TrajectoryWriter {
    /// Creates (or replaces) `path`; the header follows when the controller
    /// starts.
    pub fn create(path: &Path, columns: Columns) -> io::Result<Self> {
        Ok(Self::new(File::create(path)?, path, columns))
    }

    /// Writes to `file`, which is at `path` (named in errors).
    pub fn new(file: File, path: &Path, columns: Columns) -> Self {
        TrajectoryWriter {
            out: BufWriter::new(file),
            path: path.to_owned(),
            columns,
            layout: TreeLayout::default(),
            flushed: Instant::now(),
        }
    }

    /// The header for the tree `layout`.
    fn header(&mut self, layout: &TreeLayout) -> io::Result<()> {
        write!(self.out, "time_s,")?;
        if self.columns.truth {
            write!(self.out, "true_x,true_y,true_theta,")?;
        }
        write!(self.out, "pose_x,pose_y,pose_theta,odom_x,odom_y,odom_theta,ego_x,ego_y,ego_theta,ego_failures,ego_step_cv,frame,ego_anchor,cmd_velocity,cmd_rot_velocity,winner")?;
        if self.columns.hold {
            write!(self.out, ",hold")?;
        }
        if self.columns.camera_pan {
            write!(self.out, ",camera_pan_cmd,camera_pan")?;
        }
        for node in layout.nodes.iter().skip(1) {
            write!(self.out, ",vote:{}", node.path)?;
        }
        writeln!(self.out)?;
        self.out.flush()
    }

    /// One tick's row; the egomotion columns are empty when the robot runs
    /// no estimator. The command is the tree's; where the hold column says
    /// so, the robot was sent STOP instead.
    fn row(&mut self, record: &TickRecord) -> io::Result<()> {
        let (pose, odometry, egomotion) = (&record.state.pose, &record.state.odometry, &record.state.egomotion);
        // A heading command has no rate yet; the robot picks one.
        let (v, w) = (record.command.velocity(), record.command.rot_velocity().unwrap_or(f64::NAN));
        let layout = &self.layout;
        let winner = layout.winning_path(record).unwrap_or("");
        write!(self.out, "{:.3},", record.time())?;
        if self.columns.truth {
            match &record.truth {
                Some(t) => write!(self.out, "{:.5},{:.5},{:.5},", t.pose.x, t.pose.y, t.pose.theta)?,
                None => write!(self.out, ",,,")?,
            }
        }
        for p in [pose, odometry] {
            write!(self.out, "{:.5},{:.5},{:.5},", p.x, p.y, p.theta)?;
        }
        match egomotion.pose {
            Some(p) => write!(self.out, "{:.5},{:.5},{:.5},{},", p.x, p.y, p.theta, egomotion.failures)?,
            None => write!(self.out, ",,,,")?,
        }
        match egomotion.last_step_cv {
            Some(cv) => write!(self.out, "{cv:.6},")?,
            None => write!(self.out, ",")?,
        }
        write!(self.out, "{},", record.state.stereo.number)?;
        match egomotion.anchor_frame {
            Some(anchor) => write!(self.out, "{anchor},")?,
            None => write!(self.out, ",")?,
        }
        write!(self.out, "{v:.4},{w:.4},{winner}")?;
        if self.columns.hold {
            match record.hold {
                Some(Hold::StaleData) => write!(self.out, ",stale_data")?,
                Some(Hold::Contact) => write!(self.out, ",contact")?,
                None => write!(self.out, ",")?,
            }
        }
        if self.columns.camera_pan {
            let root = &record.nodes[0].action;
            match root.motion.camera_pan.filter(|_| root.is_voting()) {
                Some(pan) => write!(self.out, ",{pan:.5}")?,
                None => write!(self.out, ",")?,
            }
            match record.state.camera_aim {
                Some(aim) => write!(self.out, ",{:.5}", aim.pan)?,
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

    /// Names the file in an error.
    fn named(&self, e: io::Error) -> io::Error {
        io::Error::new(e.kind(), format!("{}: {e}", self.path.display()))
    }
}

impl TickSink for TrajectoryWriter {
    fn start(&mut self, layout: &TreeLayout) -> io::Result<()> {
        self.layout = layout.clone();
        self.header(layout).map_err(|e| self.named(e))
    }

    fn record(&mut self, record: &TickRecord) -> io::Result<()> {
        self.row(record).map_err(|e| self.named(e))
    }

    /// Names the winners by the new tree; the columns stay.
    fn tree_changed(&mut self, layout: &TreeLayout) -> io::Result<()> {
        self.layout = layout.clone();
        Ok(())
    }

    /// Flushes everything to disk.
    fn finish(&mut self) -> io::Result<()> {
        self.out.flush().map_err(|e| self.named(e))
    }
}
