//! The ROS 2 messages ubf speaks, as serde structs whose field order is the
//! `.msg` definition's, so that CDR (de)serialises them as ROS 2 does.
//! Each names its ROS 2 type through [`RosMessage`].

use serde::{Deserialize, Serialize};
use serde_big_array::BigArray;
use ubf_core::Pose2;

/// A ROS 2 message type.
pub trait RosMessage: Serialize + for<'de> Deserialize<'de> + Send + 'static {
    /// The ROS 2 name, `pkg/msg/Type`.
    const NAME: &'static str;

    /// The `ros2msg` schema rosbag2 stores for it: the `.msg` text with
    /// every nested type's appended (`schemas/`).
    const SCHEMA: &'static str;

    /// The DDS type name, `pkg::msg::dds_::Type_`.
    fn dds_name() -> String {
        let (package, name) = Self::NAME.split_once("/msg/").expect("a ROS 2 name is pkg/msg/Type");
        format!("{package}::msg::dds_::{name}_")
    }
}

/// A DDS type name as ROS 2 names the type: `nav_msgs/msg/Odometry` for
/// `nav_msgs::msg::dds_::Odometry_`; a name of another form as it is.
pub fn ros_name(dds_name: &str) -> String {
    let ros = dds_name.strip_suffix('_').and_then(|name| {
        let (package, name) = name.split_once("::msg::dds_::")?;
        Some(format!("{package}/msg/{name}"))
    });
    ros.unwrap_or_else(|| dds_name.to_owned())
}

/// `message` as a ROS 2 serialized message: the CDR encapsulation header
/// (little-endian CDR) and the message, as DDS sends it and rosbag2 stores
/// it.
pub fn to_cdr<M: Serialize>(message: &M) -> Vec<u8> {
    let mut bytes = vec![0x00, 0x01, 0x00, 0x00];
    rustdds::serialization::to_writer_with_rep_id(&mut bytes, message, rustdds::RepresentationIdentifier::CDR_LE)
        .expect("a message of plain fields always serialises");
    bytes
}

macro_rules! ros_message {
    ($type:ty, $name:literal, $schema:literal) => {
        impl RosMessage for $type {
            const NAME: &'static str = $name;
            const SCHEMA: &'static str = include_str!(concat!("schemas/", $schema));
        }
    };
}

/// `builtin_interfaces/msg/Time`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds past `sec`.
    pub nanosec: u32,
}

impl Time {
    /// `seconds` (≥ 0) as a ROS time.
    pub fn from_seconds(seconds: f64) -> Time {
        let seconds = seconds.max(0.0);
        let sec = seconds.floor();
        Time { sec: sec.min(i32::MAX as f64) as i32, nanosec: (((seconds - sec) * 1e9) as u32).min(999_999_999) }
    }

    /// The time in seconds.
    pub fn seconds(&self) -> f64 {
        f64::from(self.sec) + f64::from(self.nanosec) * 1e-9
    }
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// When the data was taken.
    pub stamp: Time,
    /// The frame the data is in.
    pub frame_id: String,
}

impl Header {
    /// A header stamped `seconds` in `frame`.
    pub fn new(seconds: f64, frame: &str) -> Header {
        Header { stamp: Time::from_seconds(seconds), frame_id: frame.to_owned() }
    }
}

/// `geometry_msgs/msg/Vector3`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Twist`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    /// m/s.
    pub linear: Vector3,
    /// rad/s.
    pub angular: Vector3,
}
ros_message!(Twist, "geometry_msgs/msg/Twist", "geometry_msgs__Twist.msg");

impl Twist {
    /// Forward at `velocity` m/s while turning at `turn_rate` rad/s.
    pub fn planar(velocity: f64, turn_rate: f64) -> Twist {
        Twist {
            linear: Vector3 { x: velocity, ..Vector3::default() },
            angular: Vector3 { z: turn_rate, ..Vector3::default() },
        }
    }
}

/// `geometry_msgs/msg/TwistStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TwistStamped {
    /// Stamp and frame.
    pub header: Header,
    /// The twist.
    pub twist: Twist,
}
ros_message!(TwistStamped, "geometry_msgs/msg/TwistStamped", "geometry_msgs__TwistStamped.msg");

/// `geometry_msgs/msg/Point`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// x, m.
    pub x: f64,
    /// y, m.
    pub y: f64,
    /// z, m.
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Quaternion::from_yaw(0.0)
    }
}

