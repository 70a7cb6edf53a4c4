//! `run.mcap`: a run's log in MCAP, the format Foxglove and the ROS 2 tools
//! read. Poses use Foxglove's well-known schemas (JSON-encoded), so the 3D
//! and Plot panels show them with no plug-in; the tree's actions, votes and
//! winners, the world and the report are JSON too, under `ubf.*` schemas.
//!
//! The log is written as the run goes and a chunk is closed every second of
//! controller time, so a killed process leaves a file readable up to its
//! last chunk. Chunk boundaries follow controller time, not the wall clock,
//! so the same scenario and seed give the same bytes.
//!
//! Topics:
//! - `/pose/true`, `/pose/odometry`, `/pose/egomotion`
//!   (`foxglove.PoseInFrame`, frame `world`): every tick;
//! - `/goal` (`foxglove.PoseInFrame`) and `/scene` (`foxglove.SceneUpdate`:
//!   walls as lines, landmarks as spheres), once at the start;
//! - `/world` (`ubf.World`) and `/run` (`ubf.Run`: scenario, seed, start
//!   pose and outline), once at the start, for `ubf replay`;
//! - `/tree` (`ubf.Tick`): every tick, the command, the winning behaviour
//!   and each node's vote and whether it won;
//! - `/ranges` (`foxglove.SceneUpdate`): every tick, a line from each range
//!   sensor to its echo;
//! - `/observations` (`foxglove.SceneUpdate`): at each new stereo frame,
//!   the landmarks it saw;
//! - `/camera/left`, `/camera/right` (`foxglove.CompressedImage`, PNG):
//!   each stereo frame's rectified pair, when the camera keeps its images
//!   and the log was asked for them ([`McapLog::log_images`]);
//! - `/collision` (`ubf.Collision`): where the robot touched something;
//! - `/report` (`ubf.Report`): the run's report, at the end.

use crate::sealed_file::SealedFile;
use mcap::records::MessageHeader;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use ubf_core::{Pose2, State, TickRecord, TickSink, TreeLayout};

/// Why the log could not be written.
#[derive(Debug, thiserror::Error)]
#[error("writing {}: {message}", path.display())]
pub struct LogError {
    path: PathBuf,
    message: String,
}

impl LogError {
    /// Writing `path` failed, for the reason `message`.
    pub fn new(path: &Path, message: impl Into<String>) -> LogError {
        LogError { path: path.to_owned(), message: message.into() }
    }
}

/// The world as `/world` carries it: what `ubf replay` needs to redraw the
/// plot.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct WorldMessage {
    /// Wall segments, `[[x0, y0], [x1, y1]]`, m.
    pub segments: Vec<[[f64; 2]; 2]>,
    /// Fixed landmarks, `[x, y, z]`, m.
    pub landmarks: Vec<[f64; 3]>,
    /// People at the start, `[x, y]`, m.
    pub people: Vec<[f64; 2]>,
    /// Featureless stretches of wall, `[[x0, y0], [x1, y1]]`, m.
    pub featureless: Vec<[[f64; 2]; 2]>,
}

impl WorldMessage {
    /// The simulator's world as `/world` carries it.
    pub fn of(world: &ubf_robots::sim::World) -> WorldMessage {
        let landmarks = world
            .landmarks
            .iter()
            .filter_map(|lm| match lm.anchor {
                ubf_robots::sim::Anchor::Fixed { position, .. } => Some(position),
                ubf_robots::sim::Anchor::Person { .. } => None,
            })
            .collect();
        let half = world.corridor.as_ref().map_or(0.0, |c| c.width / 2.0);
        WorldMessage {
            segments: world.segments.iter().map(|s| [[s.a.0, s.a.1], [s.b.0, s.b.1]]).collect(),
            landmarks,
            people: (0..world.people.len()).map(|i| world.person_position(i, 0.0)).map(|(x, y)| [x, y]).collect(),
            featureless: world
                .featureless
                .iter()
                .map(|f| {
                    let y = match f.side {
                        ubf_robots::sim::Side::Left => half,
                        ubf_robots::sim::Side::Right => -half,
                    };
                    [[f.from, y], [f.to, y]]
                })
                .collect(),
        }
    }
}

/// What `/run` carries.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct RunMessage {
    /// The scenario's name.
    pub scenario: String,
    /// The run's seed.
    pub seed: u64,
    /// The robot's pose at the start.
    pub start: [f64; 3],
    /// Its outline there, counter-clockwise, m.
    pub outline: [[f64; 2]; 4],
    /// The goal, if there is one: `[x, y, tolerance]`.
    pub goal: Option<[f64; 3]>,
}

