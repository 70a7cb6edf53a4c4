//! A tick as the ROS 2 messages ubf publishes and logs: one view shared by
//! the live publisher and the rosbag2 log, so that what RViz shows live and
//! what `ros2 bag play` replays are the same messages.
//!
//! Frames follow REP 105: ubf's world frame is `odom`, the robot is
//! `base_link`, and `odom` → `base_link` is the wheels' own odometry, which
//! moves continuously. The pose the tree steers by, which the wall compass
//! and egomotion correct in steps, is a topic of its own. Beside a ROS 2
//! robot, whose driver publishes its own `odom`, ubf's world is a frame of
//! its own ([`ubf_robots::ros2::world_frame()`]), which the robot places.

use ubf_core::{Pose2, StereoImages, TickRecord, TreeLayout};
use ubf_robots::ros2::msg::{
    Header, Image, LaserScan, NodeVote, Odometry, Pose, PoseStamped, PoseWithCovariance, RosMessage, TFMessage, Tick,
    Time, Twist, TwistWithCovariance,
};

/// ubf's world frame where ubf publishes the robot's odometry itself: REP
/// 105's `odom`.
pub const ODOM_FRAME: &str = "odom";

/// Where each message goes. Relative names go under a namespace; `/tf` is
/// absolute, as tf2 expects.
pub mod topics {
    /// The wheels' pose in `odom` as a transform.
    pub const TF: &str = "/tf";
    /// The wheels' odometry.
    pub const ODOM: &str = "odom";
    /// The range sensors, as one planar scan.
    pub const SCAN: &str = "scan";
    /// The stereo camera's left image.
    pub const LEFT_IMAGE: &str = "camera/left/image_raw";
    /// The stereo camera's right image.
    pub const RIGHT_IMAGE: &str = "camera/right/image_raw";
    /// What the tree decided.
    pub const TICK: &str = "ubf/tick";
    /// The goal.
    pub const GOAL: &str = "ubf/goal";
    /// Where a simulated robot really is.
    pub const TRUE_POSE: &str = "ubf/pose/true";
    /// Where egomotion puts the robot.
    pub const EGOMOTION_POSE: &str = "ubf/pose/egomotion";
    /// The pose the tree steers by: odometry as the wall compass and
    /// egomotion corrected it.
    pub const STEERED_POSE: &str = "ubf/pose/steered";
}

/// A message of the view, by type.
#[derive(Clone, Debug, PartialEq)]
pub enum Message {
    /// `tf2_msgs/msg/TFMessage`.
    Tf(TFMessage),
    /// `nav_msgs/msg/Odometry` (boxed: its covariances make it ten times
    /// the others' size).
    Odometry(Box<Odometry>),
    /// `sensor_msgs/msg/LaserScan`.
    Scan(LaserScan),
    /// `sensor_msgs/msg/Image`.
    Image(Image),
    /// `geometry_msgs/msg/PoseStamped`.
    Pose(PoseStamped),
    /// `ubf_msgs/msg/Tick`.
    Tick(Tick),
}

impl Message {
    /// The message's ROS 2 type name.
    pub fn type_name(&self) -> &'static str {
        match self {
            Message::Tf(_) => TFMessage::NAME,
            Message::Odometry(_) => Odometry::NAME,
            Message::Scan(_) => LaserScan::NAME,
            Message::Image(_) => Image::NAME,
            Message::Pose(_) => PoseStamped::NAME,
            Message::Tick(_) => Tick::NAME,
        }
    }

    /// The message's `ros2msg` schema.
    pub fn schema(&self) -> &'static str {
        match self {
            Message::Tf(_) => TFMessage::SCHEMA,
            Message::Odometry(_) => Odometry::SCHEMA,
            Message::Scan(_) => LaserScan::SCHEMA,
            Message::Image(_) => Image::SCHEMA,
            Message::Pose(_) => PoseStamped::SCHEMA,
            Message::Tick(_) => Tick::SCHEMA,
        }
    }

    /// The message as CDR, as DDS sends it and rosbag2 stores it.
    pub fn to_cdr(&self) -> Vec<u8> {
        use ubf_robots::ros2::msg::to_cdr;
        match self {
            Message::Tf(m) => to_cdr(m),
            Message::Odometry(m) => to_cdr(m.as_ref()),
            Message::Scan(m) => to_cdr(m),
            Message::Image(m) => to_cdr(m),
            Message::Pose(m) => to_cdr(m),
            Message::Tick(m) => to_cdr(m),
        }
    }
}

