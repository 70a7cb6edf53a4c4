//! The static transform tree a robot publishes on `/tf_static`, and where
//! its scanner sits by it: what `tf2_echo base_link laser` would say.

use super::config::{Ros2Config, ScanMount};
use super::msg::{Point, Pose, TFMessage, Transform};
use super::node::{Node, Qos, Subscription};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use std::collections::HashMap;
use std::time::{Duration, Instant};
use ubf_core::RobotError;

/// The most frames kept. Robots have tens; the bound keeps what a stranger
/// on the domain can make ubf hold, and walk every tick, small.
const MOST_FRAMES: usize = 1000;

/// The longest frame name kept, bytes. Real ones are tens; the bound keeps
/// what walking the tree and saying a name cost small.
const MOST_NAME_BYTES: usize = 256;

/// How far from level a scanner may tilt and its scan still be read as
/// lying in the floor's plane, degrees. A scanner tilted further (down, to
/// see the floor) sees obstacles at other distances than
/// its ranges say in the plane.
const MOST_TILT_DEG: f64 = 10.0;

/// How far from the robot's centre a scanner may sit, m: as far as a
/// mount written in the robot file may say.
const MOST_MOUNT_M: f64 = 10.0;

/// Frames and their poses in their parents, as `/tf_static` gave them.
#[derive(Debug, Default)]
pub struct StaticTransforms {
    /// Each frame's parent and its pose there, by the frame's name.
    parents: HashMap<String, (String, Isometry3<f64>)>,
}

/// A frame's name as tf2 keys it: without a leading `/` (ROS 1's habit).
fn frame_name(name: &str) -> &str {
    name.strip_prefix('/').unwrap_or(name)
}

/// A frame's name as said: quoted, control characters escaped, cut short.
pub(super) fn said(name: &str) -> String {
    format!("\"{}\"", crate::printable::text_cut(name.as_bytes(), 60))
}

impl StaticTransforms {
    /// Takes in a message's transforms: a later transform of a frame
    /// replaces the earlier, as in tf2. Why any was left out, if one was.
    pub fn insert(&mut self, message: TFMessage) -> Option<String> {
        let mut left_out = None;
        for stamped in message.transforms {
            let (parent, child) = (frame_name(&stamped.header.frame_id), frame_name(&stamped.child_frame_id));
            let why = if parent.is_empty() || child.is_empty() || parent == child {
                Err("a frame needs a name, and a parent of another".to_owned())
            } else if parent.len() > MOST_NAME_BYTES || child.len() > MOST_NAME_BYTES {
                Err(format!("a name longer than {MOST_NAME_BYTES} bytes"))
            } else if self.parents.len() >= MOST_FRAMES && !self.parents.contains_key(child) {
                Err(format!("more than {MOST_FRAMES} frames were published, and no more are kept"))
            } else {
                isometry(&stamped.transform).map(|pose| {
                    self.parents.insert(child.to_owned(), (parent.to_owned(), pose));
                })
            };
            // The first left out is said; its names are escaped (which
            // costs, for long ones) only then.
            if let (Err(why), None) = (why, &left_out) {
                left_out = Some(format!("frame {} in {}: {why}", said(child), said(parent)));
            }
        }
        left_out
    }