impl Quaternion {
    /// A rotation of `yaw` rad about z.
    pub fn from_yaw(yaw: f64) -> Quaternion {
        Quaternion { x: 0.0, y: 0.0, z: (yaw / 2.0).sin(), w: (yaw / 2.0).cos() }
    }

    /// The rotation's yaw, rad (its roll and pitch ignored).
    pub fn yaw(&self) -> f64 {
        (2.0 * (self.w * self.z + self.x * self.y)).atan2(1.0 - 2.0 * (self.y * self.y + self.z * self.z))
    }
}

/// `geometry_msgs/msg/Pose`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

impl Pose {
    /// Why the pose is no pose, if it is not: a position not finite or
    /// further out than any odometry counts, or an orientation that is no
    /// rotation (its norm far from 1: all zeros from a driver that never
    /// fills it, or numbers not normalised, whose yaw means nothing).
    pub fn why_unusable(&self) -> Option<String> {
        let shown = ubf_core::config::shown;
        let Point { x, y, z } = self.position;
        if ![x, y, z].iter().all(|v| v.is_finite()) {
            return Some(format!("its position ({}, {}, {}) is not finite", shown(x), shown(y), shown(z)));
        }
        if ![x, y, z].iter().all(|v| v.abs() <= MOST_POSITION_M) {
            return Some(format!(
                "its position ({}, {}, {}) has a coordinate beyond ±{} km, further than any robot drives",
                shown(x),
                shown(y),
                shown(z),
                MOST_POSITION_M / 1e3
            ));
        }
        let Quaternion { x, y, z, w } = self.orientation;
        let norm = (x * x + y * y + z * z + w * w).sqrt();
        if !((1.0 - ROTATION_NORM_SLACK)..=(1.0 + ROTATION_NORM_SLACK)).contains(&norm) {
            return Some(format!(
                "its orientation ({}, {}, {}, {}) is no rotation (its norm is {}, not 1)",
                shown(x),
                shown(y),
                shown(z),
                shown(w),
                shown(norm)
            ));
        }
        None
    }
}

/// How far from its origin odometry may put the robot, m. Beyond it the
/// numbers are garbage (the robot's motion is then lost in their
/// rounding, and a pose printed runs to hundreds of digits).
const MOST_POSITION_M: f64 = 1e9;

/// How far from 1 a quaternion's norm may be and it still be taken as a
/// rotation: drivers' arithmetic in single precision is well within it.
const ROTATION_NORM_SLACK: f64 = 0.1;

impl Pose {
    /// A planar pose.
    pub fn planar(pose: &Pose2) -> Pose {
        Pose { position: Point { x: pose.x, y: pose.y, z: 0.0 }, orientation: Quaternion::from_yaw(pose.theta) }
    }

    /// The pose in the plane.
    pub fn to_pose2(&self) -> Pose2 {
        Pose2::new(self.position.x, self.position.y, self.orientation.yaw())
    }
}

/// `geometry_msgs/msg/PoseWithCovariance`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// Row-major 6 × 6 covariance of x, y, z and the rotations about them.
    #[serde(with = "BigArray")]
    pub covariance: [f64; 36],
}

/// `geometry_msgs/msg/TwistWithCovariance`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TwistWithCovariance {
    /// The twist.
    pub twist: Twist,
    /// Row-major 6 × 6 covariance.
    #[serde(with = "BigArray")]
    pub covariance: [f64; 36],
}

impl Default for PoseWithCovariance {
    fn default() -> Self {
        PoseWithCovariance { pose: Pose::default(), covariance: [0.0; 36] }
    }
}

impl Default for TwistWithCovariance {
    fn default() -> Self {
        TwistWithCovariance { twist: Twist::default(), covariance: [0.0; 36] }
    }
}

/// `nav_msgs/msg/Odometry`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Odometry {
    /// Stamp and the pose's frame (`odom`).
    pub header: Header,
    /// The twist's frame (`base_link`).
    pub child_frame_id: String,
    /// The pose in `header.frame_id`.
    pub pose: PoseWithCovariance,
    /// The velocity in `child_frame_id`.
    pub twist: TwistWithCovariance,
}
ros_message!(Odometry, "nav_msgs/msg/Odometry", "nav_msgs__Odometry.msg");

