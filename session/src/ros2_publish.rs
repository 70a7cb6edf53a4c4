//! A sink publishing every tick on ROS 2 (`/tf`, `odom`, `scan`, camera
//! images, `ubf/tick`, `ubf/goal`), so that RViz, Foxglove or `ros2 topic
//! echo` see a run or a drive as it happens. Run it behind a
//! [`ubf_core::BackgroundSink`]: a slow network then drops records, never a
//! tick.

use crate::ros2_view::{topics, Message, Ros2View, Shown};
use std::collections::BTreeMap;
use ubf_core::{BackgroundSink, RobotError, TickRecord, TickSink, TreeLayout};
use ubf_robots::ros2::msg::{Image, LaserScan, Odometry, PoseStamped, TFMessage, Tick};
use ubf_robots::ros2::{Node, Publisher, Qos};

/// One topic's writer, by message type.
enum Writer {
    Tf(Publisher<TFMessage>),
    Odometry(Publisher<Odometry>),
    Scan(Publisher<LaserScan>),
    Image(Publisher<Image>),
    Pose(Publisher<PoseStamped>),
    Tick(Publisher<Tick>),
}

/// The QoS ROS 2 tools expect on `topic`.
fn qos_of(topic: &str) -> Qos {
    match topic {
        topics::SCAN | topics::LEFT_IMAGE | topics::RIGHT_IMAGE => Qos::SensorData,
        topics::GOAL => Qos::Latched,
        _ => Qos::Reliable,
    }
}

/// A message of one type for a topic whose writer was made for another: a
/// fault of the view, reported instead of published.
#[derive(Debug, thiserror::Error)]
#[error("a {message} on a topic of another type")]
struct OtherType {
    /// The message's ROS 2 type.
    message: &'static str,
}

/// Publishes ticks on ROS 2.
pub struct Ros2Publisher {
    view: Ros2View,
    writers: BTreeMap<&'static str, Writer>,
    /// The first publishing failure is reported; later ones are not.
    warned: bool,
    /// Last, so that it is dropped after its writers.
    node: Node,
}

impl Ros2Publisher {
    /// Joins `domain` under `namespace`, publishing what `shown` asks for
    /// with ubf's world named `world`, stamped with the wall clock (tf2
    /// and RViz drop what is far from now).
    pub fn new(domain: u16, namespace: &str, shown: Shown, world: &str) -> Result<Ros2Publisher, RobotError> {
        let node = Node::join(domain, namespace)?;
        let epoch_s =
            std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64());
        let view = Ros2View::new(shown, epoch_s).in_world_frame(world.to_owned());
        Ok(Ros2Publisher { view, writers: BTreeMap::new(), warned: false, node })
    }

    fn writer(&mut self, topic: &'static str, message: &Message) -> Result<&Writer, RobotError> {
        if !self.writers.contains_key(topic) {
            let (node, qos) = (&self.node, qos_of(topic));
            let writer = match message {
                Message::Tf(_) => Writer::Tf(node.writer(topic, qos)?),
                Message::Odometry(_) => Writer::Odometry(node.writer(topic, qos)?),
                Message::Scan(_) => Writer::Scan(node.writer(topic, qos)?),
                Message::Image(_) => Writer::Image(node.writer(topic, qos)?),
                Message::Pose(_) => Writer::Pose(node.writer(topic, qos)?),
                Message::Tick(_) => Writer::Tick(node.writer(topic, qos)?),
            };
            self.writers.insert(topic, writer);
        }
        Ok(&self.writers[topic])
    }

    fn publish(&mut self, topic: &'static str, message: Message) -> Result<(), RobotError> {
        match (self.writer(topic, &message)?, message) {
            (Writer::Tf(w), Message::Tf(m)) => w.publish(m),
            (Writer::Odometry(w), Message::Odometry(m)) => w.publish(*m),
            (Writer::Scan(w), Message::Scan(m)) => w.publish(m),
            (Writer::Image(w), Message::Image(m)) => w.publish(m),
            (Writer::Pose(w), Message::Pose(m)) => w.publish(m),
            (Writer::Tick(w), Message::Tick(m)) => w.publish(m),
            (_, message) => Err(RobotError::Middleware {
                what: self.node.resolve(topic),
                source: Box::new(OtherType { message: message.type_name() }),
            }),
        }
    }
}

impl TickSink for Ros2Publisher {
    fn start(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.view.start(layout);
        Ok(())
    }

    fn tree_changed(&mut self, layout: &TreeLayout) -> std::io::Result<()> {
        self.view.start(layout);
        Ok(())
    }

    /// Publishes the tick. A failure is reported once and never stops the
    /// robot: the ROS 2 view is for watching, not for control.
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        let mut messages = Vec::new();
        self.view.messages(record, |topic, _, message| messages.push((topic, message)));
        for (topic, message) in messages {
            if let Err(why) = self.publish(topic, message) {
                if !std::mem::replace(&mut self.warned, true) {
                    tracing::warn!("{why}; the ROS 2 view may miss messages");
                }
            }
        }
        Ok(())
    }
}

/// A ROS 2 publisher in `domain` (unset: `ROS_DOMAIN_ID`) under
/// `namespace`, with ubf's world named `world` (`odom` where ubf publishes
/// the robot's odometry, [`ubf_robots::ros2::world_frame()`] beside a ROS 2
/// robot's own), on a thread of its own: a slow network drops records,
/// never a tick.
pub fn background_publisher(
    shown: Shown,
    domain: Option<u16>,
    namespace: &str,
    world: &str,
) -> Result<BackgroundSink, RobotError> {
    let domain = domain.map_or_else(ubf_robots::ros2::domain_from_env, Ok)?;
    let publisher = Ros2Publisher::new(domain, namespace, shown, world)?;
    BackgroundSink::spawn("ROS 2 publisher", publisher, QUEUE).map_err(RobotError::Io)
}

/// Ticks the ROS 2 publisher may fall behind by before records are dropped.
const QUEUE: usize = 64;
