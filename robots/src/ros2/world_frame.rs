//! The drive's world frame beside a ROS 2 robot: where the robot stood
//! when the drive began, which its goal is in. Odometry's poses are taken
//! into it, and where it sits in odometry's own frame is published for tf,
//! so that RViz and Foxglove draw ubf's goal and poses where the robot's
//! own transforms put the robot, whatever odometry read when the drive
//! began.

use super::msg::{Odometry, TFMessage};
use ubf_core::Pose2;

/// The world frame's name: `ubf_world`, prefixed by the namespace
/// (`robot1/ubf_world`) as the frames of several robots are.
pub fn world_frame(namespace: &str) -> String {
    match namespace.trim_matches('/') {
        "" => "ubf_world".into(),
        namespace => format!("{namespace}/ubf_world"),
    }
}

/// The world pose of odometry's `pose`, where odometry read `first` at
/// world pose `origin`: origin ∘ first⁻¹ ∘ pose.
pub(super) fn world_pose(pose: &Pose2, first: &Pose2, origin: &Pose2) -> Pose2 {
    origin.compose(&pose.relative_to(first))
}

/// Where the world frame sits in odometry's frame, as a static transform,
/// where odometry read `first` at world pose `origin`: first ∘ origin⁻¹,
/// [`world_pose`] inverted.
pub(super) fn in_odom(first: &Odometry, origin: Pose2, namespace: &str) -> TFMessage {
    // tf2 refuses a frame named with a leading `/` (ROS 1's habit).
    let odom = match first.header.frame_id.trim_start_matches('/') {
        "" => "odom",
        frame => frame,
    };
    let world = first.pose.pose.to_pose2().compose(&Pose2::default().relative_to(&origin));
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64());
    TFMessage::planar(now, odom, &world_frame(namespace), &world)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros2::msg::Pose;

    fn near(a: &Pose2, b: &Pose2) -> bool {
        (a.x - b.x).abs() < 1e-9
            && (a.y - b.y).abs() < 1e-9
            && ubf_core::angle_difference(a.theta, b.theta).abs() < 1e-9
    }

    #[test]
    fn the_world_frame_sits_in_odometry_s_frame_where_the_drive_began() {
        // Odometry read (3, 1) facing +y where the drive's world pose is
        // (1, 2) turned 0.5 rad (a drive resumed from its pose file).
        let mut first = Odometry::default();
        first.header.frame_id = "/robot1/odom".into();
        first.pose.pose = Pose::planar(&Pose2::new(3.0, 1.0, std::f64::consts::FRAC_PI_2));
        let origin = Pose2::new(1.0, 2.0, 0.5);
        let message = in_odom(&first, origin, "/robot1/");
        let transform = &message.transforms[0];
        let frames = (transform.header.frame_id.as_str(), transform.child_frame_id.as_str());
        assert_eq!(frames, ("robot1/odom", "robot1/ubf_world"));
        let t = &transform.transform;
        let world_in_odom = Pose2::new(t.translation.x, t.translation.y, t.rotation.yaw());
        // The robot's first pose is the origin in the world, and odometry's
        // first pose in odom.
        assert!(near(&world_in_odom.compose(&origin), &first.pose.pose.to_pose2()));
        // Any odometry taken into the world and placed back by the
        // transform is where odometry put it.
        for odometry in [Pose2::new(5.0, 2.0, 0.3), Pose2::new(-4.0, 7.5, -2.9), Pose2::new(3.0, 1.0, 1.0)] {
            let world = world_pose(&odometry, &first.pose.pose.to_pose2(), &origin);
            assert!(near(&world_in_odom.compose(&world), &odometry), "{odometry:?}");
        }
        assert_eq!(world_frame(""), "ubf_world");
    }
}