    /// `frame`'s pose in the root of its tree, and that root's name.
    fn in_root<'a>(&'a self, frame: &'a str) -> Result<(&'a str, Isometry3<f64>), String> {
        let (mut name, mut pose) = (frame, Isometry3::identity());
        // A walk longer than there are frames has come round again.
        for _ in 0..=self.parents.len() {
            let Some((parent, in_parent)) = self.parents.get(name) else { return Ok((name, pose)) };
            pose = in_parent * pose;
            name = parent;
        }
        Err(format!("its frames loop above {}, through {}", said(frame), said(name)))
    }

    /// Whether `frame` is in the tree, as a child or as a parent.
    fn has(&self, frame: &str) -> bool {
        self.parents.contains_key(frame) || self.parents.values().any(|(parent, _)| parent == frame)
    }

    /// `frame`'s pose in `base`, if the tree joins them.
    fn pose_in(&self, base: &str, frame: &str) -> Result<Isometry3<f64>, String> {
        if self.parents.is_empty() {
            return Err("nothing has come on it".into());
        }
        let (base_root, base_pose) = self.in_root(base)?;
        let (frame_root, frame_pose) = self.in_root(frame)?;
        if base_root != frame_root {
            let (base_said, frame_said) = (said(base), said(frame));
            let why = match (self.has(base), self.has(frame)) {
                (false, _) => format!("{base_said}, the robot's body, is not there (is `base_frame` its name?)"),
                (true, false) if self.parents.len() >= MOST_FRAMES => {
                    format!("{frame_said} is not there, and {MOST_FRAMES} frames came before it, no more kept")
                }
                (true, false) => format!("{frame_said} is not there"),
                (true, true) => format!("{frame_said} is joined to other frames"),
            };
            return Err(format!("it does not join {frame_said} to {base_said}: {why}"));
        }
        Ok(base_pose.inverse() * frame_pose)
    }

    /// Where a scanner whose scans come in `frame` sits on a robot whose
    /// body is `base`. The frame the robot's body is itself is its centre;
    /// no frame is nowhere, as tf2 has it.
    pub fn scan_mount(&self, base: &str, frame: &str) -> Result<ScanMount, String> {
        let (base, frame) = (frame_name(base), frame_name(frame));
        if frame.is_empty() {
            return Err("the scan names no frame (its header.frame_id is empty) to look up".into());
        }
        if frame == base {
            return Ok(ScanMount::default());
        }
        let pose = self.pose_in(base, frame)?;
        let up = pose.rotation * Vector3::z();
        let tilt = up.z.abs().clamp(0.0, 1.0).acos().to_degrees();
        if tilt > MOST_TILT_DEG {
            return Err(format!(
                "it tilts {} {tilt:.0}° from level in {}: its scan is not in the floor's plane, which \
                 ubf reads a scan in (at most {MOST_TILT_DEG}° from it)",
                said(frame),
                said(base)
            ));
        }
        let (x, y) = (pose.translation.x, pose.translation.y);
        if x.hypot(y) > MOST_MOUNT_M {
            let far = x.hypot(y);
            return Err(format!("it puts {} {far:.1} m from {}, further than a scanner sits", said(frame), said(base)));
        }
        let ahead = pose.rotation * Vector3::x();
        Ok(ScanMount { x, y, heading_deg: ahead.y.atan2(ahead.x).to_degrees(), upside_down: up.z < 0.0 })
    }
}

/// Where a scanner sits by the robot's static transforms, as they come:
/// each scan's frame looked up in the robot's body frame.
pub(super) struct PublishedMounts {
    transforms: Subscription<TFMessage>,
    tree: StaticTransforms,
    base_frame: String,
    /// Whether a transform left out has been said: once is enough.
    left_out_said: bool,
    /// The frame last looked up and what was found, until more
    /// transforms come: the tree is walked once for them, not every tick.
    found: Option<(String, Result<ScanMount, String>)>,
    /// The mount last said and its frame, to say when it moves.
    said: Option<(String, ScanMount)>,
    /// When a move was last said: at most one line every
    /// [`MOVES_SAID_EVERY`], whatever a broadcaster does.
    move_said_at: Option<Instant>,
}

/// How often a scanner's moves are said at most.
const MOVES_SAID_EVERY: Duration = Duration::from_secs(10);

/// Whether `to` is elsewhere than `from`, by more than a republished
/// mount's rounding: a centimetre, a degree, or the other way up.
fn moved(from: &ScanMount, to: &ScanMount) -> bool {
    let turned = ubf_core::angle_difference(from.heading_deg.to_radians(), to.heading_deg.to_radians());
    (from.x - to.x).hypot(from.y - to.y) > 0.01
        || turned.abs() > 1f64.to_radians()
        || from.upside_down != to.upside_down
}

impl PublishedMounts {
    /// The topic the transforms come on.
    pub(super) fn topic(&self) -> &str {
        self.transforms.topic()
    }

