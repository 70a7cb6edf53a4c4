//! The JSON topics of a run or a drive, one layer for the MCAP log
//! ([`crate::mcap_log`]) and the live view ([`crate::live`]): which topics
//! there are, their schemas, and the messages each tick makes. Poses use
//! Foxglove's well-known schemas (JSON-encoded), so the 3D and Plot panels
//! show them with no plug-in; the tree's actions, votes and winners, the
//! world and the report are JSON too, under `ubf.*` schemas.
//!
//! Topics:
//! - `/pose/true`, `/pose/odometry` (the pose steered by),
//!   `/pose/wheels` (the wheels' own odometry, before the wall compass or
//!   egomotion corrected it), `/pose/egomotion` (`foxglove.PoseInFrame`,
//!   frame `world`): every tick;
//! - `/goal` (`foxglove.PoseInFrame`) and `/scene` (`foxglove.SceneUpdate`:
//!   walls as lines, landmarks as spheres), at the start;
//! - `/world` (`ubf.World`) and `/run` (`ubf.Run`: scenario, seed, start
//!   pose and outline), at the start, for `ubf replay`;
//! - `/tree` (`ubf.Tick`): every tick, the command, the winning behaviour
//!   and each node's vote and whether it won;
//! - `/ranges` (`foxglove.SceneUpdate`): every tick, a line from each range
//!   sensor to its echo;
//! - `/observations` (`foxglove.SceneUpdate`): at each new stereo frame,
//!   the landmarks it saw;
//! - `/camera/left`, `/camera/right` (`foxglove.CompressedImage`, PNG):
//!   each stereo frame's rectified pair, when the camera keeps its images
//!   and they were asked for ([`JsonTopics::images`]);
//! - `/collision` (`ubf.Collision`): where the robot touched something;
//! - `/report` (`ubf.Report`, or `ubf.DriveReport` for a drive): the
//!   report, at the end.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::json;
use ubf_core::{Pose2, State, TickRecord, TreeLayout};

/// Where the topics go: an MCAP file, or the live view's channels.
pub trait JsonChannels {
    /// Why a message could not be taken.
    type Error;