/// What of a tick the view shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shown {
    /// The robot's own topics: `/tf` (`odom` → `base_link`), `odom` and
    /// `scan`. Off for a ROS 2 robot, whose driver publishes them.
    pub robot: bool,
    /// The camera's images, at each new stereo frame that carries them.
    pub images: bool,
    /// The tree's decision (`ubf/tick`), its goal (`ubf/goal`) and the pose
    /// it steers by (`ubf/pose/steered`).
    pub tree: bool,
}

/// Turns ticks into ROS 2 messages.
pub struct Ros2View {
    shown: Shown,
    /// Seconds added to controller time for a stamp: 0 for a log that must
    /// be the same bytes for the same seed, the Unix time at the start for
    /// live messages (tf2 drops transforms far from now).
    epoch_s: f64,
    layout: TreeLayout,
    /// The frame of ubf's world, which poses and the goal are in.
    world: String,
    frame: u64,
    goal: Option<[f64; 3]>,
    /// Controller time the goal was last shown.
    goal_at: f64,
}

/// Seconds of controller time between goals shown again.
const GOAL_EVERY_S: f64 = 1.0;

/// Bins of the scan the range sensors are drawn into: one a degree.
const SCAN_BINS: usize = 360;

impl Ros2View {
    /// A view showing `shown`, stamping with controller time plus
    /// `epoch_s`.
    pub fn new(shown: Shown, epoch_s: f64) -> Ros2View {
        let world = ODOM_FRAME.to_owned();
        Ros2View { shown, epoch_s, layout: TreeLayout::default(), world, frame: 0, goal: None, goal_at: 0.0 }
    }

    /// This view, with ubf's world named `frame` instead of `odom`.
    pub fn in_world_frame(self, frame: String) -> Ros2View {
        Ros2View { world: frame, ..self }
    }

    /// Learns the tree's shape, to name the nodes of each tick.
    pub fn start(&mut self, layout: &TreeLayout) {
        self.layout = layout.clone();
    }

    /// The stamp of controller time `time`, s.
    pub fn stamp(&self, time: f64) -> f64 {
        self.epoch_s + time
    }