    /// Reads the robot's static transforms (tf2's static QoS: reliable,
    /// transient local, so that those published long before come too).
    pub(super) fn new(config: &Ros2Config, node: &Node) -> Result<PublishedMounts, RobotError> {
        Ok(PublishedMounts {
            transforms: node.reader::<TFMessage>(&config.tf_static, Qos::Latched)?,
            tree: StaticTransforms::default(),
            base_frame: config.base_frame.clone(),
            left_out_said: false,
            found: None,
            said: None,
            move_said_at: None,
        })
    }

    /// Takes in the static transforms published since the last call.
    pub(super) fn update(&mut self) -> Result<(), RobotError> {
        let (tree, mut came, mut left_out) = (&mut self.tree, false, None);
        self.transforms.take_each(|message| {
            came = true;
            left_out = tree.insert(message).or(left_out.take());
        })?;
        if came {
            self.found = None;
        }
        if let Some(why) = left_out.filter(|_| !self.left_out_said) {
            tracing::warn!(
                "a transform on {} was left out: {why} (others left out go unsaid)",
                self.transforms.topic()
            );
            self.left_out_said = true;
        }
        Ok(())
    }

    /// Where the scanner of a scan in `frame` sits, or why that is not
    /// known. Said on the log when first found, and when it moves.
    pub(super) fn of(&mut self, frame: &str) -> Result<ScanMount, String> {
        if let Some((_, found)) = self.found.as_ref().filter(|(last, _)| last == frame) {
            return found.clone();
        }
        let found = self.tree.scan_mount(&self.base_frame, frame).map_err(|why| {
            format!(
                "its scanner's mount was looked up on {}, and {why}: write `scan_mount` in the robot file's \
                 `ros2: (...)` to say where it sits",
                self.transforms.topic()
            )
        });
        // A move held back is looked up again until it has been said.
        let said = found.as_ref().map_or(true, |mount| self.say_where(frame, *mount));
        self.found = said.then(|| (frame.to_owned(), found.clone()));
        found
    }

    /// Says where the scanner (of `frame`) is found to sit: the first
    /// time, and when it has moved (at most every [`MOVES_SAID_EVERY`]).
    /// Whether all there is to say has been said: not a move held back.
    fn say_where(&mut self, frame: &str, mount: ScanMount) -> bool {
        let (topic, frame_said, now_at, now) = (self.transforms.topic(), said(frame), placed(&mount), Instant::now());
        match self.said.as_ref() {
            Some((said_frame, was)) if said_frame == frame => {
                if !moved(was, &mount) {
                    return true;
                }
                if self.move_said_at.is_some_and(|at| now - at < MOVES_SAID_EVERY) {
                    return false;
                }
                tracing::warn!(
                    "the scanner ({frame_said}) moved on {topic} during the drive, from {} to {now_at}: its scans \
                     are read from there now",
                    placed(was)
                );
                self.move_said_at = Some(now);
            }
            _ => tracing::info!("the scanner ({frame_said}) sits at {now_at}, as {topic} places it"),
        }
        self.said = Some((frame.to_owned(), mount));
        true
    }
}

/// A mount as said: `(0.20, 0.00) m facing 180°, upside down`.
pub(super) fn placed(mount: &ScanMount) -> String {
    let turned = if mount.upside_down { ", upside down" } else { "" };
    // Rounded first: -0.3° would read "-0°"; adding 0 makes -0 plain 0.
    let (x, y) = ((mount.x * 100.0).round() / 100.0 + 0.0, (mount.y * 100.0).round() / 100.0 + 0.0);
    let heading = mount.heading_deg.round() + 0.0;
    format!("({x:.2}, {y:.2}) m facing {heading:.0}°{turned}")
}

/// A transform as an isometry, unless it is none (the checks odometry's
/// poses pass).
fn isometry(transform: &Transform) -> Result<Isometry3<f64>, String> {
    let Transform { translation: t, rotation: q } = *transform;
    let pose = Pose { position: Point { x: t.x, y: t.y, z: t.z }, orientation: q };
    if let Some(why) = pose.why_unusable() {
        return Err(why);
    }
    let rotation = UnitQuaternion::from_quaternion(Quaternion::new(q.w, q.x, q.y, q.z));
    Ok(Isometry3::from_parts(Translation3::new(t.x, t.y, t.z), rotation))
}

