//! Any ROS 2 robot: one that takes `geometry_msgs/msg/Twist` on `/cmd_vel`
//! and publishes `nav_msgs/msg/Odometry` on `/odom` (and, if it has one,
//! `sensor_msgs/msg/LaserScan` on `/scan`), reached over DDS with no ROS
//! installation.
//!
//! - [`msg`]: the ROS 2 messages ubf reads and writes;
//! - [`node`]: a DDS participant with ROS 2's naming and QoS conventions;
//! - [`robot`]: [`Ros2Robot`], the [`ubf_core::Robot`] it drives;
//! - `cmd_vel`: the velocity commands, `Twist` or `TwistStamped`;
//! - `transforms`: the static transform tree, where the scanner sits.

mod cmd_vel;
pub mod msg;
pub mod node;
pub mod robot;
mod transforms;

pub use cmd_vel::Ros2EmergencyStop;
pub use node::{domain_from_env, Node, Publisher, Qos, Subscription};
pub use robot::{world_frame, Ros2Config, Ros2Robot, ScanMount};
