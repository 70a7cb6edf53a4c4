//! The pose file: where the robot stands in the drive's world frame, kept
//! on disk so that a drive restarted after a crash (a service's restart)
//! resumes in the same frame, its goal in the same place, instead of
//! starting a new frame wherever the robot happens to stand.

use std::io;
use std::path::{Path, PathBuf};
use ubf_core::{Pose2, TickRecord, TickSink};

/// Seconds of controller time between writes while driving.
const WRITE_EVERY_S: f64 = 1.0;

/// Why a pose file could not be read.
#[derive(Debug, thiserror::Error)]
#[error("{}: {why}; remove it to start a new world frame where the robot stands", path.display())]
pub struct PoseFileError {
    path: PathBuf,
    why: String,
}

/// The pose `path` holds, if it exists.
pub(super) fn read(path: &Path) -> Result<Option<Pose2>, PoseFileError> {
    let fail = |why: String| PoseFileError { path: path.to_owned(), why };
    let text = match ubf_core::config::read_bounded(path, ubf_core::config::MOST_SETTINGS_BYTES) {
        Ok(bytes) => ubf_core::config::utf8_text(bytes).map_err(|e| fail(e.to_string()))?,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(fail(e.to_string())),
    };
    let pose: Pose2 = ubf_core::config::from_ron(&text).map_err(|e| fail(format!("{e}")))?;
    if ![pose.x, pose.y].iter().all(|v| v.abs() <= 1e4) || !pose.theta.is_finite() {
        return Err(fail(format!("({}, {}, {}) is not a pose within 10 km", pose.x, pose.y, pose.theta)));
    }
    Ok(Some(pose))
}

/// Writes `pose` to `path` atomically (a temporary file beside it, then a
/// rename), so a crash leaves the old pose or the new one, never half.
pub(super) fn write(path: &Path, pose: &Pose2) -> io::Result<()> {
    let text = format!("(x: {:?}, y: {:?}, theta: {:?})\n", pose.x, pose.y, pose.theta);
    let mut temporary = path.as_os_str().to_owned();
    temporary.push(".tmp");
    std::fs::write(&temporary, text)?;
    std::fs::rename(&temporary, path)
}

/// A sink that writes the robot's pose to the pose file once a second.
pub(super) struct PoseFileSink {
    path: PathBuf,
    written_at: Option<f64>,
}

impl PoseFileSink {
    /// Keeps the pose in `path`.
    pub(super) fn new(path: PathBuf) -> Self {
        PoseFileSink { path, written_at: None }
    }
}

impl TickSink for PoseFileSink {
    fn record(&mut self, record: &TickRecord) -> io::Result<()> {
        let time = record.time();
        if self.written_at.is_none_or(|at| time - at >= WRITE_EVERY_S) {
            self.written_at = Some(time);
            write(&self.path, &record.state.pose)
                .map_err(|e| io::Error::new(e.kind(), format!("pose file {}: {e}", self.path.display())))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pose_written_reads_back_and_a_bad_one_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("pose.ron");
        assert!(read(&path).unwrap().is_none(), "no file: no pose");
        let pose = Pose2::new(1.25, -3.5, 0.1);
        write(&path, &pose).unwrap();
        assert_eq!(read(&path).unwrap(), Some(pose));
        std::fs::write(&path, "(x: 1e300, y: 0.0, theta: 0.0)").unwrap();
        let error = read(&path).unwrap_err().to_string();
        assert!(error.contains("pose.ron") && error.contains("remove it"), "{error}");
        std::fs::write(&path, "(x: 1.0,").unwrap();
        assert!(read(&path).is_err());
    }
}