    /// Declares `topic`, whose messages follow the JSON Schema `schema`,
    /// named `schema_name`.
    fn declare(&mut self, topic: &'static str, schema_name: &str, schema: &[u8]) -> Result<(), Self::Error>;

    /// Whether anyone takes `topic`'s messages now; a live view nobody
    /// watches is spared making them. A file takes everything.
    fn wanted(&self, _topic: &'static str) -> bool {
        true
    }

    /// Takes one message, JSON, on `topic` at controller time `time`, s.
    fn write(&mut self, topic: &'static str, time: f64, data: &[u8]) -> Result<(), Self::Error>;
}

/// The well-known schemas, in the order a log declares them.
pub const WELL_KNOWN_SCHEMAS: [(&str, &str); 3] = [
    ("foxglove.PoseInFrame", POSE_SCHEMA),
    ("foxglove.SceneUpdate", SCENE_SCHEMA),
    ("foxglove.CompressedImage", IMAGE_SCHEMA),
];

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
    /// Where the camera on a pan-tilt head points, rad from straight ahead
    /// (counter-clockwise positive); absent without a head.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_pan: Option<f64>,
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
pub fn json_schema<T: JsonSchema>() -> Vec<u8> {
    serde_json::to_vec(&schemars::schema_for!(T)).expect("a schema always serialises")
}

/// The JSON Schema of `/report`: the report without the wall time, which
/// the log leaves out so that it is the same for the same seed.
pub fn report_schema() -> Vec<u8> {
    let mut schema = schemars::schema_for!(crate::report::RunReport);
    if let Some(properties) = schema.get_mut("properties").and_then(|p| p.as_object_mut()) {
        properties.remove("wall_time_s");
    }
    if let Some(required) = schema.get_mut("required").and_then(|r| r.as_array_mut()) {
        required.retain(|field| field != "wall_time_s");
    }
    serde_json::to_vec(&schema).expect("a schema always serialises")
}

/// Indices into [`WELL_KNOWN_SCHEMAS`].
const POSE: usize = 0;
const SCENE: usize = 1;
const IMAGE: usize = 2;

const POSE_SCHEMA: &str = r#"{"title":"foxglove.PoseInFrame","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"frame_id":{"type":"string"},"pose":{"type":"object","properties":{"position":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}},"orientation":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"},"w":{"type":"number"}}}}}}}"#;
const SCENE_SCHEMA: &str = r#"{"title":"foxglove.SceneUpdate","type":"object","properties":{"deletions":{"type":"array"},"entities":{"type":"array","items":{"type":"object","properties":{"timestamp":{"type":"object"},"frame_id":{"type":"string"},"id":{"type":"string"},"lifetime":{"type":"object"},"frame_locked":{"type":"boolean"},"metadata":{"type":"array"},"arrows":{"type":"array"},"cubes":{"type":"array"},"spheres":{"type":"array"},"cylinders":{"type":"array"},"lines":{"type":"array"},"triangles":{"type":"array"},"texts":{"type":"array"},"models":{"type":"array"}}}}}}"#;
const IMAGE_SCHEMA: &str = r#"{"title":"foxglove.CompressedImage","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"frame_id":{"type":"string"},"data":{"type":"string","contentEncoding":"base64"},"format":{"type":"string"}}}"#;

/// Nanoseconds of controller time, as MCAP and Foxglove count.
pub fn nanos(time: f64) -> u64 {
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

/// The messages a run or drive makes, tick by tick: what it remembers
/// between ticks to make them (the tree, the last stereo frame, the
/// collisions so far).
#[derive(Debug, Default)]
pub struct JsonTopics {
    /// The tree, to name the nodes of each tick.
    layout: TreeLayout,
    /// The stereo frame whose observations were made last.
    frame: u64,
    /// Collisions so far.
    collisions: u32,
    /// Whether stereo pairs are made.
    images: bool,
}

impl JsonTopics {
    /// Declares every topic on `out`, `/report`'s schema named and given
    /// by `report`.
    pub fn declare<C: JsonChannels>(out: &mut C, report: (&str, Vec<u8>)) -> Result<(), C::Error> {
        for (topic, schema) in [
            ("/camera/left", IMAGE),
            ("/camera/right", IMAGE),
            ("/pose/true", POSE),
            ("/pose/odometry", POSE),
            ("/pose/wheels", POSE),
            ("/pose/egomotion", POSE),
            ("/goal", POSE),
            ("/scene", SCENE),
            ("/ranges", SCENE),
            ("/observations", SCENE),
        ] {
            let (name, data) = WELL_KNOWN_SCHEMAS[schema];
            out.declare(topic, name, data.as_bytes())?;
        }
        for (topic, name, schema) in [
            ("/world", "ubf.World", json_schema::<WorldMessage>()),
            ("/run", "ubf.Run", json_schema::<RunMessage>()),
            ("/tree", "ubf.Tick", json_schema::<TickMessage>()),
            ("/collision", "ubf.Collision", json_schema::<CollisionMessage>()),
            ("/report", report.0, report.1),
        ] {
            out.declare(topic, name, &schema)?;
        }
        Ok(())
    }

    /// Makes each stereo frame's pair of images (PNG, about 0.2 MB a pair
    /// of 640 × 480), where the camera keeps them; off by default.
    pub fn images(&mut self, images: bool) {
        self.images = images;
    }

    /// Names the nodes of the ticks to come by `layout`.
    pub fn start(&mut self, layout: &TreeLayout) {
        self.layout = layout.clone();
    }

    /// Takes what `record` says has happened as known, without making
    /// messages of it: ticks before it were not shown because nobody
    /// watched, and a collision that happened then is not news now.
    pub fn catch_up(&mut self, record: &TickRecord) {
        if let Some(truth) = &record.truth {
            self.collisions = truth.collisions;
        }
    }

    /// What the run is: its world, goal and the scene Foxglove draws, at
    /// `time` (0 in a log; a live view says it again for late viewers).
    pub fn describe<C: JsonChannels>(
        out: &mut C,
        time: f64,
        run: &RunMessage,
        world: &WorldMessage,
    ) -> Result<(), C::Error> {
        send(out, "/run", time, run)?;
        send(out, "/world", time, world)?;
        if let Some([x, y, _]) = run.goal {
            send(out, "/goal", time, &pose_json(time, &Pose2::new(x, y, 0.0)))?;
        }
        if !out.wanted("/scene") {
            return Ok(());
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
        send(out, "/scene", time, &scene_entity(time, "world", lines, spheres))
    }

    /// One tick: the poses (the truth where the robot has one, the
    /// egomotion estimate where it runs one), what the sensors saw, placed
    /// by the robot's own pose, the tree's part, and any new collision.
    pub fn tick<C: JsonChannels>(&mut self, out: &mut C, record: &TickRecord) -> Result<(), C::Error> {
        let (time, state) = (record.time(), &record.state);
        self.sensors(out, time, state)?;
        if let Some(truth) = &record.truth {
            send(out, "/pose/true", time, &pose_json(time, &truth.pose))?;
        }
        send(out, "/pose/odometry", time, &pose_json(time, &state.pose))?;
        send(out, "/pose/wheels", time, &pose_json(time, &state.odometry))?;
        if let Some(e) = &state.egomotion.pose {
            send(out, "/pose/egomotion", time, &pose_json(time, e))?;
        }
        if out.wanted("/tree") {
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
                camera_pan: record.state.camera_aim.map(|aim| aim.pan),
            };
            send(out, "/tree", time, &tick)?;
        }
        if let Some(truth) = record.truth.filter(|t| t.collisions > self.collisions) {
            self.collisions = truth.collisions;
            send(out, "/collision", time, &CollisionMessage { x: truth.pose.x, y: truth.pose.y })?;
        }
        Ok(())
    }

    /// The range sensors' echoes every tick, and a new stereo frame's
    /// landmarks, in the world by the robot's own pose.
    fn sensors<C: JsonChannels>(&mut self, out: &mut C, time: f64, state: &State) -> Result<(), C::Error> {
        let pose = &state.pose;
        if out.wanted("/ranges") {
            let mut echoes = Vec::new();
            for reading in &state.ranges {
                let Some(range) = reading.range else { continue };
                let sensor = pose.compose(&reading.pose_robot_sensor);
                let hit = sensor.compose(&Pose2::new(range, 0.0, 0.0));
                echoes.extend([point(sensor.x, sensor.y, 0.3), point(hit.x, hit.y, 0.3)]);
            }
            let lines = vec![line_list(echoes, 0.02, [0.2, 0.6, 0.9, 0.8])];
            send(out, "/ranges", time, &scene_entity(time, "ranges", lines, Vec::new()))?;
        }
        let frame = &state.stereo;
        if frame.number != self.frame && frame.number != 0 {
            self.frame = frame.number;
            if out.wanted("/observations") {
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
                let scene = scene_entity(frame.time, "observations", Vec::new(), spheres);
                send(out, "/observations", frame.time, &scene)?;
            }
            if let Some(images) = frame.images.as_deref().filter(|_| self.images) {
                stereo_pair(out, frame.time, images)?;
            }
        }
        Ok(())
    }
}

/// Sends `message` on `topic` at `time`, if anyone wants it.
pub fn send<C: JsonChannels>(
    out: &mut C,
    topic: &'static str,
    time: f64,
    message: &impl Serialize,
) -> Result<(), C::Error> {
    if !out.wanted(topic) {
        return Ok(());
    }
    let data = serde_json::to_vec(message).expect("messages always serialise");
    out.write(topic, time, &data)
}

/// A stereo pair as two `foxglove.CompressedImage` PNGs.
fn stereo_pair<C: JsonChannels>(out: &mut C, time: f64, images: &ubf_core::StereoImages) -> Result<(), C::Error> {
    use base64::Engine;
    use image::ImageEncoder;
    for (topic, frame_id, pixels) in
        [("/camera/left", "camera_left", &images.left), ("/camera/right", "camera_right", &images.right)]
    {
        if !out.wanted(topic) {
            continue;
        }
        let mut png = Vec::new();
        let encoded = image::codecs::png::PngEncoder::new(&mut png).write_image(
            pixels,
            images.width,
            images.height,
            image::ExtendedColorType::L8,
        );
        if let Err(e) = encoded {
            // A pair whose pixels do not fill its size: the log goes on
            // without it.
            tracing::warn!("{topic}: stereo pair at {time:.3} s not logged: {e}");
            continue;
        }
        let message = json!({
            "timestamp": stamp(time),
            "frame_id": frame_id,
            "data": base64::engine::general_purpose::STANDARD.encode(&png),
            "format": "png",
        });
        send(out, topic, time, &message)?;
    }
    Ok(())
}
