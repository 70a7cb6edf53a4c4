//! The `ros2: (...)` settings of a robot file: topics, QoS, frames, and
//! where the scanner sits.

use super::node::Qos;
use serde::Deserialize;
use ubf_core::Pose2;

/// The `ros2: (...)` settings of a robot file. The defaults are ROS 2's
/// conventions: topics `cmd_vel`, `odom`, `scan` in the root namespace,
/// reliable keep-last-10 for commands and odometry, sensor data QoS for
/// the scan, the domain in `ROS_DOMAIN_ID`, the scanner where the robot's
/// static transforms put it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Ros2Config {
    /// The robot's namespace (`/robot1`), for several robots on one
    /// network; relative topic names go under it.
    pub namespace: String,
    /// The DDS domain (unset: `ROS_DOMAIN_ID`, or 0).
    pub domain_id: Option<u16>,
    /// Where velocity commands go.
    pub cmd_vel: String,
    /// Whether they go as `geometry_msgs/msg/TwistStamped` (unset: as the
    /// robot reads them, by discovery: stamped if they are read as that
    /// and not as `Twist`, else `Twist`).
    pub cmd_vel_stamped: Option<bool>,
    /// Where odometry comes from.
    pub odom: String,
    /// Where laser scans come from, if the robot publishes them.
    pub scan: String,
    /// The odometry reader's QoS (`SensorData` hears best-effort drivers).
    pub odom_qos: Qos,
    /// The scan reader's QoS.
    pub scan_qos: Qos,
    /// How long to wait for the first odometry message, s.
    pub connect_timeout_s: f64,
    /// Where the scanner sits on the robot. Unset: where `tf_static` puts
    /// the frame each scan names, in `base_frame`.
    pub scan_mount: Option<ScanMount>,
    /// The robot's body frame, which its scanner's mount is looked up in.
    pub base_frame: String,
    /// Where the robot publishes its static transforms (its scanner's
    /// mount among them): relative, under the namespace, as multi-robot
    /// setups remap it; `/tf_static` for one that does not.
    pub tf_static: String,
}

/// Where a scanner sits on the robot, as `ros2 run tf2_ros tf2_echo
/// base_link <the scan's frame>` gives it: `scan_mount: (x: 0.2, y: 0.0,
/// heading_deg: 0.0)`, and `upside_down: true` for one mounted under a
/// plate (rolled half a turn, so that its angles run clockwise).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScanMount {
    /// Metres ahead of the robot's centre (`base_link`).
    #[serde(default, deserialize_with = "mount_m")]
    pub x: f64,
    /// Metres to its left.
    #[serde(default, deserialize_with = "mount_m")]
    pub y: f64,
    /// Where the scan's angle 0 points, degrees counter-clockwise from
    /// the robot's heading.
    #[serde(default, deserialize_with = "ubf_core::config::angle_deg")]
    pub heading_deg: f64,
    /// Whether the scanner is upside down.
    #[serde(default)]
    pub upside_down: bool,
}

fn mount_m<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    ubf_core::config::number_in(d, -10.0..=10.0, "from -10 to 10 m")
}

impl ScanMount {
    /// The pose, in the robot's frame, of the beam at `angle` in the
    /// scan's.
    pub(super) fn beam(&self, angle: f64) -> Pose2 {
        let angle = if self.upside_down { -angle } else { angle };
        Pose2::new(self.x, self.y, self.heading_deg.to_radians() + angle)
    }
}

impl Ros2Config {
    /// How long each wait of connecting may take: for the first odometry,
    /// the reader of the commands, the scanner's mount.
    pub fn connect_timeout(&self) -> std::time::Duration {
        std::time::Duration::from_secs_f64(self.connect_timeout_s.clamp(0.1, 600.0))
    }
}

impl Default for Ros2Config {
    fn default() -> Self {
        Ros2Config {
            namespace: String::new(),
            domain_id: None,
            cmd_vel: "cmd_vel".into(),
            cmd_vel_stamped: None,
            odom: "odom".into(),
            scan: "scan".into(),
            odom_qos: Qos::Reliable,
            scan_qos: Qos::SensorData,
            connect_timeout_s: 5.0,
            scan_mount: None,
            base_frame: "base_link".into(),
            tf_static: "tf_static".into(),
        }
    }
}
