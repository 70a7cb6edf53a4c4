//! One policy for every command that writes a folder (`run`, `sweep`,
//! `frames`): an absent or empty `--out` is used; a non-empty one is refused
//! unless `--overwrite` is given, and even then only an earlier output of the
//! same command is removed, and only if everything in the folder is what
//! that command writes: never a file the user keeps there, such as the very
//! scenario the command reads.

use super::CliError;
use std::path::{Path, PathBuf};

/// What a command's earlier output looks like: the files any of its
/// outputs holds, and every name it writes, so `--overwrite` never deletes
/// anything else.
pub(super) struct OutputKind {
    /// The command, as the user typed it (`ubf run`).
    pub command: &'static str,
    /// Files of which at least one is in every earlier output (a sweep's
    /// shards are told by their records' names instead).
    pub markers: &'static [&'static str],
    /// The first thing in an entry of the folder that the command did not
    /// write: the entry itself, or something inside it.
    pub stranger: fn(&Path) -> Option<PathBuf>,
}

/// A run's output: `report.json` is written last, `run.mcap` first.
pub(super) const RUN: OutputKind =
    OutputKind { command: "ubf run", markers: &["report.json", "run.mcap"], stranger: run_stranger };

/// A sweep's output, finished or interrupted.
pub(super) const SWEEP: OutputKind =
    OutputKind { command: "ubf sweep", markers: &["summary.json", ".sweep-plan.json"], stranger: sweep_stranger };

/// A recording of stereo pairs.
pub(super) const FRAMES: OutputKind =
    OutputKind { command: "ubf frames", markers: &["frames.csv", "camera.ron"], stranger: frames_stranger };

/// The entry's file name, if it has one that is text.
fn name_of(entry: &Path) -> &str {
    entry.file_name().and_then(|name| name.to_str()).unwrap_or("")
}

/// A file written atomically leaves `.NAME.partial` if killed mid-write.
fn is_partial(name: &str) -> bool {
    name.starts_with('.') && name.ends_with(".partial")
}

/// A regular file, not a link to one: a link ubf never writes.
fn is_file(entry: &Path) -> bool {
    entry.symlink_metadata().is_ok_and(|m| m.is_file())
}

/// A folder, not a link to one.
fn is_folder(entry: &Path) -> bool {
    entry.symlink_metadata().is_ok_and(|m| m.is_dir())
}

/// The first stranger among folder `dir`'s entries, by `stranger`; the
/// folder itself if it cannot be read.
fn stranger_in(dir: &Path, stranger: fn(&Path) -> Option<PathBuf>) -> Option<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Some(dir.to_owned()) };
    let mut paths: Vec<PathBuf> = entries.flatten().map(|entry| entry.path()).collect();
    paths.sort();
    paths.iter().find_map(|path| stranger(path))
}

/// `entry` itself if `written` says the command did not write it.
fn unless(entry: &Path, written: bool) -> Option<PathBuf> {
    (!written).then(|| entry.to_owned())
}

fn run_stranger(entry: &Path) -> Option<PathBuf> {
    match name_of(entry) {
        // `ubf replay` draws its plot beside the log.
        "report.json" | "trajectory.csv" | "plot.png" | "run.mcap" | "run-replay.png" => unless(entry, is_file(entry)),
        name if name == crate::run::ROSBAG_DIR => match is_folder(entry) {
            true => stranger_in(entry, |file| {
                let name = name_of(file);
                unless(file, is_file(file) && (name == "metadata.yaml" || name.ends_with(".mcap")))
            }),
            false => Some(entry.to_owned()),
        },
        name => unless(entry, is_partial(name) && !entry.is_symlink()),
    }
}

/// A sweep's shard record, `shard-K-of-N.json`, or its plan.
fn is_shard_file(name: &str) -> bool {
    let name = name.strip_prefix('.').unwrap_or(name);
    name.starts_with("shard-") && name.ends_with(".json")
}

/// A seed's folder in a sweep: `seed-N`, or `.seed-N.partial` while it is
/// written.
fn is_seed_name(name: &str) -> bool {
    let seed = name.strip_prefix('.').unwrap_or(name).split('.').next().unwrap_or("");
    seed.strip_prefix("seed-").is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

fn sweep_stranger(entry: &Path) -> Option<PathBuf> {
    let name = name_of(entry);
    match name {
        "summary.json" | "summary.csv" | ".sweep-plan.json" => unless(entry, is_file(entry)),
        _ if is_shard_file(name) || is_partial(name) => unless(entry, is_file(entry) || is_folder(entry)),
        // A scenario's folder: its seeds' folders, each a run's output.
        _ if is_folder(entry) => stranger_in(entry, |seed| match is_seed_name(name_of(seed)) && is_folder(seed) {
            true => stranger_in(seed, run_stranger),
            false => Some(seed.to_owned()),
        }),
        _ => Some(entry.to_owned()),
    }
}

fn frames_stranger(entry: &Path) -> Option<PathBuf> {
    match name_of(entry) {
        "frames.csv" | "camera.ron" => unless(entry, is_file(entry)),
        "left" | "right" if is_folder(entry) => {
            stranger_in(entry, |image| unless(image, is_file(image) && name_of(image).ends_with(".png")))
        }
        name => unless(entry, is_partial(name) && is_file(entry)),
    }
}

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
    #[error(
        "--out holds {}, which `{command}` does not write: not deleting it, nor the rest. Move it out, or choose \
         another directory",
        path.display()
    )]
    Stranger { path: PathBuf, command: &'static str },
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
            OutputError::NotEmpty { .. } | OutputError::NotOurs { .. } | OutputError::Stranger { .. } => {
                CliError::bad_input(error)
            }
        }
    }
}

