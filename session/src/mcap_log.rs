//! `run.mcap`: a run's log in MCAP, the format Foxglove and the ROS 2 tools
//! read, holding the JSON topics of [`crate::json_topics`].
//!
//! The log is written as the run goes and a chunk is closed every second of
//! controller time, so a killed process leaves a file readable up to its
//! last chunk. Chunk boundaries follow controller time, not the wall clock,
//! so the same scenario and seed give the same bytes.

use crate::json_topics::{
    json_schema, nanos, report_schema, JsonChannels, JsonTopics, RunMessage, WorldMessage, WELL_KNOWN_SCHEMAS,
};
use crate::sealed_file::SealedFile;
use mcap::records::MessageHeader;
use schemars::JsonSchema;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use ubf_core::{TickRecord, TickSink, TreeLayout};

/// Why a log could not be written, or read back.
#[derive(Debug, thiserror::Error)]
#[error("{doing} {}: {message}", path.display())]
pub struct LogError {
    doing: &'static str,
    path: PathBuf,
    message: String,
}

impl LogError {
    /// Writing `path` failed, for the reason `message`.
    pub fn new(path: &Path, message: impl Into<String>) -> LogError {
        LogError { doing: "writing", path: path.to_owned(), message: message.into() }
    }

    /// Reading `path` back failed, for the reason `message`.
    pub fn reading(path: &Path, message: impl Into<String>) -> LogError {
        LogError { doing: "reading", path: path.to_owned(), message: message.into() }
    }
}

/// A run log being written: a [`TickSink`] that the controller feeds.
pub struct McapLog {
    file: McapFile,
    topics: JsonTopics,
    /// Controller time of the last closed chunk, s.
    flushed_at: f64,
}

/// The MCAP file the topics go to.
struct McapFile {
    writer: mcap::Writer<SealedFile>,
    path: PathBuf,
    channels: BTreeMap<&'static str, u16>,
    sequence: u32,
    /// Message bytes written so far (before compression).
    logged_bytes: u64,
}

/// Seconds of controller time between closed chunks.
const CHUNK_EVERY_S: f64 = 1.0;

impl McapFile {
    fn fail(&self, e: &dyn std::fmt::Display) -> LogError {
        LogError::new(&self.path, e.to_string())
    }
}

impl JsonChannels for McapFile {
    type Error = LogError;

    fn declare(&mut self, topic: &'static str, schema_name: &str, schema: &[u8]) -> Result<(), LogError> {
        // The writer gives a schema it has already written the same id.
        let schema = self.writer.add_schema(schema_name, "jsonschema", schema).map_err(|e| self.fail(&e))?;
        let id = self.writer.add_channel(schema, topic, "json", &BTreeMap::new()).map_err(|e| self.fail(&e))?;
        self.channels.insert(topic, id);
        Ok(())
    }

    fn write(&mut self, topic: &'static str, time: f64, data: &[u8]) -> Result<(), LogError> {
        self.logged_bytes += data.len() as u64;
        let channel_id = self.channels[topic];
        self.sequence += 1;
        let header =
            MessageHeader { channel_id, sequence: self.sequence, log_time: nanos(time), publish_time: nanos(time) };
        self.writer.write_to_known_channel(&header, data).map_err(|e| self.fail(&e))
    }
}

impl McapLog {
    /// Creates (or replaces) the log at `path`, declares its topics and
    /// writes what the run is: its world, goal and the scene Foxglove draws.
    pub fn create(path: &Path, run: &RunMessage, world: &WorldMessage) -> Result<McapLog, LogError> {
        let mut log = McapLog::open(path, ("ubf.Report", report_schema()))?;
        JsonTopics::describe(&mut log.file, 0.0, run, world)?;
        Ok(log)
    }

