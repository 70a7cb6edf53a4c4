//! One policy for every command that writes a folder (`run`, `sweep`,
//! `frames`): an absent or empty `--out` is used; a non-empty one is refused
//! unless `--overwrite` is given, and even then only an earlier output of the
//! same command is removed, never a folder that merely happens to be there.

use super::CliError;
use std::path::{Path, PathBuf};

/// What a command's earlier output looks like: the files any of its
/// outputs holds, so `--overwrite` never deletes anything else.
pub(super) struct OutputKind {
    /// The command, as the user typed it (`ubf run`).
    pub command: &'static str,
    /// Files of which at least one is in every earlier output.
    pub markers: &'static [&'static str],
}

/// A run's output: `report.json` is written last, `run.mcap` first.
pub(super) const RUN: OutputKind = OutputKind { command: "ubf run", markers: &["report.json", "run.mcap"] };

/// A sweep's output, finished or interrupted.
pub(super) const SWEEP: OutputKind =
    OutputKind { command: "ubf sweep", markers: &["summary.json", ".sweep-plan.json"] };

/// A recording of stereo pairs.
pub(super) const FRAMES: OutputKind = OutputKind { command: "ubf frames", markers: &["frames.csv", "camera.ron"] };

/// Why a folder cannot take a command's output.
#[derive(Debug, thiserror::Error)]
pub(super) enum OutputError {
    #[error("cannot read --out {}: {source}", dir.display())]
    Unreadable { dir: PathBuf, source: std::io::Error },
    #[error(
        "--out {} is not empty: new files would mix with what is there. Choose another directory, or pass \
         --overwrite to replace an earlier `{command}` output{resume}",
        dir.display(),
        resume = resume_hint(.command)
    )]
    NotEmpty { dir: PathBuf, command: &'static str },
    #[error(
        "--out {} holds none of {markers}, so it is not an earlier `{command}` output: not deleting it. \
         Choose another directory",
        dir.display(),
        markers = .markers.join(", ")
    )]
    NotOurs { dir: PathBuf, command: &'static str, markers: &'static [&'static str] },
    #[error("cannot clear {}: {source}", path.display())]
    Clearing { path: PathBuf, source: std::io::Error },
}

/// Only a sweep can be resumed; its refusal says so.
fn resume_hint(command: &str) -> &'static str {
    if command == SWEEP.command {
        ", or --resume to finish an interrupted sweep"
    } else {
        ""
    }
}

impl From<OutputError> for CliError {
    /// The directory's state is the user's to change; failing to read or
    /// clear it is not.
    fn from(error: OutputError) -> Self {
        match error {
            OutputError::Unreadable { .. } | OutputError::Clearing { .. } => CliError::failed(error),
            OutputError::NotEmpty { .. } | OutputError::NotOurs { .. } => CliError::bad_input(error),
        }
    }
}

/// Makes `out` ready for `kind`'s output: absent or empty, or, with
/// `overwrite`, an earlier output of the same command, which is removed.
pub(super) fn prepare(out: &Path, kind: &OutputKind, overwrite: bool) -> Result<(), OutputError> {
    let mut entries = match std::fs::read_dir(out) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(source) => return Err(OutputError::Unreadable { dir: out.to_owned(), source }),
    };
    if entries.next().is_none() {
        return Ok(());
    }
    if !overwrite {
        return Err(OutputError::NotEmpty { dir: out.to_owned(), command: kind.command });
    }
    if !kind.markers.iter().any(|marker| out.join(marker).is_file()) {
        return Err(OutputError::NotOurs { dir: out.to_owned(), command: kind.command, markers: kind.markers });
    }
    std::fs::remove_dir_all(out).map_err(|source| OutputError::Clearing { path: out.to_owned(), source })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_absent_or_empty_folder_is_used_as_it_is() {
        let dir = tempfile::tempdir().unwrap();
        prepare(&dir.path().join("new"), &RUN, false).unwrap();
        prepare(dir.path(), &RUN, false).unwrap();
        assert!(dir.path().is_dir());
    }

    #[test]
    fn an_earlier_output_is_kept_unless_overwrite_is_asked_for() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("report.json"), "{}").unwrap();
        let refused = prepare(dir.path(), &RUN, false).unwrap_err().to_string();
        assert!(refused.contains("is not empty") && refused.contains("--overwrite"), "{refused}");
        assert!(dir.path().join("report.json").exists());
        prepare(dir.path(), &RUN, true).unwrap();
        assert!(!dir.path().exists());
    }

    #[test]
    fn overwrite_never_deletes_a_folder_another_command_or_the_user_filled() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("thesis.tex"), "precious").unwrap();
        for kind in [&RUN, &SWEEP, &FRAMES] {
            let refused = prepare(dir.path(), kind, true).unwrap_err().to_string();
            assert!(refused.contains("not deleting it"), "{refused}");
        }
        // A sweep's output is not a run's either.
        std::fs::write(dir.path().join("summary.json"), "{}").unwrap();
        assert!(prepare(dir.path(), &RUN, true).is_err());
        assert_eq!(std::fs::read_to_string(dir.path().join("thesis.tex")).unwrap(), "precious");
    }
}
