//! Files that appear whole or not at all.
//!
//! [`write()`] writes into a temporary name in the file's own folder and
//! renames it over the file once every byte is in: a process stopped at any
//! point (Ctrl-C, SIGKILL) leaves either the old file or the new one, and a
//! write that fails (a full disk, a file size limit) leaves neither a
//! half-written file nor an empty one, only the error.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The temporary name [`write()`] writes `path` under before renaming it:
/// `.NAME.partial` beside it. A process killed mid-write may leave one; the
/// next write of the same file replaces it.
pub fn partial_name(path: &Path) -> PathBuf {
    let name = path.file_name().map_or_else(|| "file".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.partial"))
}

/// Writes `bytes` to `path` atomically: to [`partial_name`] first, then
/// renamed over `path`. On failure the temporary file is removed and `path`
/// is as it was.
pub fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let partial = partial_name(path);
    let written = std::fs::File::create(&partial).and_then(|mut file| {
        file.write_all(bytes)?;
        file.flush()
    });
    let renamed = written.and_then(|()| std::fs::rename(&partial, path));
    if renamed.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    renamed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_replaced_whole_and_leaves_no_temporary_name() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("report.json");
        write(&path, b"first").unwrap();
        write(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["report.json"]);
        // A folder standing where the file goes: an error, and nothing left.
        std::fs::create_dir(dir.path().join("taken")).unwrap();
        std::fs::write(dir.path().join("taken/inside"), b"").unwrap();
        assert!(write(&dir.path().join("taken"), b"x").is_err());
        assert!(!partial_name(&dir.path().join("taken")).exists());
    }
}