    /// Creates the log of a session on a real robot at `path`: no world,
    /// a `/report` of the `ubf.DriveReport` kind ([`McapLog::write_report`]),
    /// and, in a metadata record `ubf.wall_clock`, the UTC time at which
    /// the log's time 0 was (`utc_start`, RFC 3339, and
    /// `unix_time_ns`), to within a tick.
    pub fn create_for_drive<T: JsonSchema>(path: &Path, run: &RunMessage) -> Result<McapLog, LogError> {
        let mut log = McapLog::open(path, ("ubf.DriveReport", json_schema::<T>()))?;
        let now = time::OffsetDateTime::now_utc();
        let file = &mut log.file;
        let utc = now.format(&time::format_description::well_known::Rfc3339).map_err(|e| file.fail(&e))?;
        let metadata = mcap::records::Metadata {
            name: "ubf.wall_clock".into(),
            metadata: BTreeMap::from([
                ("utc_start".to_owned(), utc),
                ("unix_time_ns".to_owned(), now.unix_timestamp_nanos().to_string()),
            ]),
        };
        file.writer.write_metadata(&metadata).map_err(|e| file.fail(&e))?;
        JsonTopics::describe(file, 0.0, run, &WorldMessage::default())?;
        Ok(log)
    }

    /// Writes `report` on `/report` at `time` and flushes, so that it is
    /// in the file whatever happens next.
    pub fn write_report(&mut self, time: f64, report: &impl Serialize) -> Result<(), LogError> {
        crate::json_topics::send(&mut self.file, "/report", time, report)?;
        let file = &mut self.file;
        file.writer.flush().map_err(|e| file.fail(&e))
    }

    /// Message bytes logged so far, before compression: what a cap on the
    /// log's size counts.
    pub fn logged_bytes(&self) -> u64 {
        self.file.logged_bytes
    }

    /// Logs each stereo frame's pair of images (PNG, about 0.2 MB a pair
    /// of 640 × 480), where the camera keeps them; off by default.
    pub fn log_images(&mut self, images: bool) {
        self.topics.images(images);
    }

    /// Opens the log with its channels, `/report`'s schema named and given
    /// by `report`.
    fn open(path: &Path, report: (&str, Vec<u8>)) -> Result<McapLog, LogError> {
        let fail = |e: &dyn std::fmt::Display| LogError::new(path, e.to_string());
        let file = SealedFile::create(path).map_err(|e| fail(&e))?;
        let options = mcap::WriteOptions::new().profile("").library(concat!("ubf ", env!("CARGO_PKG_VERSION")));
        let writer = options.create(file).map_err(|e| fail(&e))?;
        let mut file =
            McapFile { writer, path: path.to_owned(), channels: BTreeMap::new(), sequence: 0, logged_bytes: 0 };
        // The well-known schemas first, as the log has always had them:
        // the same run gives the same bytes as it did.
        for (name, schema) in WELL_KNOWN_SCHEMAS {
            file.writer.add_schema(name, "jsonschema", schema.as_bytes()).map_err(|e| fail(&e))?;
        }
        JsonTopics::declare(&mut file, report)?;
        Ok(McapLog { file, topics: JsonTopics::default(), flushed_at: 0.0 })
    }

    /// Writes the report and closes the log (its summary and footer).
    pub fn close_with_report(mut self, time: f64, report: &impl Serialize) -> Result<(), LogError> {
        crate::json_topics::send(&mut self.file, "/report", time, report)?;
        self.close()
    }

    /// Closes the log without a report (a run that failed): what was
    /// written stays readable.
    pub fn close(mut self) -> Result<(), LogError> {
        let file = &mut self.file;
        file.writer.finish().map_err(|e| file.fail(&e))?;
        Ok(())
    }
}

impl TickSink for McapLog {
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.topics.start(layout);
        Ok(())
    }

    fn tree_changed(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.topics.start(layout);
        Ok(())
    }

    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        self.topics.tick(&mut self.file, record).map_err(std::io::Error::other)?;
        let time = record.time();
        if time - self.flushed_at >= CHUNK_EVERY_S {
            let file = &mut self.file;
            file.writer.flush().map_err(|e| std::io::Error::other(file.fail(&e)))?;
            self.flushed_at = time;
        }
        Ok(())
    }

    /// Closes the chunk under way, so that everything logged is readable;
    /// the summary is written when the log is closed (or dropped).
    fn finish(&mut self) -> std::io::Result<()> {
        let file = &mut self.file;
        file.writer.flush().map_err(|e| std::io::Error::other(file.fail(&e)))
    }
}
