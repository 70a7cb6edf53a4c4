//! Any ROS 2 robot: one that takes `geometry_msgs/msg/Twist` (or
//! `TwistStamped`) on `/cmd_vel`
//! and publishes `nav_msgs/msg/Odometry` on `/odom` (and, if it has one,
//! `sensor_msgs/msg/LaserScan` on `/scan`), reached over DDS with no ROS
//! installation.
//!
//! - [`msg`]: the ROS 2 messages ubf reads and writes;
//! - [`node`]: a DDS participant with ROS 2's naming and QoS conventions;
//! - [`config`]: the robot file's `ros2: (...)` settings;
//! - [`robot`]: [`Ros2Robot`], the [`ubf_core::Robot`] it drives;
//! - `cmd_vel`: the velocity commands, `Twist` or `TwistStamped`;
//! - `transforms`: the static transform tree, where the scanner sits;
//! - [`world_frame`](mod@world_frame): the drive's frame beside the robot's odometry.

mod cmd_vel;
pub mod config;
pub mod msg;
pub mod node;
pub mod robot;
mod transforms;
pub mod world_frame;

pub use cmd_vel::Ros2EmergencyStop;
pub use config::{Ros2Config, ScanMount};
pub use node::{domain_from_env, Node, Publisher, Qos, Subscription};
pub use robot::Ros2Robot;
pub use world_frame::world_frame;