#[cfg(test)]
mod tests {
    use super::super::msg::{Header, TransformStamped, Vector3 as RosVector3};
    use super::*;

    /// A transform of `child` in `parent`: translation `xyz`, then the
    /// rotation roll-pitch-yaw `rpy_deg`.
    fn transform(parent: &str, child: &str, xyz: [f64; 3], rpy_deg: [f64; 3]) -> TransformStamped {
        let [roll, pitch, yaw] = rpy_deg.map(f64::to_radians);
        let q = UnitQuaternion::from_euler_angles(roll, pitch, yaw);
        TransformStamped {
            header: Header::new(0.0, parent),
            child_frame_id: child.into(),
            transform: Transform {
                translation: RosVector3 { x: xyz[0], y: xyz[1], z: xyz[2] },
                rotation: super::super::msg::Quaternion { x: q.i, y: q.j, z: q.k, w: q.w },
            },
        }
    }

    fn tree_of(transforms: Vec<TransformStamped>) -> StaticTransforms {
        let mut tree = StaticTransforms::default();
        assert_eq!(tree.insert(TFMessage { transforms }), None);
        tree
    }

    fn assert_mount(mount: ScanMount, x: f64, y: f64, heading_deg: f64, upside_down: bool) {
        assert!((mount.x - x).abs() < 1e-9 && (mount.y - y).abs() < 1e-9, "{mount:?}");
        assert!(ubf_core::angle_difference(mount.heading_deg.to_radians(), heading_deg.to_radians()).abs() < 1e-9);
        assert_eq!(mount.upside_down, upside_down, "{mount:?}");
    }

    #[test]
    fn a_scanner_down_a_chain_of_frames_sits_where_the_chain_puts_it() {
        // A plate 0.2 m ahead and 0.3 m up, turned a quarter left, the
        // scanner 0.1 m ahead on it, facing backwards.
        let tree = tree_of(vec![
            transform("base_link", "plate", [0.2, 0.0, 0.3], [0.0, 0.0, 90.0]),
            transform("/plate", "laser", [0.1, 0.0, 0.05], [0.0, 0.0, 180.0]),
        ]);
        assert_mount(tree.scan_mount("base_link", "laser").unwrap(), 0.2, 0.1, 270.0, false);
        assert_mount(tree.scan_mount("base_link", "/laser").unwrap(), 0.2, 0.1, 270.0, false);
        assert_mount(tree.scan_mount("base_link", "base_link").unwrap(), 0.0, 0.0, 0.0, false);
        // No frame is nowhere, as in tf2: not the centre.
        assert!(tree.scan_mount("base_link", "").unwrap_err().contains("names no frame"));
    }

    #[test]
    fn a_scanner_beside_the_base_under_a_common_root_is_found_through_it() {
        // base_footprint holds both: the base 0.1 m up, the scanner 0.3 m
        // behind and 0.2 m up.
        let tree = tree_of(vec![
            transform("base_footprint", "base_link", [0.0, 0.0, 0.1], [0.0, 0.0, 0.0]),
            transform("base_footprint", "laser", [-0.3, 0.05, 0.2], [0.0, 0.0, 30.0]),
        ]);
        assert_mount(tree.scan_mount("base_link", "laser").unwrap(), -0.3, 0.05, 30.0, false);
        assert_mount(tree.scan_mount("base_footprint", "laser").unwrap(), -0.3, 0.05, 30.0, false);
    }

