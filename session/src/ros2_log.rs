//! A run's or a drive's log as a rosbag2 directory, the form `ros2 bag
//! info`, `ros2 bag play`, the `rosbags` library and Foxglove read: a
//! `metadata.yaml` beside an MCAP whose profile is `ros2`, whose messages
//! are CDR and whose schemas are the `ros2msg` definitions (standard types
//! where they exist, ubf's own `ubf_msgs/msg/Tick` with its definition
//! embedded).
//!
//! The messages are those the live ROS 2 view publishes
//! ([`crate::ros2_view`]), plus `/ubf/report` (`std_msgs/msg/String`, the
//! report as JSON) at the end. Stamps are controller time plus an epoch:
//! 0 for a simulated run, so that the same scenario and seed give the same
//! bytes; the wall clock at the start for a drive.

use crate::mcap_log::LogError;
use crate::ros2_view::{topics, Ros2View, Shown};
use crate::sealed_file::SealedFile;
use mcap::records::MessageHeader;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use ubf_core::{TickRecord, TickSink, TreeLayout};
use ubf_robots::ros2::msg::{to_cdr, RosMessage, StringMessage};

/// The form of a run's or a drive's MCAP log.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, clap::ValueEnum)]
pub enum LogFormat {
    /// JSON messages with Foxglove's schemas (and ubf's own): what Foxglove,
    /// `ubf replay` and the plot read.
    #[default]
    #[value(name = "json")]
    Json,
    /// Also a rosbag2 directory of CDR messages of standard ROS 2 types,
    /// for `ros2 bag` and the rosbags library.
    #[value(name = "ros2")]
    Ros2,
}

/// The topic of the report at the end of the log.
pub const REPORT_TOPIC: &str = "/ubf/report";

/// Seconds of controller time between closed chunks, as in the JSON log:
/// a killed process leaves a log readable up to its last chunk.
const CHUNK_EVERY_S: f64 = 1.0;

/// A topic of the bag.
struct Channel {
    id: u16,
    type_name: &'static str,
    qos: &'static str,
    count: u64,
}

/// A rosbag2 directory being written: a [`TickSink`].
pub struct Ros2Log {
    writer: mcap::Writer<SealedFile>,
    dir: PathBuf,
    file_name: String,
    view: Ros2View,
    schemas: BTreeMap<&'static str, u16>,
    channels: BTreeMap<String, Channel>,
    sequence: u32,
    /// Log times of the first and the last message, ns.
    span_ns: Option<(u64, u64)>,
    flushed_at: f64,
}

/// rosbag2's record of a writer's QoS (its numeric YAML form): what
/// `ros2 bag play` offers again. Reliable and volatile.
const RELIABLE_QOS: &str = "- history: 3\n  depth: 0\n  reliability: 1\n  durability: 2\n  deadline:\n    sec: 9223372036\n    nsec: 854775807\n  lifespan:\n    sec: 9223372036\n    nsec: 854775807\n  liveliness: 1\n  liveliness_lease_duration:\n    sec: 9223372036\n    nsec: 854775807\n  avoid_ros_namespace_conventions: false";
/// Best effort and volatile, as sensor data is published.
const SENSOR_QOS: &str = "- history: 3\n  depth: 0\n  reliability: 2\n  durability: 2\n  deadline:\n    sec: 9223372036\n    nsec: 854775807\n  lifespan:\n    sec: 9223372036\n    nsec: 854775807\n  liveliness: 1\n  liveliness_lease_duration:\n    sec: 9223372036\n    nsec: 854775807\n  avoid_ros_namespace_conventions: false";

fn qos_of(topic: &str) -> &'static str {
    match topic {
        topics::SCAN | topics::LEFT_IMAGE | topics::RIGHT_IMAGE => SENSOR_QOS,
        _ => RELIABLE_QOS,
    }
}

/// A log time, ns.
fn nanos(seconds: f64) -> u64 {
    (seconds.max(0.0) * 1e9).round() as u64
}

impl Ros2Log {
    /// Creates the directory `dir` (which must not hold a bag already) and
    /// the bag in it, logging what `shown` asks for, stamped with
    /// controller time plus `epoch_s`.
    pub fn create(dir: &Path, shown: Shown, epoch_s: f64) -> Result<Ros2Log, LogError> {
        let fail = |e: &dyn std::fmt::Display| LogError::new(dir, e.to_string());
        if dir.join("metadata.yaml").exists() {
            return Err(fail(&"a rosbag2 log is there already; move it away or choose another folder"));
        }
        std::fs::create_dir_all(dir).map_err(|e| fail(&e))?;
        let stem = dir.file_name().map_or_else(|| "ubf".into(), |s| s.to_string_lossy().into_owned());
        let file_name = format!("{stem}_0.mcap");
        let file = SealedFile::create(&dir.join(&file_name)).map_err(|e| fail(&e))?;
        let options = mcap::WriteOptions::new().profile("ros2").library(concat!("ubf ", env!("CARGO_PKG_VERSION")));
        let writer = options.create(file).map_err(|e| fail(&e))?;
        Ok(Ros2Log {
            writer,
            dir: dir.to_owned(),
            file_name,
            view: Ros2View::new(shown, epoch_s),
            schemas: BTreeMap::new(),
            channels: BTreeMap::new(),
            sequence: 0,
            span_ns: None,
            flushed_at: 0.0,
        })
    }

