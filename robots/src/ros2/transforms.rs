//! The static transform tree a robot publishes on `/tf_static`, and where
//! its scanner sits by it: what `tf2_echo base_link laser` would say.

use super::msg::{Point, Pose, TFMessage, Transform};
use super::robot::ScanMount;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use std::collections::HashMap;

/// The most frames kept. Robots have tens; the bound keeps what a stranger
/// on the domain can make ubf hold, and walk every tick, small.
const MOST_FRAMES: usize = 1000;

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

impl StaticTransforms {
    /// Takes in a message's transforms: a later transform of a frame
    /// replaces the earlier, as in tf2. Why any was left out, if one was.
    pub fn insert(&mut self, message: TFMessage) -> Option<String> {
        let mut left_out = None;
        for stamped in message.transforms {
            let (parent, child) = (frame_name(&stamped.header.frame_id), frame_name(&stamped.child_frame_id));
            let why = if parent.is_empty() || child.is_empty() || parent == child {
                Some(format!("a frame {child:?} in a parent {parent:?}: a frame needs a name, and a parent of another"))
            } else if self.parents.len() >= MOST_FRAMES && !self.parents.contains_key(child) {
                Some(format!("frame {child:?}: more than {MOST_FRAMES} frames were published, and no more are kept"))
            } else {
                match isometry(&stamped.transform) {
                    Ok(pose) => {
                        self.parents.insert(child.to_owned(), (parent.to_owned(), pose));
                        None
                    }
                    Err(why) => Some(format!("frame {child:?} in {parent:?}: {why}")),
                }
            };
            left_out = left_out.or(why);
        }
        left_out
    }

    /// `frame`'s pose in the root of its tree, and that root's name.
    fn in_root<'a>(&'a self, frame: &'a str) -> Result<(&'a str, Isometry3<f64>), String> {
        let (mut name, mut pose) = (frame, Isometry3::identity());
        let mut path = vec![frame];
        while let Some((parent, in_parent)) = self.parents.get(name) {
            pose = in_parent * pose;
            name = parent;
            if path.contains(&name) {
                path.push(name);
                return Err(format!("its frames loop: {}", path.join(" → ")));
            }
            path.push(name);
        }
        Ok((name, pose))
    }

    /// `frame`'s pose in `base`, if the tree joins them.
    fn pose_in(&self, base: &str, frame: &str) -> Result<Isometry3<f64>, String> {
        if self.parents.is_empty() {
            return Err("nothing has come on it".into());
        }
        let (base_root, base_pose) = self.in_root(base)?;
        let (frame_root, frame_pose) = self.in_root(frame)?;
        if base_root != frame_root {
            let known = if self.parents.contains_key(frame) { "is joined to other frames" } else { "is not there" };
            return Err(format!("it does not join {frame:?} to {base:?}: {frame:?} {known}"));
        }
        Ok(base_pose.inverse() * frame_pose)
    }

    /// Where a scanner whose scans come in `frame` sits on a robot whose
    /// body is `base`. The frame the robot's body is itself is its centre.
    pub fn scan_mount(&self, base: &str, frame: &str) -> Result<ScanMount, String> {
        let (base, frame) = (frame_name(base), frame_name(frame));
        if frame.is_empty() || frame == base {
            return Ok(ScanMount::default());
        }
        let pose = self.pose_in(base, frame)?;
        let up = pose.rotation * Vector3::z();
        let tilt = up.z.abs().clamp(0.0, 1.0).acos().to_degrees();
        if tilt > MOST_TILT_DEG {
            return Err(format!(
                "it tilts {frame:?} {tilt:.0}° from level in {base:?}: its scan is not in the floor's plane, which \
                 ubf reads a scan in (at most {MOST_TILT_DEG}° from it)"
            ));
        }
        let (x, y) = (pose.translation.x, pose.translation.y);
        if x.hypot(y) > MOST_MOUNT_M {
            return Err(format!("it puts {frame:?} {:.1} m from {base:?}, further than a scanner sits", x.hypot(y)));
        }
        let ahead = pose.rotation * Vector3::x();
        Ok(ScanMount { x, y, heading_deg: ahead.y.atan2(ahead.x).to_degrees(), upside_down: up.z < 0.0 })
    }
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
        assert_mount(tree.scan_mount("base_link", "").unwrap(), 0.0, 0.0, 0.0, false);
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
        assert_eq!(why, "its frames loop: laser → b → a → b");
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