    #[test]
    fn each_beam_points_where_the_mount_turns_it_upright_or_upside_down() {
        // Yawed, rolled half a turn (under a plate) and both, slightly
        // tilted: each beam, turned by the whole rotation and laid on the
        // floor, points where the planar mount says.
        for rpy_deg in [[0.0, 0.0, 0.0], [0.0, 3.0, 70.0], [180.0, 0.0, 0.0], [180.0, -2.0, -120.0], [176.0, 0.0, 45.0]]
        {
            let tree = tree_of(vec![transform("base_link", "laser", [0.1, -0.2, 0.3], rpy_deg)]);
            let mount = tree.scan_mount("base_link", "laser").unwrap();
            assert_eq!(mount.upside_down, rpy_deg[0] > 90.0, "{rpy_deg:?}");
            let [roll, pitch, yaw] = rpy_deg.map(f64::to_radians);
            let rotation = UnitQuaternion::from_euler_angles(roll, pitch, yaw);
            for beam_deg in [-135.0f64, -90.0, -10.0, 0.0, 45.0, 90.0, 170.0] {
                let beam = beam_deg.to_radians();
                let direction = rotation * Vector3::new(beam.cos(), beam.sin(), 0.0);
                let on_floor = direction.y.atan2(direction.x);
                let error = ubf_core::angle_difference(mount.beam(beam).theta, on_floor);
                assert!(error.abs() < 0.003, "{rpy_deg:?}, beam {beam_deg}°: {error} rad off");
            }
        }
    }

    #[test]
    fn a_frame_the_tree_does_not_join_to_the_base_is_said() {
        let tree = tree_of(vec![transform("base_link", "camera", [0.1, 0.0, 0.2], [0.0, 0.0, 0.0])]);
        let why = tree.scan_mount("base_link", "laser").unwrap_err();
        assert_eq!(why, "it does not join \"laser\" to \"base_link\": \"laser\" is not there");
        let tree = tree_of_two_robots();
        let why = tree.scan_mount("base_link", "laser").unwrap_err();
        assert_eq!(why, "it does not join \"laser\" to \"base_link\": \"laser\" is joined to other frames");
        let why = tree.scan_mount("base_footprint", "laser").unwrap_err();
        assert!(
            why.ends_with("\"base_footprint\", the robot's body, is not there (is `base_frame` its name?)"),
            "{why}"
        );
    }

    fn tree_of_two_robots() -> StaticTransforms {
        tree_of(vec![
            transform("base_link", "camera", [0.1, 0.0, 0.2], [0.0, 0.0, 0.0]),
            transform("other/base_link", "laser", [0.1, 0.0, 0.2], [0.0, 0.0, 0.0]),
        ])
    }

    #[test]
    fn a_scanner_tilted_from_level_is_refused() {
        let tree = tree_of(vec![transform("base_link", "laser", [0.1, 0.0, 0.2], [0.0, 20.0, 0.0])]);
        let why = tree.scan_mount("base_link", "laser").unwrap_err();
        assert!(why.starts_with("it tilts \"laser\" 20° from level"), "{why}");
        let tree = tree_of(vec![transform("base_link", "laser", [0.1, 0.0, 0.2], [0.0, 5.0, 0.0])]);
        assert!(tree.scan_mount("base_link", "laser").is_ok());
    }

    #[test]
    fn frames_that_loop_are_said_and_end() {
        let tree = tree_of(vec![
            transform("a", "b", [0.1, 0.0, 0.0], [0.0, 0.0, 0.0]),
            transform("b", "a", [0.1, 0.0, 0.0], [0.0, 0.0, 0.0]),
            transform("b", "laser", [0.1, 0.0, 0.0], [0.0, 0.0, 0.0]),
        ]);
        let why = tree.scan_mount("base_link", "laser").unwrap_err();
        assert!(why.starts_with("its frames loop above \"laser\", through "), "{why}");
    }