    fn fail(&self, e: &dyn std::fmt::Display) -> LogError {
        LogError::new(&self.dir, e.to_string())
    }

    /// Writes one CDR message of type `type_name` on `topic`, stamped
    /// `stamp_s`.
    fn write(
        &mut self,
        topic: &str,
        (type_name, schema): (&'static str, &'static str),
        stamp_s: f64,
        data: &[u8],
    ) -> Result<(), LogError> {
        if !self.channels.contains_key(topic) {
            let schema_id = match self.schemas.get(type_name) {
                Some(id) => *id,
                None => {
                    let id =
                        self.writer.add_schema(type_name, "ros2msg", schema.as_bytes()).map_err(|e| self.fail(&e))?;
                    self.schemas.insert(type_name, id);
                    id
                }
            };
            let qos = qos_of(topic);
            let metadata = BTreeMap::from([("offered_qos_profiles".to_owned(), qos.to_owned())]);
            let id = self.writer.add_channel(schema_id, topic, "cdr", &metadata).map_err(|e| self.fail(&e))?;
            self.channels.insert(topic.to_owned(), Channel { id, type_name, qos, count: 0 });
        }
        let channel = self.channels.get_mut(topic).expect("added above");
        channel.count += 1;
        self.sequence += 1;
        let time = nanos(stamp_s);
        self.span_ns = Some(self.span_ns.map_or((time, time), |(first, last)| (first.min(time), last.max(time))));
        let header =
            MessageHeader { channel_id: channel.id, sequence: self.sequence, log_time: time, publish_time: time };
        self.writer.write_to_known_channel(&header, data).map_err(|e| self.fail(&e))
    }

    fn tick(&mut self, record: &TickRecord) -> Result<(), LogError> {
        let mut messages = Vec::new();
        self.view.messages(record, |topic, stamp, message| messages.push((topic, stamp, message)));
        for (topic, stamp, message) in messages {
            self.write(&ros_name(topic), (message.type_name(), message.schema()), stamp, &message.to_cdr())?;
        }
        if record.time() - self.flushed_at >= CHUNK_EVERY_S {
            self.writer.flush().map_err(|e| self.fail(&e))?;
            self.flushed_at = record.time();
        }
        Ok(())
    }

    /// Writes `report` (JSON) on [`REPORT_TOPIC`] at controller time
    /// `time`, and closes the bag.
    pub fn close_with_report(mut self, time: f64, report: &serde_json::Value) -> Result<(), LogError> {
        let text = StringMessage { data: report.to_string() };
        let stamp = self.view.stamp(time);
        self.write(REPORT_TOPIC, (StringMessage::NAME, StringMessage::SCHEMA), stamp, &to_cdr(&text))?;
        self.close()
    }

    /// Closes the bag (its MCAP summary and footer, then `metadata.yaml`).
    pub fn close(mut self) -> Result<(), LogError> {
        self.writer.finish().map_err(|e| self.fail(&e))?;
        self.write_metadata()
    }

    /// Writes `metadata.yaml` (rosbag2's version 5) for what is logged so
    /// far, through a temporary file, so that a reader never sees half of
    /// one.
    fn write_metadata(&self) -> Result<(), LogError> {
        let (first, last) = self.span_ns.unwrap_or((0, 0));
        let total: u64 = self.channels.values().map(|c| c.count).sum();
        let mut yaml = format!(
            "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  duration:\n    nanoseconds: \
             {}\n  starting_time:\n    nanoseconds_since_epoch: {first}\n  message_count: {total}\n  \
             topics_with_message_count:\n",
            last - first
        );
        for (name, channel) in &self.channels {
            let qos: String = channel.qos.lines().map(|line| format!("\n          {line}")).collect();
            yaml += &format!(
                "    - topic_metadata:\n        name: {name}\n        type: {}\n        serialization_format: cdr\n        \
                 offered_qos_profiles: |-{qos}\n      message_count: {}\n",
                channel.type_name, channel.count
            );
        }
        yaml += &format!(
            "  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n    - {file}\n  files:\n    - \
             path: {file}\n      starting_time:\n        nanoseconds_since_epoch: {first}\n      duration:\n        \
             nanoseconds: {}\n      message_count: {total}\n",
            last - first,
            file = self.file_name
        );
        let (path, temporary) = (self.dir.join("metadata.yaml"), self.dir.join(".metadata.yaml.part"));
        std::fs::write(&temporary, yaml).and_then(|()| std::fs::rename(&temporary, &path)).map_err(|e| self.fail(&e))
    }
}

/// A topic of the view as the bag names it: absolute.
fn ros_name(topic: &str) -> String {
    if topic.starts_with('/') {
        topic.to_owned()
    } else {
        format!("/{topic}")
    }
}

impl TickSink for Ros2Log {
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.view.start(layout);
        Ok(())
    }

    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        self.tick(record).map_err(std::io::Error::other)
    }

    fn tree_changed(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.view.start(layout);
        Ok(())
    }

    /// Closes the chunk under way and writes `metadata.yaml` for what is
    /// logged, so that a drive's bag is whole even if nothing closes it;
    /// [`Ros2Log::close`] writes them again with the summary.
    fn finish(&mut self) -> std::io::Result<()> {
        self.writer.flush().map_err(|e| std::io::Error::other(self.fail(&e)))?;
        self.write_metadata().map_err(std::io::Error::other)
    }
}