/// Makes `out` ready for `kind`'s output: absent or empty, or, with
/// `overwrite`, an earlier output of the same command and nothing else,
/// whose entries are removed (the folder stays).
pub(super) fn prepare(out: &Path, kind: &OutputKind, overwrite: bool) -> Result<(), OutputError> {
    let unreadable = |source| OutputError::Unreadable { dir: out.to_owned(), source };
    let entries: Vec<PathBuf> = match std::fs::read_dir(out) {
        Ok(entries) => entries.map(|entry| entry.map(|e| e.path())).collect::<Result<_, _>>().map_err(unreadable)?,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(source) => return Err(unreadable(source)),
    };
    if entries.is_empty() {
        return Ok(());
    }
    if !overwrite {
        return Err(OutputError::NotEmpty { dir: out.to_owned(), command: kind.command });
    }
    let marked = kind.markers.iter().any(|marker| is_file(&out.join(marker)))
        || (kind.command == SWEEP.command && entries.iter().any(|entry| is_shard_file(name_of(entry))));
    if !marked {
        return Err(OutputError::NotOurs { dir: out.to_owned(), command: kind.command, markers: kind.markers });
    }
    let mut sorted = entries.clone();
    sorted.sort();
    if let Some(stranger) = sorted.iter().find_map(|entry| (kind.stranger)(entry)) {
        return Err(OutputError::Stranger { path: stranger, command: kind.command });
    }
    for entry in &entries {
        let removed = if is_folder(entry) { std::fs::remove_dir_all(entry) } else { std::fs::remove_file(entry) };
        removed.map_err(|source| OutputError::Clearing { path: entry.clone(), source })?;
    }
    Ok(())
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
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
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

    #[test]
    fn overwrite_keeps_what_the_command_does_not_write_and_then_deletes_nothing() {
        // The scenario beside its run's output, a user's notes in a sweep's.
        let dir = tempfile::tempdir().unwrap();
        let run = dir.path().join("run");
        std::fs::create_dir(&run).unwrap();
        for file in ["report.json", "run.mcap", "my.ron"] {
            std::fs::write(run.join(file), "kept").unwrap();
        }
        let refused = prepare(&run, &RUN, true).unwrap_err().to_string();
        assert!(refused.contains("my.ron") && refused.contains("not deleting it"), "{refused}");
        assert!(run.join("report.json").exists() && run.join("my.ron").exists());
        let sweep = dir.path().join("sweep");
        std::fs::create_dir_all(sweep.join("corridor/seed-0")).unwrap();
        std::fs::write(sweep.join("summary.json"), "{}").unwrap();
        std::fs::write(sweep.join("corridor/seed-0/report.json"), "{}").unwrap();
        std::fs::write(sweep.join("corridor/notes.txt"), "kept").unwrap();
        let refused = prepare(&sweep, &SWEEP, true).unwrap_err().to_string();
        assert!(refused.contains("corridor"), "{refused}");
        assert!(sweep.join("corridor/notes.txt").exists() && sweep.join("summary.json").exists());
        // A stranger deep inside is the one named; a link is never ours.
        std::fs::remove_file(sweep.join("corridor/notes.txt")).unwrap();
        std::fs::write(sweep.join("corridor/seed-0/notes.txt"), "kept").unwrap();
        let refused = prepare(&sweep, &SWEEP, true).unwrap_err().to_string();
        assert!(refused.contains("seed-0/notes.txt"), "{refused}");
        std::fs::remove_file(sweep.join("corridor/seed-0/notes.txt")).unwrap();
        std::os::unix::fs::symlink(dir.path().join("run"), sweep.join("corridor/seed-0/run-rosbag2")).unwrap();
        assert!(prepare(&sweep, &SWEEP, true).unwrap_err().to_string().contains("run-rosbag2"));
        std::fs::remove_file(sweep.join("corridor/seed-0/run-rosbag2")).unwrap();
        // Without the stranger, the sweep's output goes and the folder stays.
        std::fs::create_dir_all(sweep.join("corridor/.seed-1.partial")).unwrap();
        std::fs::write(sweep.join("shard-0-of-2.json"), "{}").unwrap();
        prepare(&sweep, &SWEEP, true).unwrap();
        assert_eq!(std::fs::read_dir(&sweep).unwrap().count(), 0);
        // A rosbag2 folder is looked into too; a shard's output is a sweep's.
        let bag = run.join("run-rosbag2");
        std::fs::create_dir(&bag).unwrap();
        std::fs::write(bag.join("metadata.yaml"), "").unwrap();
        std::fs::write(bag.join("notes.md"), "kept").unwrap();
        std::fs::remove_file(run.join("my.ron")).unwrap();
        assert!(prepare(&run, &RUN, true).unwrap_err().to_string().contains("run-rosbag2/notes.md"));
        std::fs::remove_file(bag.join("notes.md")).unwrap();
        prepare(&run, &RUN, true).unwrap();
        std::fs::write(sweep.join("shard-0-of-2.json"), "{}").unwrap();
        prepare(&sweep, &SWEEP, true).unwrap();
    }
}