/// What `/tree` carries each tick.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TickMessage {
    /// Controller time, s.
    pub time: f64,
    /// Commanded forward speed, m/s.
    pub velocity: f64,
    /// Commanded turn rate, rad/s; `null` where the command gave a heading.
    pub rot_velocity: Option<f64>,
    /// The winning behaviour's path in the tree, if one won.
    pub winner: Option<String>,
    /// Every node's path, effective vote and whether it won, in pre-order.
    pub nodes: Vec<NodeVote>,
}

/// One node's part in a tick.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct NodeVote {
    /// Its path in the tree.
    pub path: String,
    /// Its effective vote.
    pub vote: f64,
    /// Whether its action won at its parent.
    pub won: bool,
    /// Whether it is a composite.
    pub composite: bool,
}

/// What `/collision` carries: where the robot touched something.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CollisionMessage {
    /// The robot's true x then, m.
    pub x: f64,
    /// Its true y, m.
    pub y: f64,
}

/// The JSON Schema of `T`, as a JSON log's schema record holds it.
fn json_schema<T: JsonSchema>() -> Vec<u8> {
    serde_json::to_vec(&schemars::schema_for!(T)).expect("a schema always serialises")
}

/// The JSON Schema of `/report`: the report without the wall time, which
/// the log leaves out so that it is the same for the same seed.
fn report_schema() -> Vec<u8> {
    let mut schema = schemars::schema_for!(crate::report::RunReport);
    if let Some(properties) = schema.get_mut("properties").and_then(|p| p.as_object_mut()) {
        properties.remove("wall_time_s");
    }
    if let Some(required) = schema.get_mut("required").and_then(|r| r.as_array_mut()) {
        required.retain(|field| field != "wall_time_s");
    }
    serde_json::to_vec(&schema).expect("a schema always serialises")
}

/// A run log being written: a [`TickSink`] that the controller feeds.
pub struct McapLog {
    writer: mcap::Writer<SealedFile>,
    path: PathBuf,
    channels: BTreeMap<&'static str, u16>,
    sequence: u32,
    /// Controller time of the last closed chunk, s.
    flushed_at: f64,
    /// The stereo frame whose observations were logged last.
    frame: u64,
    /// The tree, to name the nodes of each tick.
    layout: TreeLayout,
    /// Collisions logged so far.
    collisions: u32,
    /// Whether stereo pairs are logged.
    images: bool,
    /// Message bytes written so far (before compression).
    logged_bytes: u64,
}

/// Seconds of controller time between closed chunks.
const CHUNK_EVERY_S: f64 = 1.0;

const POSE_SCHEMA: &str = r#"{"title":"foxglove.PoseInFrame","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"frame_id":{"type":"string"},"pose":{"type":"object","properties":{"position":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}},"orientation":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"},"w":{"type":"number"}}}}}}}"#;
const SCENE_SCHEMA: &str = r#"{"title":"foxglove.SceneUpdate","type":"object","properties":{"deletions":{"type":"array"},"entities":{"type":"array","items":{"type":"object","properties":{"timestamp":{"type":"object"},"frame_id":{"type":"string"},"id":{"type":"string"},"lifetime":{"type":"object"},"frame_locked":{"type":"boolean"},"metadata":{"type":"array"},"arrows":{"type":"array"},"cubes":{"type":"array"},"spheres":{"type":"array"},"cylinders":{"type":"array"},"lines":{"type":"array"},"triangles":{"type":"array"},"texts":{"type":"array"},"models":{"type":"array"}}}}}}"#;
const IMAGE_SCHEMA: &str = r#"{"title":"foxglove.CompressedImage","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"frame_id":{"type":"string"},"data":{"type":"string","contentEncoding":"base64"},"format":{"type":"string"}}}"#;

/// Nanoseconds of controller time, as MCAP and Foxglove count.
fn nanos(time: f64) -> u64 {
    (time.max(0.0) * 1e9).round() as u64
}