    /// Every message of `record`, with its topic and its stamp, s.
    pub fn messages(&mut self, record: &TickRecord, mut emit: impl FnMut(&'static str, f64, Message)) {
        let (state, t) = (&record.state, self.stamp(record.time()));
        if self.shown.robot {
            let wheels = &state.odometry;
            emit(topics::TF, t, Message::Tf(TFMessage::planar(t, &self.world, "base_link", wheels)));
            let odometry = odometry(Header::new(t, &self.world), wheels, state.velocity, state.rot_velocity);
            emit(topics::ODOM, t, Message::Odometry(Box::new(odometry)));
            if !state.ranges.is_empty() {
                emit(topics::SCAN, t, Message::Scan(scan(t, record)));
            }
        }
        // The goal when it changes, and once a second for viewers that
        // join late with a volatile reader (RViz's default).
        let goal = state.goal.filter(|_| self.shown.tree).map(|g| [g.x, g.y, g.tolerance]);
        if goal != self.goal || record.time() >= self.goal_at + GOAL_EVERY_S {
            self.goal = goal;
            self.goal_at = record.time();
            if let Some([x, y, _]) = goal {
                emit(topics::GOAL, t, Message::Pose(self.pose_stamped(t, &Pose2::new(x, y, 0.0))));
            }
        }
        if let Some(truth) = &record.truth {
            emit(topics::TRUE_POSE, t, Message::Pose(self.pose_stamped(t, &truth.pose)));
        }
        let frame = &state.stereo;
        if frame.number != self.frame && frame.number != 0 {
            self.frame = frame.number;
            let stamp = self.stamp(frame.time);
            if let Some(pose) = &state.egomotion.pose {
                emit(topics::EGOMOTION_POSE, stamp, Message::Pose(self.pose_stamped(stamp, pose)));
            }
            if let Some(images) = frame.images.as_deref().filter(|_| self.shown.images) {
                emit(topics::LEFT_IMAGE, stamp, Message::Image(image(stamp, "camera_left", images, &images.left)));
                emit(topics::RIGHT_IMAGE, stamp, Message::Image(image(stamp, "camera_right", images, &images.right)));
            }
        }
        if self.shown.tree {
            emit(topics::STEERED_POSE, t, Message::Pose(self.pose_stamped(t, &state.pose)));
            emit(topics::TICK, t, Message::Tick(self.tick(t, record)));
        }
    }

    fn pose_stamped(&self, stamp: f64, pose: &Pose2) -> PoseStamped {
        PoseStamped { header: Header::new(stamp, &self.world), pose: Pose::planar(pose) }
    }

    fn tick(&self, stamp: f64, record: &TickRecord) -> Tick {
        let layout = &self.layout;
        Tick {
            stamp: Time::from_seconds(stamp),
            tick: record.tick,
            winner: layout.winning_path(record).unwrap_or_default().to_owned(),
            linear: record.command.velocity(),
            angular: record.command.rot_velocity().unwrap_or(0.0),
            stop: record.command == ubf_core::Command::Stop,
            nodes: layout
                .nodes
                .iter()
                .zip(&record.nodes)
                .map(|(info, node)| NodeVote {
                    path: info.path.clone(),
                    vote: node.action.effective_vote(),
                    weight: node.weight,
                    won: node.won,
                })
                .collect(),
        }
    }
}

fn odometry(header: Header, pose: &Pose2, velocity: f64, rot_velocity: f64) -> Odometry {
    Odometry {
        header,
        child_frame_id: "base_link".into(),
        pose: PoseWithCovariance { pose: Pose::planar(pose), ..PoseWithCovariance::default() },
        twist: TwistWithCovariance { twist: Twist::planar(velocity, rot_velocity), ..TwistWithCovariance::default() },
    }
}

/// The range sensors as one scan from `base_link`: each echo drawn into
/// the degree bin of its bearing from the robot's centre (the nearest echo
/// where two fall in one bin); bins with no echo read infinity, REP 117's
/// "nothing seen".
fn scan(stamp: f64, record: &TickRecord) -> LaserScan {
    let increment = std::f64::consts::TAU / SCAN_BINS as f64;
    let mut ranges = vec![f32::INFINITY; SCAN_BINS];
    let mut range_max = 0.0f64;
    for reading in &record.state.ranges {
        range_max = range_max.max(reading.max_range);
        let Some(range) = reading.range else { continue };
        let hit = reading.pose_robot_sensor.compose(&Pose2::new(range, 0.0, 0.0));
        let bin = ((hit.y.atan2(hit.x) + std::f64::consts::PI) / increment).floor() as usize % SCAN_BINS;
        ranges[bin] = ranges[bin].min(hit.x.hypot(hit.y) as f32);
    }
    LaserScan {
        header: Header::new(stamp, "base_link"),
        angle_min: -std::f32::consts::PI,
        angle_max: (std::f64::consts::PI - increment) as f32,
        angle_increment: increment as f32,
        time_increment: 0.0,
        scan_time: 0.0,
        range_min: 0.0,
        range_max: range_max as f32,
        ranges,
        intensities: Vec::new(),
    }
}

fn image(stamp: f64, frame: &str, images: &StereoImages, pixels: &[u8]) -> Image {
    Image {
        header: Header::new(stamp, frame),
        height: images.height,
        width: images.width,
        encoding: "mono8".into(),
        is_bigendian: 0,
        step: images.width,
        data: pixels.to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odom_is_the_wheels_and_the_steered_pose_a_topic_of_its_own() {
        // The wheels say one pose, the pose steered by (a compass's or
        // egomotion's correction) another: tf and odom follow the wheels,
        // as REP 105's continuous odom frame asks, and the tree's pose has
        // its own topic.
        let mut record = TickRecord::default();
        record.state.odometry = Pose2::new(2.0, 0.5, 0.1);
        record.state.pose = Pose2::new(2.2, 0.3, 0.05);
        let mut view = Ros2View::new(Shown { robot: true, images: false, tree: true }, 0.0);
        let mut poses = Vec::new();
        view.messages(&record, |topic, _, message| match message {
            Message::Tf(tf) => poses.push((topic, tf.transforms[0].transform.translation.x)),
            Message::Odometry(odom) => poses.push((topic, odom.pose.pose.position.x)),
            Message::Pose(pose) => poses.push((topic, pose.pose.position.x)),
            _ => {}
        });
        assert_eq!(poses, [(topics::TF, 2.0), (topics::ODOM, 2.0), (topics::STEERED_POSE, 2.2)]);
        // Without the tree (a simulator served to another stack), no pose
        // of a tree.
        let mut view = Ros2View::new(Shown { robot: true, images: false, tree: false }, 0.0);
        let mut topics_seen = Vec::new();
        view.messages(&record, |topic, _, _| topics_seen.push(topic));
        assert_eq!(topics_seen, [topics::TF, topics::ODOM]);
    }
}