    #[test]
    fn transforms_that_are_none_are_left_out_and_said() {
        let mut tree = StaticTransforms::default();
        let mut no_rotation = transform("base_link", "laser", [0.1, 0.0, 0.2], [0.0, 0.0, 0.0]);
        no_rotation.transform.rotation = super::super::msg::Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 0.0 };
        let mut not_finite = transform("base_link", "sonar", [0.1, 0.0, 0.2], [0.0, 0.0, 0.0]);
        not_finite.transform.translation.x = f64::NAN;
        let itself = transform("laser", "laser", [0.1, 0.0, 0.2], [0.0, 0.0, 0.0]);
        for (stamped, said) in
            [(no_rotation, "is no rotation"), (not_finite, "is not finite"), (itself, "a parent of another")]
        {
            let why = tree.insert(TFMessage { transforms: vec![stamped] }).expect("left out");
            assert!(why.contains(said), "{why}");
        }
        assert!(tree.scan_mount("base_link", "laser").is_err());
        let far = transform("base_link", "laser", [30.0, 0.0, 0.2], [0.0, 0.0, 0.0]);
        assert_eq!(tree.insert(TFMessage { transforms: vec![far] }), None);
        assert!(tree.scan_mount("base_link", "laser").unwrap_err().contains("30.0 m from"));
    }

    #[test]
    fn a_long_name_is_left_out_and_a_name_is_said_escaped_and_cut() {
        let mut tree = StaticTransforms::default();
        let long = "l".repeat(MOST_NAME_BYTES + 1);
        let why = tree.insert(TFMessage { transforms: vec![transform("base_link", &long, [0.1; 3], [0.0; 3])] });
        let why = why.expect("left out");
        assert!(why.contains("longer than 256 bytes") && why.len() < 200, "{why}");
        assert_eq!(said("a\u{1b}[2Jb"), "\"a\\u{1b}[2Jb\"");
    }

    #[test]
    fn a_long_chain_is_walked_in_as_many_steps_as_there_are_frames() {
        let frames: Vec<String> = (0..MOST_FRAMES).map(|k| format!("f{k}")).collect();
        let chain = (1..MOST_FRAMES).map(|k| transform(&frames[k - 1], &frames[k], [0.001, 0.0, 0.0], [0.0; 3]));
        let mut tree = tree_of(chain.collect());
        assert!((tree.scan_mount("f0", &frames[MOST_FRAMES - 1]).unwrap().x - 0.999).abs() < 1e-9);
        // Closed into a ring, the walk ends.
        tree.parents.insert("f0".into(), (frames[MOST_FRAMES - 1].clone(), Isometry3::identity()));
        assert!(tree.scan_mount("base_link", "f5").unwrap_err().starts_with("its frames loop"));
    }

    #[test]
    fn a_mount_moves_by_more_than_a_republished_mount_s_rounding() {
        let at = ScanMount { x: 0.2, y: 0.0, heading_deg: 179.9, upside_down: false };
        assert!(!moved(&at, &ScanMount { x: 0.2 + 1e-9, heading_deg: -179.8, ..at }));
        assert!(moved(&at, &ScanMount { x: 0.22, ..at }));
        assert!(moved(&at, &ScanMount { heading_deg: 177.0, ..at }));
        assert!(moved(&at, &ScanMount { upside_down: true, ..at }));
    }

    #[test]
    fn a_mount_is_said_without_a_minus_zero() {
        let ahead = ScanMount { x: 0.2, y: -0.0001, heading_deg: -0.3, upside_down: false };
        assert_eq!(placed(&ahead), "(0.20, 0.00) m facing 0°");
        let under = ScanMount { heading_deg: -90.2, upside_down: true, ..ahead };
        assert_eq!(placed(&under), "(0.20, 0.00) m facing -90°, upside down");
    }

    #[test]
    fn no_more_frames_are_kept_than_the_bound_but_known_ones_still_change() {
        let mut tree = StaticTransforms::default();
        let many = (0..MOST_FRAMES + 5).map(|k| transform("base_link", &format!("f{k}"), [0.1, 0.0, 0.0], [0.0; 3]));
        let why = tree.insert(TFMessage { transforms: many.collect() }).expect("left out");
        assert!(why.contains("more than 1000 frames"), "{why}");
        assert_eq!(tree.parents.len(), MOST_FRAMES);
        let moved = transform("base_link", "f0", [0.5, 0.0, 0.0], [0.0; 3]);
        assert_eq!(tree.insert(TFMessage { transforms: vec![moved] }), None);
        assert_mount(tree.scan_mount("base_link", "f0").unwrap(), 0.5, 0.0, 0.0, false);
    }
}