/// `sensor_msgs/msg/LaserScan`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LaserScan {
    /// Stamp and the scanner's frame.
    pub header: Header,
    /// First beam's angle, rad.
    pub angle_min: f32,
    /// Last beam's angle, rad.
    pub angle_max: f32,
    /// Angle between beams, rad.
    pub angle_increment: f32,
    /// Time between beams, s.
    pub time_increment: f32,
    /// Time between scans, s.
    pub scan_time: f32,
    /// Shortest valid range, m.
    pub range_min: f32,
    /// Longest valid range, m.
    pub range_max: f32,
    /// One range a beam, m (outside the valid span: no echo).
    pub ranges: Vec<f32>,
    /// One intensity a beam, or none.
    pub intensities: Vec<f32>,
}
ros_message!(LaserScan, "sensor_msgs/msg/LaserScan", "sensor_msgs__LaserScan.msg");

impl LaserScan {
    /// Why the scan says nothing about where obstacles are, if it does not:
    /// beams whose directions cannot be told, a valid span that is empty,
    /// no beams, or every beam invalid (NaN, by REP 117). Taken as open
    /// space, such a scan would let the robot drive into what it misses.
    pub fn why_unusable(&self) -> Option<String> {
        let shown = |v: f32| ubf_core::config::shown(f64::from(v));
        let geometry = [self.angle_min, self.angle_increment, self.range_min, self.range_max];
        if !geometry.iter().all(|v| v.is_finite()) {
            return Some(format!(
                "angle_min {}, angle_increment {}, range_min {}, range_max {}: not all finite",
                shown(self.angle_min),
                shown(self.angle_increment),
                shown(self.range_min),
                shown(self.range_max)
            ));
        }
        if self.range_min > self.range_max {
            return Some(format!("range_min {} is beyond range_max {}", shown(self.range_min), shown(self.range_max)));
        }
        if self.ranges.is_empty() {
            return Some("it has no beams".into());
        }
        if self.ranges.iter().all(|r| r.is_nan()) {
            return Some(format!("all of its {} beams are NaN (invalid)", self.ranges.len()));
        }
        None
    }
}

/// `geometry_msgs/msg/PoseStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseStamped {
    /// Stamp and frame.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}
ros_message!(PoseStamped, "geometry_msgs/msg/PoseStamped", "geometry_msgs__PoseStamped.msg");

/// `geometry_msgs/msg/Transform`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// Translation, m.
    pub translation: Vector3,
    /// Rotation.
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    /// Stamp and parent frame.
    pub header: Header,
    /// Child frame.
    pub child_frame_id: String,
    /// Child in parent.
    pub transform: Transform,
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TFMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}
ros_message!(TFMessage, "tf2_msgs/msg/TFMessage", "tf2_msgs__TFMessage.msg");

impl TFMessage {
    /// The planar transform of `child` in `parent` at `seconds`.
    pub fn planar(seconds: f64, parent: &str, child: &str, pose: &Pose2) -> TFMessage {
        TFMessage {
            transforms: vec![TransformStamped {
                header: Header::new(seconds, parent),
                child_frame_id: child.to_owned(),
                transform: Transform {
                    translation: Vector3 { x: pose.x, y: pose.y, z: 0.0 },
                    rotation: Quaternion::from_yaw(pose.theta),
                },
            }],
        }
    }
}

/// `sensor_msgs/msg/Image`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Image {
    /// Stamp and the camera's optical frame.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Pixel encoding (`mono8`).
    pub encoding: String,
    /// Whether the data is big-endian.
    pub is_bigendian: u8,
    /// Bytes a row.
    pub step: u32,
    /// The pixels, row after row.
    pub data: Vec<u8>,
}
ros_message!(Image, "sensor_msgs/msg/Image", "sensor_msgs__Image.msg");

/// `std_msgs/msg/String`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StringMessage {
    /// The text.
    pub data: String,
}
ros_message!(StringMessage, "std_msgs/msg/String", "std_msgs__String.msg");

/// `ubf_msgs/msg/NodeVote`: one node of the tree in a tick.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NodeVote {
    /// The node's path in the tree.
    pub path: String,
    /// Its action's vote.
    pub vote: f64,
    /// Its weight in its composite.
    pub weight: f64,
    /// Whether its composite took its action.
    pub won: bool,
}