fn stamp(time: f64) -> serde_json::Value {
    let ns = nanos(time);
    json!({"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000})
}

fn pose_json(time: f64, pose: &Pose2) -> serde_json::Value {
    let half = pose.theta / 2.0;
    json!({
        "timestamp": stamp(time),
        "frame_id": "world",
        "pose": {
            "position": {"x": pose.x, "y": pose.y, "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": half.sin(), "w": half.cos()},
        },
    })
}

fn identity_orientation() -> serde_json::Value {
    json!({"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0})
}

fn point(x: f64, y: f64, z: f64) -> serde_json::Value {
    json!({"x": x, "y": y, "z": z})
}

/// A `foxglove.LinePrimitive` drawing a segment between each pair of
/// `points`, in the world frame.
fn line_list(points: Vec<serde_json::Value>, thickness: f64, [r, g, b, a]: [f64; 4]) -> serde_json::Value {
    json!({
        "type": 2, "pose": identity_pose(), "thickness": thickness, "scale_invariant": false,
        "points": points, "color": {"r": r, "g": g, "b": b, "a": a}, "colors": [], "indices": [],
    })
}

fn identity_pose() -> serde_json::Value {
    json!({"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": identity_orientation()})
}

/// A `foxglove.SceneUpdate` replacing the entity `id` with these lines and
/// spheres.
fn scene_entity(
    time: f64,
    id: &str,
    lines: Vec<serde_json::Value>,
    spheres: Vec<serde_json::Value>,
) -> serde_json::Value {
    json!({
        "deletions": [],
        "entities": [{
            "timestamp": stamp(time), "frame_id": "world", "id": id,
            "lifetime": {"sec": 0, "nsec": 0}, "frame_locked": false, "metadata": [],
            "arrows": [], "cubes": [], "spheres": spheres, "cylinders": [], "lines": lines,
            "triangles": [], "texts": [], "models": [],
        }],
    })
}

impl McapLog {
    /// Creates (or replaces) the log at `path`, declares its topics and
    /// writes what the run is: its world, goal and the scene Foxglove draws.
    pub fn create(path: &Path, run: &RunMessage, world: &WorldMessage) -> Result<McapLog, LogError> {
        let mut log = McapLog::open(path, ("ubf.Report", report_schema()))?;
        log.describe(run, world)?;
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
        let utc = now.format(&time::format_description::well_known::Rfc3339).map_err(|e| log.fail(&e))?;
        let metadata = mcap::records::Metadata {
            name: "ubf.wall_clock".into(),
            metadata: BTreeMap::from([
                ("utc_start".to_owned(), utc),
                ("unix_time_ns".to_owned(), now.unix_timestamp_nanos().to_string()),
            ]),
        };
        log.writer.write_metadata(&metadata).map_err(|e| log.fail(&e))?;
        log.describe(run, &WorldMessage::default())?;
        Ok(log)
    }

    /// Writes `report` on `/report` at `time` and flushes, so that it is
    /// in the file whatever happens next.
    pub fn write_report(&mut self, time: f64, report: &impl Serialize) -> Result<(), LogError> {
        self.write("/report", time, report)?;
        self.writer.flush().map_err(|e| self.fail(&e))
    }

    /// Message bytes logged so far, before compression: what a cap on the
    /// log's size counts.
    pub fn logged_bytes(&self) -> u64 {
        self.logged_bytes
    }

    /// Logs each stereo frame's pair of images (PNG, about 0.2 MB a pair
    /// of 640 × 480), where the camera keeps them; off by default.
    pub fn log_images(&mut self, images: bool) {
        self.images = images;
    }

    /// Opens the log with its channels, `/report`'s schema named and given
    /// by `report`.
    fn open(path: &Path, report: (&str, Vec<u8>)) -> Result<McapLog, LogError> {
        let fail = |e: &dyn std::fmt::Display| LogError { path: path.to_owned(), message: e.to_string() };
        let file = SealedFile::create(path).map_err(|e| fail(&e))?;
        let options = mcap::WriteOptions::new().profile("").library(concat!("ubf ", env!("CARGO_PKG_VERSION")));
        let mut writer = options.create(file).map_err(|e| fail(&e))?;
        let mut channels = BTreeMap::new();
        let no_metadata = BTreeMap::new();
        let pose =
            writer.add_schema("foxglove.PoseInFrame", "jsonschema", POSE_SCHEMA.as_bytes()).map_err(|e| fail(&e))?;
        let scene =
            writer.add_schema("foxglove.SceneUpdate", "jsonschema", SCENE_SCHEMA.as_bytes()).map_err(|e| fail(&e))?;
        let image = writer
            .add_schema("foxglove.CompressedImage", "jsonschema", IMAGE_SCHEMA.as_bytes())
            .map_err(|e| fail(&e))?;
        for (topic, schema) in [
            ("/camera/left", image),
            ("/camera/right", image),
            ("/pose/true", pose),
            ("/pose/odometry", pose),
            ("/pose/egomotion", pose),
            ("/goal", pose),
            ("/scene", scene),
            ("/ranges", scene),
            ("/observations", scene),
        ] {
            let id = writer.add_channel(schema, topic, "json", &no_metadata).map_err(|e| fail(&e))?;
            channels.insert(topic, id);
        }
        for (topic, name, schema) in [
            ("/world", "ubf.World", json_schema::<WorldMessage>()),
            ("/run", "ubf.Run", json_schema::<RunMessage>()),
            ("/tree", "ubf.Tick", json_schema::<TickMessage>()),
            ("/collision", "ubf.Collision", json_schema::<CollisionMessage>()),
            ("/report", report.0, report.1),
        ] {
            let schema = writer.add_schema(name, "jsonschema", &schema).map_err(|e| fail(&e))?;
            let id = writer.add_channel(schema, topic, "json", &no_metadata).map_err(|e| fail(&e))?;
            channels.insert(topic, id);
        }
        Ok(McapLog {
            writer,
            path: path.to_owned(),
            channels,
            sequence: 0,
            flushed_at: 0.0,
            frame: 0,
            layout: TreeLayout::default(),
            collisions: 0,
            images: false,
            logged_bytes: 0,
        })
    }

    fn fail(&self, e: &dyn std::fmt::Display) -> LogError {
        LogError { path: self.path.clone(), message: e.to_string() }
    }

    /// Writes one message on `topic` at controller time `time`.
    fn write(&mut self, topic: &'static str, time: f64, message: &impl Serialize) -> Result<(), LogError> {
        let data = serde_json::to_vec(message).expect("messages always serialise");
        self.logged_bytes += data.len() as u64;
        let channel_id = self.channels[topic];
        self.sequence += 1;
        let header =
            MessageHeader { channel_id, sequence: self.sequence, log_time: nanos(time), publish_time: nanos(time) };
        self.writer.write_to_known_channel(&header, &data).map_err(|e| self.fail(&e))
    }

    /// The run's start: what it is, its world, goal and the scene Foxglove
    /// draws.
    fn describe(&mut self, run: &RunMessage, world: &WorldMessage) -> Result<(), LogError> {
        self.write("/run", 0.0, run)?;
        self.write("/world", 0.0, world)?;
        if let Some([x, y, _]) = run.goal {
            self.write("/goal", 0.0, &pose_json(0.0, &Pose2::new(x, y, 0.0)))?;
        }
        let walls: Vec<serde_json::Value> =
            world.segments.iter().flat_map(|[a, b]| [point(a[0], a[1], 0.0), point(b[0], b[1], 0.0)]).collect();
        let spheres: Vec<serde_json::Value> = world
            .landmarks
            .iter()
            .map(|[x, y, z]| {
                json!({
                    "pose": {"position": point(*x, *y, *z), "orientation": identity_orientation()},
                    "size": point(0.15, 0.15, 0.15),
                    "color": {"r": 0.9, "g": 0.1, "b": 0.1, "a": 1.0},
                })
            })
            .collect();
        let lines = vec![line_list(walls, 0.05, [0.1, 0.1, 0.1, 1.0])];
        let scene = scene_entity(0.0, "world", lines, spheres);
        self.write("/scene", 0.0, &scene)
    }

    /// One tick: the poses (the truth where the robot has one, the
    /// egomotion estimate where it runs one), what the sensors saw, placed
    /// by the robot's own pose, the tree's part, and any new collision.
    fn tick(&mut self, record: &TickRecord) -> Result<(), LogError> {
        let (time, state) = (record.time(), &record.state);
        self.sensors(time, state)?;
        if let Some(truth) = &record.truth {
            self.write("/pose/true", time, &pose_json(time, &truth.pose))?;
        }
        self.write("/pose/odometry", time, &pose_json(time, &state.pose))?;
        if let Some(e) = &state.egomotion.pose {
            self.write("/pose/egomotion", time, &pose_json(time, e))?;
        }
        let layout = &self.layout;
        let tick = TickMessage {
            time,
            velocity: record.command.velocity(),
            rot_velocity: record.command.rot_velocity(),
            winner: layout.winning_path(record).map(str::to_owned),
            nodes: layout
                .nodes
                .iter()
                .zip(&record.nodes)
                .map(|(info, node)| NodeVote {
                    path: info.path.clone(),
                    vote: node.action.effective_vote(),
                    won: node.won,
                    composite: info.composite,
                })
                .collect(),
        };
        self.write("/tree", time, &tick)?;
        if let Some(truth) = record.truth.filter(|t| t.collisions > self.collisions) {
            self.collisions = truth.collisions;
            self.write("/collision", time, &CollisionMessage { x: truth.pose.x, y: truth.pose.y })?;
        }
        if time - self.flushed_at >= CHUNK_EVERY_S {
            self.writer.flush().map_err(|e| self.fail(&e))?;
            self.flushed_at = time;
        }
        Ok(())
    }

    /// The range sensors' echoes every tick, and a new stereo frame's
    /// landmarks, in the world by the robot's own pose.
    fn sensors(&mut self, time: f64, state: &State) -> Result<(), LogError> {
        let pose = &state.pose;
        let mut echoes = Vec::new();
        for reading in &state.ranges {
            let Some(range) = reading.range else { continue };
            let sensor = pose.compose(&reading.pose_robot_sensor);
            let hit = sensor.compose(&Pose2::new(range, 0.0, 0.0));
            echoes.extend([point(sensor.x, sensor.y, 0.3), point(hit.x, hit.y, 0.3)]);
        }
        let lines = vec![line_list(echoes, 0.02, [0.2, 0.6, 0.9, 0.8])];
        self.write("/ranges", time, &scene_entity(time, "ranges", lines, Vec::new()))?;
        let frame = &state.stereo;
        if frame.number != self.frame && frame.number != 0 {
            self.frame = frame.number;
            let mount = frame.calibration.map_or(ubf_core::CameraMount::ahead(0.0, 0.0, 0.0), |c| c.mount);
            let spheres: Vec<serde_json::Value> = frame
                .landmarks
                .iter()
                .map(|l| {
                    let [forward, left, z] = mount.cam_to_robot(l.point_cam);
                    let (wx, wy) = pose.transform_point(forward, left);
                    json!({
                        "pose": {"position": point(wx, wy, z), "orientation": identity_orientation()},
                        "size": {"x": 0.12, "y": 0.12, "z": 0.12},
                        "color": {"r": 0.1, "g": 0.4, "b": 1.0, "a": 0.9},
                    })
                })
                .collect();
            self.write("/observations", frame.time, &scene_entity(frame.time, "observations", Vec::new(), spheres))?;
            if let Some(images) = frame.images.as_deref().filter(|_| self.images) {
                self.stereo_pair(frame.time, images)?;
            }
        }
        Ok(())
    }

    /// A stereo pair as two `foxglove.CompressedImage` PNGs.
    fn stereo_pair(&mut self, time: f64, images: &ubf_core::StereoImages) -> Result<(), LogError> {
        use base64::Engine;
        use image::ImageEncoder;
        for (topic, frame_id, pixels) in
            [("/camera/left", "camera_left", &images.left), ("/camera/right", "camera_right", &images.right)]
        {
            let mut png = Vec::new();
            image::codecs::png::PngEncoder::new(&mut png)
                .write_image(pixels, images.width, images.height, image::ExtendedColorType::L8)
                .map_err(|e| self.fail(&e))?;
            let message = json!({
                "timestamp": stamp(time),
                "frame_id": frame_id,
                "data": base64::engine::general_purpose::STANDARD.encode(&png),
                "format": "png",
            });
            self.write(topic, time, &message)?;
        }
        Ok(())
    }

    /// Writes the report and closes the log (its summary and footer).
    pub fn close_with_report(mut self, time: f64, report: &impl Serialize) -> Result<(), LogError> {
        self.write("/report", time, report)?;
        self.close()
    }

    /// Closes the log without a report (a run that failed): what was
    /// written stays readable.
    pub fn close(mut self) -> Result<(), LogError> {
        self.writer.finish().map_err(|e| self.fail(&e))?;
        Ok(())
    }
}

impl TickSink for McapLog {
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.layout = layout.clone();
        Ok(())
    }

    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        self.tick(record).map_err(std::io::Error::other)
    }

    /// Closes the chunk under way, so that everything logged is readable;
    /// the summary is written when the log is closed (or dropped).
    fn finish(&mut self) -> std::io::Result<()> {
        self.writer.flush().map_err(|e| std::io::Error::other(self.fail(&e)))
    }
}
