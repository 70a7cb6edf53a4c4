//! A run read back from its JSON log: what `ubf replay` prints and the plot
//! is drawn from.

use crate::json_topics::{RunMessage, TickMessage, WorldMessage};
use crate::mcap_log::LogError;
use std::io::Read;
use std::path::Path;

/// The longest record (a chunk, compressed or not) [`read`] accepts: far
/// beyond what the log writes (chunks of under a megabyte).
const MOST_RECORD_BYTES: usize = 256 << 20;

/// A point where the winning behaviour changed.
#[derive(Clone, Debug, PartialEq)]
pub struct Decision {
    /// Where, m.
    pub at: (f64, f64),
    /// The behaviour that won from there (its node name).
    pub winner: String,
}

/// What the tree asked for, tick by tick.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Timeline {
    /// Seconds since the start.
    pub time: Vec<f64>,
    /// Commanded forward speed, m/s.
    pub speed: Vec<f64>,
    /// Commanded turn rate, °/s (NaN where the command gave a heading).
    pub turn_deg: Vec<f64>,
    /// Each behaviour's (leaf's) name and its vote per tick.
    pub votes: Vec<(String, Vec<f64>)>,
    /// Where the camera on a pan-tilt head pointed, ° from straight ahead
    /// (NaN where the log does not say); empty without a head.
    pub camera_pan_deg: Vec<f64>,
}

/// A run read back from its log.
#[derive(Clone, Debug, Default)]
pub struct ReplayedRun {
    /// What `/run` said, if the log got that far.
    pub run: Option<RunMessage>,
    /// The world.
    pub world: WorldMessage,
    /// The true path, the odometric one, and the egomotion one.
    pub true_path: Vec<(f64, f64)>,
    /// The robot's own (odometric) path.
    pub odometry_path: Vec<(f64, f64)>,
    /// Where the winning behaviour changed, and the new winner's name.
    pub decisions: Vec<Decision>,
    /// Where the robot touched something.
    pub collisions: Vec<(f64, f64)>,
    /// Speed, turn rate and votes over time.
    pub timeline: Timeline,
    /// The report, if the run finished.
    pub report: Option<serde_json::Value>,
    /// Why reading stopped early: a log cut short by a killed process.
    pub cut_short: Option<String>,
}

/// Reads the log at `path` back: everything up to its end, or, for a log
/// a killed process left, up to its last whole chunk.
pub fn read(path: &Path) -> Result<ReplayedRun, LogError> {
    // A FIFO or a device in the log's place is refused rather than read
    // without end.
    let file = ubf_core::config::open_regular(path).map_err(|e| LogError::reading(path, e.to_string()))?;
    read_from(std::io::BufReader::new(file), path)
}

/// Reads a log back from `source` as [`read`] does, its errors naming
/// it `name`. A read that fails (the disk, the network) is an error; a log
/// that ends early is read up to its last whole chunk.
pub fn read_from(mut source: impl Read, name: &Path) -> Result<ReplayedRun, LogError> {
    let fail = |message: String| LogError::reading(name, message);
    // A record's length comes from the file: one corrupted length must be
    // an error, not an attempt to allocate exabytes.
    let options = mcap::sans_io::LinearReaderOptions::default()
        .with_skip_end_magic(true)
        .with_record_length_limit(MOST_RECORD_BYTES);
    let mut reader = mcap::sans_io::MessageReader::new_with_options(options);
    let stream = std::iter::from_fn(|| loop {
        match reader.next_event()? {
            // Read as the parser asks, not whole: a log may be gigabytes.
            Ok(mcap::sans_io::MessageReadEvent::ReadRequest(need)) => {
                let into = reader.insert(need);
                // A read a signal interrupted is tried again: the parser
                // takes 0 bytes read as the log's end.
                let read = loop {
                    match source.read(into) {
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        read => break read,
                    }
                };
                match read {
                    Ok(n) => reader.notify_read(n),
                    Err(e) => return Some(Err(mcap::McapError::from(e))),
                }
            }
            Ok(mcap::sans_io::MessageReadEvent::Message(message)) => return Some(Ok(message)),
            Err(e) => return Some(Err(e)),
        }
    });
    let mut out = ReplayedRun::default();
    let mut leaves: Vec<usize> = Vec::new();
    let mut last_winner: Option<String> = None;
    for message in stream {
        let message = match message {
            Ok(m) => m,
            // The disk failed: not a log cut short, which is what the
            // parser's own errors are here.
            Err(mcap::McapError::Io(e)) => return Err(fail(e.to_string())),
            Err(e) => {
                out.cut_short = Some(e.to_string());
                break;
            }
        };
        let topic = message.channel.topic.as_str();
        let parse = |what: &str| -> Result<serde_json::Value, LogError> {
            serde_json::from_slice(&message.data).map_err(|e| fail(format!("{topic} ({what}): {e}")))
        };
        let position = |v: &serde_json::Value| {
            let p = &v["pose"]["position"];
            (p["x"].as_f64().unwrap_or(f64::NAN), p["y"].as_f64().unwrap_or(f64::NAN))
        };
        match topic {
            "/run" => out.run = Some(serde_json::from_slice(&message.data).map_err(|e| fail(format!("/run: {e}")))?),
            "/world" => out.world = serde_json::from_slice(&message.data).map_err(|e| fail(format!("/world: {e}")))?,
            "/pose/true" => out.true_path.push(position(&parse("pose")?)),
            "/pose/odometry" => out.odometry_path.push(position(&parse("pose")?)),
            "/report" => out.report = Some(parse("report")?),
            "/collision" => {
                let at = parse("collision")?;
                out.collisions.push((at["x"].as_f64().unwrap_or(f64::NAN), at["y"].as_f64().unwrap_or(f64::NAN)));
            }
            "/tree" => {
                let tick: TickMessage =
                    serde_json::from_slice(&message.data).map_err(|e| fail(format!("/tree: {e}")))?;
                if out.timeline.votes.is_empty() {
                    leaves = (0..tick.nodes.len()).filter(|&i| i > 0 && !tick.nodes[i].composite).collect();
                    out.timeline.votes = leaves.iter().map(|&i| (tick.nodes[i].path.clone(), Vec::new())).collect();
                }
                out.timeline.time.push(tick.time);
                out.timeline.speed.push(tick.velocity);
                out.timeline.turn_deg.push(tick.rot_velocity.map_or(f64::NAN, f64::to_degrees));
                if let Some(pan) = tick.camera_pan {
                    // Filled in from the first tick that says, so that the
                    // series stays aligned with `time`.
                    out.timeline.camera_pan_deg.resize(out.timeline.time.len() - 1, f64::NAN);
                    out.timeline.camera_pan_deg.push(pan.to_degrees());
                }
                for ((_, votes), &i) in out.timeline.votes.iter_mut().zip(&leaves) {
                    votes.push(tick.nodes.get(i).map_or(f64::NAN, |n| n.vote));
                }
                if tick.winner != last_winner && last_winner.is_some() {
                    if let (Some(winner), Some(&at)) = (&tick.winner, out.true_path.last()) {
                        let name = winner.rsplit('/').next().unwrap_or(winner).to_owned();
                        out.decisions.push(Decision { at, winner: name });
                    }
                }
                last_winner = tick.winner;
            }
            _ => {}
        }
    }
    Ok(out)
}