/// `ubf_msgs/msg/Tick`: what the tree decided in one tick.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Tick {
    /// The controller's time.
    pub stamp: Time,
    /// The tick's number.
    pub tick: u64,
    /// The winning leaf's path, empty if none voted.
    pub winner: String,
    /// Commanded forward velocity, m/s (0 for stop).
    pub linear: f64,
    /// Commanded turn rate, rad/s (0 for stop or a heading command).
    pub angular: f64,
    /// Whether the command was STOP.
    pub stop: bool,
    /// Every node of the tree, in pre-order.
    pub nodes: Vec<NodeVote>,
}
ros_message!(Tick, "ubf_msgs/msg/Tick", "ubf_msgs__Tick.msg");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ros_names_come_back_from_dds_names() {
        assert_eq!(ros_name(&Odometry::dds_name()), Odometry::NAME);
        assert_eq!(ros_name("SomeVendorType"), "SomeVendorType");
    }

    #[test]
    fn dds_names_follow_the_ros2_convention() {
        assert_eq!(Twist::dds_name(), "geometry_msgs::msg::dds_::Twist_");
        assert_eq!(Odometry::dds_name(), "nav_msgs::msg::dds_::Odometry_");
    }

    #[test]
    fn cdr_has_the_encapsulation_header_and_aligned_doubles() {
        let bytes = to_cdr(&Twist::planar(0.5, -1.0));
        assert_eq!(bytes.len(), 4 + 48);
        assert_eq!(&bytes[..4], &[0, 1, 0, 0]);
        assert_eq!(&bytes[4..12], &0.5f64.to_le_bytes());
        assert_eq!(&bytes[44..52], &(-1.0f64).to_le_bytes());
    }

    #[test]
    fn schemas_start_with_the_types_own_fields() {
        assert!(Twist::SCHEMA.contains("MSG: geometry_msgs/Vector3"));
        assert!(Tick::SCHEMA.contains("MSG: ubf_msgs/NodeVote"));
        assert!(Odometry::SCHEMA.contains(&format!("{}\nMSG: std_msgs/Header", "=".repeat(80))));
    }

    #[test]
    fn yaw_survives_a_quaternion() {
        for yaw in [-3.0, -1.0, 0.0, 0.5, 3.1] {
            assert!((Quaternion::from_yaw(yaw).yaw() - yaw).abs() < 1e-12);
        }
    }

    #[test]
    fn a_pose_that_is_no_pose_is_named() {
        let good = Pose { position: Point { x: 1.0, y: 2.0, z: 0.0 }, orientation: Quaternion::from_yaw(0.7) };
        assert_eq!(good.why_unusable(), None);
        let far = Pose { position: Point { x: f64::NAN, ..good.position }, ..good };
        assert_eq!(far.why_unusable().unwrap(), "its position (NaN, 2, 0) is not finite");
        let huge = Pose { position: Point { y: -1e300, ..good.position }, ..good };
        assert_eq!(
            huge.why_unusable().unwrap(),
            "its position (1, -1e300, 0) has a coordinate beyond ±1000000 km, further than any robot drives"
        );
        let far_but_counted = Pose { position: Point { x: 9e8, ..good.position }, ..good };
        assert_eq!(far_but_counted.why_unusable(), None);
        let unfilled = Pose { orientation: Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 0.0 }, ..good };
        assert!(unfilled.why_unusable().unwrap().contains("is no rotation (its norm is 0, not 1)"));
        let unnormalised = Pose { orientation: Quaternion { x: 3.0, y: -7.0, z: 0.0, w: 1.0 }, ..good };
        assert!(unnormalised.why_unusable().is_some());
    }

    #[test]
    fn a_scan_that_says_nothing_of_obstacles_is_named() {
        let good = LaserScan {
            angle_min: -1.0,
            angle_increment: 0.1,
            range_min: 0.1,
            range_max: 10.0,
            ranges: vec![1.0, f32::NAN, f32::INFINITY],
            ..LaserScan::default()
        };
        assert_eq!(good.why_unusable(), None);
        let nan_angles = LaserScan { angle_increment: f32::NAN, ..good.clone() };
        assert!(nan_angles.why_unusable().unwrap().contains("not all finite"));
        let inverted = LaserScan { range_min: 20.0, ..good.clone() };
        assert_eq!(inverted.why_unusable().unwrap(), "range_min 20 is beyond range_max 10");
        let empty = LaserScan { ranges: vec![], ..good.clone() };
        assert_eq!(empty.why_unusable().unwrap(), "it has no beams");
        let blind = LaserScan { ranges: vec![f32::NAN; 3], ..good };
        assert_eq!(blind.why_unusable().unwrap(), "all of its 3 beams are NaN (invalid)");
    }

    #[test]
    fn time_splits_into_seconds_and_nanoseconds() {
        let t = Time::from_seconds(12.25);
        assert_eq!((t.sec, t.nanosec), (12, 250_000_000));
        assert_eq!(Time::from_seconds(-1.0), Time::default());
    }
}
