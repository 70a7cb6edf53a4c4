//! A file an MCAP writer writes through that is a complete MCAP after every
//! flush, so that a process killed mid-run (SIGKILL, a power cut) leaves a
//! log the standard readers open, up to its last flush.
//!
//! The MCAP writer closes a chunk and flushes its stream every second of
//! the log. At each flush, what it wrote since goes to the file followed by
//! a provisional end: a Data End record, a Footer with no summary, and the
//! closing magic; the next flush writes over that end. Readers then read the
//! file linearly, as they do any MCAP without a summary. When the writer
//! finishes, its own summary and footer replace the provisional end and the
//! file is cut to length.
//!
//! Each flush is one positioned write: a kill lands before or after it, and
//! only a kill inside a write the kernel splits (a write of many megabytes,
//! images) can leave a torn end.

use std::fs::File;
use std::io::{self, Seek, SeekFrom, Write};
use std::os::unix::fs::FileExt;
use std::path::Path;

/// A Data End record with no CRC, a Footer with no summary, and the magic:
/// the smallest valid end of an MCAP file.
const PROVISIONAL_END: [u8; 13 + 29 + 8] = {
    let mut end = [0u8; 50];
    // Data End: opcode 0x0F, length 4, data section CRC 0 (not computed).
    end[0] = 0x0F;
    end[1] = 4;
    // Footer: opcode 0x02, length 20, summary start, summary offset start
    // and summary CRC all 0 (no summary).
    end[13] = 0x02;
    end[14] = 20;
    let magic = *b"\x89MCAP0\r\n";
    let mut i = 0;
    while i < 8 {
        end[42 + i] = magic[i];
        i += 1;
    }
    end
};

/// A file written as an MCAP writer's stream: see the module's description.
pub struct SealedFile {
    file: File,
    /// Where the bytes not yet in the file start (and the provisional end
    /// lies).
    written: u64,
    /// The bytes written since the last flush.
    pending: Vec<u8>,
    /// The stream position, relative to `written`.
    cursor: usize,
}

impl SealedFile {
    /// Creates (or replaces) the file at `path`.
    pub fn create(path: &Path) -> io::Result<SealedFile> {
        let file = File::create(path)?;
        Ok(SealedFile { file, written: 0, pending: Vec::new(), cursor: 0 })
    }

    /// Writes what is pending at the end of the file, followed by `end`.
    /// A write that fails (a full disk) leaves what is pending pending.
    fn write_pending(&mut self, end: &[u8]) -> io::Result<()> {
        let length = self.pending.len();
        self.pending.extend_from_slice(end);
        let written = self.file.write_all_at(&self.pending, self.written);
        self.pending.truncate(length);
        written?;
        self.written += length as u64;
        self.pending.clear();
        self.cursor = 0;
        Ok(())
    }

    /// Writes the finished file's last bytes and cuts it to length (the
    /// provisional end may reach past the real one).
    fn close(&mut self) -> io::Result<()> {
        self.write_pending(&[])?;
        self.file.set_len(self.written)
    }
}

impl Write for SealedFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let overlap = (self.pending.len() - self.cursor).min(buf.len());
        self.pending[self.cursor..self.cursor + overlap].copy_from_slice(&buf[..overlap]);
        self.pending.extend_from_slice(&buf[overlap..]);
        self.cursor += buf.len();
        Ok(buf.len())
    }

    /// Puts everything written so far in the file, as a complete MCAP.
    fn flush(&mut self) -> io::Result<()> {
        if self.cursor != self.pending.len() {
            return Err(io::Error::other("flushed in the middle of a record"));
        }
        self.write_pending(&PROVISIONAL_END)
    }
}

impl Seek for SealedFile {
    /// Seeks within what was written since the last flush; the writer only
    /// goes back to fill in the record it is writing.
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        let end = self.written + self.pending.len() as u64;
        let here = self.written + self.cursor as u64;
        let target = match to {
            SeekFrom::Start(p) => Some(p),
            SeekFrom::End(d) => end.checked_add_signed(d),
            SeekFrom::Current(d) => here.checked_add_signed(d),
        };
        match target {
            Some(p) if (self.written..=end).contains(&p) => {
                self.cursor = (p - self.written) as usize;
                Ok(p)
            }
            _ => Err(io::Error::new(io::ErrorKind::Unsupported, "seeking into what is already in the file")),
        }
    }
}

impl Drop for SealedFile {
    /// Whatever the writer wrote last (its summary and footer, when it
    /// finished) goes to the file, which is cut to length.
    fn drop(&mut self) {
        if let Err(e) = self.close() {
            tracing::warn!("closing a log: {e}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_is_an_error_and_the_file_stays_usable() {
        // Every write to /dev/full fails as a full disk's does.
        let Ok(mut file) = SealedFile::create(Path::new("/dev/full")) else { return };
        file.write_all(b"a record").unwrap();
        assert!(file.flush().is_err());
        // It used to lose track of what was pending and panic here.
        file.write_all(b"and another").unwrap();
        assert!(file.flush().is_err());
        assert_eq!(file.pending, b"a recordand another");
    }

    /// Messages on one channel, a flush after each; `finish` or not.
    fn write_log(path: &Path, messages: u64, finish: bool) {
        let file = SealedFile::create(path).unwrap();
        let mut writer = mcap::WriteOptions::new().create(file).unwrap();
        let channel = writer.add_channel(0, "/t", "json", &Default::default()).unwrap();
        for i in 0..messages {
            let header =
                mcap::records::MessageHeader { channel_id: channel, sequence: 0, log_time: i, publish_time: i };
            writer.write_to_known_channel(&header, b"{}").unwrap();
            writer.flush().unwrap();
        }
        if finish {
            writer.finish().unwrap();
        } else {
            // As a killed process would: nothing after the last flush.
            std::mem::forget(writer);
        }
    }

    fn count(path: &Path) -> usize {
        let bytes = std::fs::read(path).unwrap();
        mcap::MessageStream::new(&bytes).unwrap().collect::<Result<Vec<_>, _>>().unwrap().len()
    }

    #[test]
    fn a_log_is_whole_after_every_flush_and_at_its_end() {
        let dir = tempfile::tempdir().unwrap();
        let (killed, finished) = (dir.path().join("killed.mcap"), dir.path().join("finished.mcap"));
        write_log(&killed, 5, false);
        assert_eq!(count(&killed), 5, "every flushed message reads back from a killed writer's file");
        write_log(&finished, 5, true);
        assert_eq!(count(&finished), 5);
        let bytes = std::fs::read(&finished).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().expect("the finished file has its summary");
        assert_eq!(summary.stats.unwrap().message_count, 5);
    }
}
