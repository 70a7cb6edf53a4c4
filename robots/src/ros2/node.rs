//! A DDS participant that speaks ROS 2's conventions: topic names
//! (`/odom` is `rt/odom`), type names (`nav_msgs::msg::dds_::Odometry_`),
//! key-less topics and the stock QoS profiles; and that can say why a
//! topic does not match (a wrong type, a QoS the other side cannot serve).

use super::msg::RosMessage;
use rustdds::no_key::{DataReaderCdr, DataWriterCdr};
use rustdds::policy::{Durability, History, Reliability, ResourceLimits};
use rustdds::{
    DomainParticipant, DomainParticipantStatusEvent, QosPolicies, QosPolicyBuilder, StatusEvented, TopicKind,
};
use serde::Deserialize;
use ubf_core::{LinkLoss, RobotError};

/// A topic's quality of service, as ROS 2 names its stock profiles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Qos {
    /// ROS 2's default: reliable, volatile, keep last 10.
    #[default]
    Reliable,
    /// ROS 2's sensor data profile: best effort, volatile, keep last 5. A
    /// best-effort reader also hears reliable writers.
    SensorData,
    /// A latched topic (a goal, a map): reliable, transient local, keep
    /// last 1, so that a viewer that joins late still gets the last
    /// message.
    Latched,
}

impl Qos {
    /// A topic's and its readers' policies. The middleware keeps 64
    /// messages a topic whatever the history says unless limited (4 GB of
    /// a stranger's 64 MB messages): a topic keeps what its history asks
    /// for.
    fn policies(self) -> QosPolicies {
        let depth = self.depth();
        self.builder()
            .resource_limits(ResourceLimits { max_samples: depth, max_instances: 1, max_samples_per_instance: depth })
            .build()
    }

    /// A writer's policies. Its limit is its reliable send window (how many
    /// messages may await acknowledgement), not what it keeps: limited to
    /// the history's depth, one reader that stopped acknowledging (a
    /// stalled `ros2 topic echo`) would block the robot's commands, its
    /// stops included, after a second. It keeps the middleware's own
    /// window.
    fn writer_policies(self) -> QosPolicies {
        let window = WRITER_WINDOW;
        self.builder()
            .resource_limits(ResourceLimits { max_samples: window, max_instances: 1, max_samples_per_instance: window })
            .build()
    }

    /// A reader's policies: the topic's, except that a latched reader
    /// keeps one message for each of up to [`LATCHED_WRITERS`] writers.
    /// Each latched writer hands a reader that joins late its last
    /// message, all at once: a robot's static transform broadcasters each
    /// hand theirs.
    fn reader_policies(self) -> QosPolicies {
        match self {
            Qos::Latched => {
                let depth = LATCHED_WRITERS;
                self.builder()
                    .history(History::KeepLast { depth })
                    .resource_limits(ResourceLimits {
                        max_samples: depth,
                        max_instances: 1,
                        max_samples_per_instance: depth,
                    })
                    .build()
            }
            Qos::Reliable | Qos::SensorData => self.policies(),
        }
    }

    fn depth(self) -> i32 {
        match self {
            Qos::Reliable => 10,
            Qos::SensorData => 5,
            Qos::Latched => 1,
        }
    }

    fn builder(self) -> QosPolicyBuilder {
        let reliable = Reliability::Reliable { max_blocking_time: rustdds::Duration::from_millis(100) };
        let (durability, reliability) = match self {
            Qos::Reliable => (Durability::Volatile, reliable),
            Qos::SensorData => (Durability::Volatile, Reliability::BestEffort),
            Qos::Latched => (Durability::TransientLocal, reliable),
        };
        QosPolicyBuilder::new()
            .durability(durability)
            .reliability(reliability)
            .history(History::KeepLast { depth: self.depth() })
    }
}

/// How many latched writers' last messages a latched reader keeps.
const LATCHED_WRITERS: i32 = 100;

/// The middleware's reliable send window when none is set (RustDDS's
/// `DEFAULT_WRITER_MAX_SAMPLES`).
const WRITER_WINDOW: i32 = 8192;

/// What discovery saw of another participant's endpoint on a topic.
#[derive(Clone, Debug)]
struct Endpoint {
    writer: bool,
    topic: String,
    type_name: String,
    reliable: bool,
}

/// A writer of one topic.
pub struct Publisher<M: RosMessage> {
    writer: DataWriterCdr<M>,
    name: String,
}

impl<M: RosMessage> Publisher<M> {
    /// Publishes `message`.
    pub fn publish(&self, message: M) -> Result<(), RobotError> {
        self.writer.write(message, None).map_err(|e| {
            // The error carries the message back; a failure needs only why.
            let source = Box::new(e.forget_data());
            LinkLoss::SendFailed { what: format!("publishing {}", self.name), source }.into()
        })
    }

    /// Waits up to `wait` for every matched reader to acknowledge what was
    /// published; whether they all did.
    pub fn acknowledged_within(&self, wait: std::time::Duration) -> bool {
        matches!(self.writer.wait_for_acknowledgments(wait), Ok(true))
    }

    /// The topic's ROS 2 name.
    pub fn name(&self) -> &str {
        &self.name
    }
}

/// A reader of one topic.
pub struct Subscription<M: RosMessage> {
    reader: DataReaderCdr<M>,
    name: String,
    /// The writer of the last message taken, and when it was taken, where
    /// the topic must have one writer only ([`Subscription::single_writer`]).
    last_writer: Option<Option<(rustdds::GUID, std::time::Instant)>>,
    /// The middleware's reason the last message since the last readable
    /// one could not be read, if one could not.
    unreadable: Option<String>,
    /// When an unreadable message was last said on the log.
    unreadable_said_at: Option<std::time::Instant>,
}

/// The most messages [`Subscription::take_latest`] takes in one call: far
/// beyond what a topic keeps (its history's depth).
const MOST_TAKEN: usize = 1000;

/// How often skipped unreadable messages are said on the log, at most.
const UNREADABLE_SAID_EVERY: std::time::Duration = std::time::Duration::from_secs(10);

/// How long after a writer's last message another writer's is taken as a
/// second source, not as the first one's successor (a driver restarted).
const OTHER_WRITER_WITHIN: std::time::Duration = std::time::Duration::from_secs(1);

impl<M: RosMessage> Subscription<M> {
    /// This subscription, for a topic only one writer may publish on (a
    /// robot's odometry and scan, not the commands several may send): two
    /// writers at once are then an error from [`Subscription::take_latest`],
    /// as which one is the robot cannot be told, and the reader would keep
    /// either one's messages (a stray odometry once steered the robot).
    pub fn single_writer(mut self) -> Self {
        self.last_writer = Some(None);
        self
    }

    /// The topic, resolved in the node's namespace (`/robot1/odom`).
    pub fn topic(&self) -> &str {
        &self.name
    }

    /// Why the messages on the topic since the last readable one could
    /// not be read as `M`, if one could not (`could not be read as …`):
    /// what to say when the topic seems silent.
    pub fn unreadable(&self) -> Option<String> {
        self.unreadable.as_deref().map(unreadable::<M>)
    }

    /// The newest message that came since the last call, if any (older
    /// ones are taken and dropped: a controller wants the latest). A
    /// message that cannot be read as `M` is skipped, as a ROS 2 node
    /// skips it, and said on the log (at most every 10 s): a stranger on
    /// the domain must not stop the robot, and a robot whose own messages
    /// cannot be read falls silent, which its user hears about.
    pub fn take_latest(&mut self) -> Result<Option<M>, RobotError> {
        let mut latest = None;
        self.take_each(|message| latest = Some(message))?;
        Ok(latest)
    }

    /// Every message that came since the last call, oldest first, given
    /// to `each`; otherwise as [`Subscription::take_latest`].
    pub fn take_each(&mut self, mut each: impl FnMut(M)) -> Result<(), RobotError> {
        // At most a cache's worth a call, so that a flood cannot hold a tick.
        for _ in 0..MOST_TAKEN {
            match self.reader.take_next_sample() {
                Ok(Some(sample)) => {
                    if let Some(last_writer) = &mut self.last_writer {
                        let (writer, now) = (sample.sample_info().writer_guid(), std::time::Instant::now());
                        if let Some((last, at)) = *last_writer {
                            if last != writer && now - at < OTHER_WRITER_WITHIN {
                                let why = "two writers publish on it at once: which one is the robot cannot be \
                                           told; stop the other";
                                return Err(RobotError::Protocol { what: self.name.clone(), source: why.into() });
                            }
                        }
                        *last_writer = Some((writer, now));
                    }
                    self.unreadable = None;
                    each(sample.into_value());
                }
                Ok(None) => return Ok(()),
                Err(rustdds::dds::ReadError::Deserialization { reason }) => {
                    let now = std::time::Instant::now();
                    if self.unreadable_said_at.is_none_or(|at| now - at >= UNREADABLE_SAID_EVERY) {
                        tracing::warn!("a message on {}: it {}; skipped", self.name, unreadable::<M>(&reason));
                        self.unreadable_said_at = Some(now);
                    }
                    self.unreadable = Some(reason);
                }
                Err(e) => {
                    return Err(RobotError::Protocol { what: format!("a message on {}", self.name), source: e.into() })
                }
            }
        }
        Ok(())
    }
}

/// Why a message could not be taken as `M`, as a clause, from the
/// middleware's `reason`: its own text names the topic twice and the
/// type as a Rust value, and hides the one reason it gives in the middle.
fn unreadable<M: RosMessage>(reason: &str) -> String {
    let reason = reason.strip_prefix("Failed to deserialize sample bytes: ").unwrap_or(reason);
    let reason = reason.split(", ").next().unwrap_or(reason);
    format!("could not be read as {} ({reason}): something on the domain publishes another message there", M::NAME)
}

/// A ROS 2 participant in one DDS domain, under one namespace.
pub struct Node {
    participant: DomainParticipant,
    publisher: rustdds::Publisher,
    subscriber: rustdds::Subscriber,
    namespace: String,
    domain: u16,
    /// Every endpoint discovery has reported and not lost since.
    seen: std::collections::HashMap<rustdds::GUID, Endpoint>,
}

/// DDS could not set up `what`.
fn setup(what: String, e: impl std::error::Error + Send + Sync + 'static) -> RobotError {
    RobotError::Middleware { what, source: Box::new(e) }
}

/// `ROS_DOMAIN_ID`, as ROS 2 reads it: unset or empty is domain 0.
pub fn domain_from_env() -> Result<u16, RobotError> {
    match std::env::var("ROS_DOMAIN_ID") {
        Err(_) => Ok(0),
        Ok(text) if text.trim().is_empty() => Ok(0),
        // RTPS's port formula leaves room for domains 0 to 232.
        Ok(text) => text.trim().parse::<u16>().ok().filter(|d| *d <= 232).ok_or_else(|| RobotError::Setting {
            setting: "ROS_DOMAIN_ID",
            value: text.clone(),
            expected: "a whole number from 0 to 232",
        }),
    }
}

/// What a process refused netlink sockets is told.
#[cfg(target_os = "linux")]
const NETLINK_REFUSED: &str =
    "finding the network interfaces, which DDS reads through netlink sockets (a sandbox must \
                               allow them: under systemd, AF_NETLINK in RestrictAddressFamilies)";

/// Whether this process may open a netlink socket. DDS finds the network
/// interfaces through one on Linux; refused (a sandbox's address families),
/// it finds none and joins with nowhere to send or listen, so that every
/// topic is then silent and the robot's driver looks missing.
#[cfg(target_os = "linux")]
fn netlink_allowed() -> std::io::Result<()> {
    let netlink = socket2::Domain::from(libc::AF_NETLINK);
    socket2::Socket::new(netlink, socket2::Type::DGRAM, None).map(drop)
}

impl Node {
    /// Joins `domain` with topics under `namespace` (`""` or `/robot1`).
    pub fn join(domain: u16, namespace: &str) -> Result<Node, RobotError> {
        let in_domain = |what: &str| format!("ROS 2 domain {domain}: {what}");
        #[cfg(target_os = "linux")]
        netlink_allowed().map_err(|e| setup(in_domain(NETLINK_REFUSED), e))?;
        let participant = DomainParticipant::new(domain).map_err(|e| setup(in_domain("joining"), e))?;
        let qos = QosPolicyBuilder::new().build();
        let publisher = participant.create_publisher(&qos).map_err(|e| setup(in_domain("creating a publisher"), e))?;
        let subscriber =
            participant.create_subscriber(&qos).map_err(|e| setup(in_domain("creating a subscriber"), e))?;
        let namespace = namespace.trim_matches('/');
        let namespace = if namespace.is_empty() { String::new() } else { format!("/{namespace}") };
        Ok(Node { participant, publisher, subscriber, namespace, domain, seen: Default::default() })
    }

    /// The domain joined.
    pub fn domain(&self) -> u16 {
        self.domain
    }

    /// `name`'s ROS 2 name: absolute names (`/tf`) stay, relative ones go
    /// under the namespace.
    pub fn resolve(&self, name: &str) -> String {
        if name.starts_with('/') {
            name.to_owned()
        } else {
            format!("{}/{name}", self.namespace)
        }
    }

    fn topic<M: RosMessage>(&self, name: &str, qos: Qos) -> Result<rustdds::Topic, RobotError> {
        let dds_name = format!("rt{}", self.resolve(name));
        self.participant
            .create_topic(dds_name, M::dds_name(), &qos.policies(), TopicKind::NoKey)
            .map_err(|e| setup(format!("ROS 2 topic {}", self.resolve(name)), e))
    }

    /// A writer of `M` on topic `name`.
    pub fn writer<M: RosMessage>(&self, name: &str, qos: Qos) -> Result<Publisher<M>, RobotError> {
        let topic = self.topic::<M>(name, qos)?;
        let name = self.resolve(name);
        match self.publisher.create_datawriter_no_key_cdr::<M>(&topic, Some(qos.writer_policies())) {
            Ok(writer) => Ok(Publisher { writer, name }),
            Err(e) => Err(setup(format!("publishing {name}"), e)),
        }
    }

    /// A reader of `M` on topic `name`.
    pub fn reader<M: RosMessage>(&self, name: &str, qos: Qos) -> Result<Subscription<M>, RobotError> {
        let topic = self.topic::<M>(name, qos)?;
        let name = self.resolve(name);
        match self.subscriber.create_datareader_no_key_cdr::<M>(&topic, Some(qos.reader_policies())) {
            Ok(reader) => {
                Ok(Subscription { reader, name, last_writer: None, unreadable: None, unreadable_said_at: None })
            }
            Err(e) => Err(setup(format!("subscribing {name}"), e)),
        }
    }

    /// Takes in what discovery has reported since the last call.
    pub fn watch_discovery(&mut self) {
        let listener = self.participant.status_listener();
        while let Some(event) = listener.try_recv_status() {
            let (writer, endpoint) = match event {
                DomainParticipantStatusEvent::WriterDetected { writer } => (true, writer),
                DomainParticipantStatusEvent::ReaderDetected { reader } => (false, reader),
                DomainParticipantStatusEvent::WriterLost { guid, .. }
                | DomainParticipantStatusEvent::ReaderLost { guid, .. } => {
                    self.seen.remove(&guid);
                    continue;
                }
                DomainParticipantStatusEvent::ParticipantLost { id, .. } => {
                    self.seen.retain(|guid, _| guid.prefix != id);
                    continue;
                }
                _ => continue,
            };
            let reliable = endpoint.qos.is_reliable();
            let seen = Endpoint { writer, topic: endpoint.topic_name, type_name: endpoint.type_name, reliable };
            self.seen.insert(endpoint.guid, seen);
        }
    }

    /// Whether discovery has seen a writer on topic `name`.
    pub fn has_writer(&mut self, name: &str) -> bool {
        !self.writer_types(name).is_empty()
    }

    /// Why a topic this node reads as `M` with `qos` hears nothing from
    /// the writers discovery has seen on it, if discovery tells: a writer
    /// of another type, or a best-effort writer to a reliable reader.
    pub fn why_unheard<M: RosMessage>(&mut self, name: &str, qos: Qos) -> Option<String> {
        self.watch_discovery();
        let (ros_name, dds_topic) = (self.resolve(name), format!("rt{}", self.resolve(name)));
        let writers = self.seen.values().filter(|e| e.writer && e.topic == dds_topic);
        for writer in writers {
            if writer.type_name != M::dds_name() {
                return Some(format!(
                    "{ros_name} is published with type `{}`, but ubf reads it as `{}` ({})",
                    writer.type_name,
                    M::dds_name(),
                    M::NAME
                ));
            }
            if qos == Qos::Reliable && !writer.reliable {
                return Some(format!(
                    "{ros_name} is published best effort, and a reliable reader cannot hear a best-effort writer: \
                     set its QoS to `SensorData` in the robot file's `ros2: (...)`"
                ));
            }
        }
        None
    }

    /// The types (DDS names) of the readers discovery has seen on topic
    /// `name`, each once.
    pub fn reader_types(&mut self, name: &str) -> Vec<String> {
        self.endpoint_types(name, false)
    }

    /// The types (DDS names) of the writers discovery has seen on topic
    /// `name`, each once.
    pub fn writer_types(&mut self, name: &str) -> Vec<String> {
        self.endpoint_types(name, true)
    }

    fn endpoint_types(&mut self, name: &str, writers: bool) -> Vec<String> {
        self.watch_discovery();
        let dds_topic = format!("rt{}", self.resolve(name));
        let mut types: Vec<String> = self
            .seen
            .values()
            .filter(|e| e.writer == writers && e.topic == dds_topic)
            .map(|e| e.type_name.clone())
            .collect();
        types.sort();
        types.dedup();
        types
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_topic_keeps_no_more_messages_than_its_history_asks_for_a_latched_reader_one_a_writer_and_a_writer_its_window()
    {
        for (qos, depth) in [(Qos::Reliable, 10), (Qos::SensorData, 5), (Qos::Latched, 1)] {
            let policies = qos.policies();
            assert_eq!(policies.history(), Some(History::KeepLast { depth }));
            let limits = policies.resource_limits().expect("a limit");
            assert_eq!((limits.max_samples, limits.max_samples_per_instance), (depth, depth));
            let reader = qos.reader_policies();
            let kept = if qos == Qos::Latched { LATCHED_WRITERS } else { depth };
            assert_eq!(reader.history(), Some(History::KeepLast { depth: kept }));
            assert_eq!(reader.resource_limits().expect("a limit").max_samples, kept);
            let writer = qos.writer_policies();
            assert_eq!(writer.history(), Some(History::KeepLast { depth }));
            assert_eq!(writer.resource_limits().expect("a window").max_samples, WRITER_WINDOW);
        }
    }

    #[test]
    fn an_unreadable_message_is_said_in_a_sentence() {
        // As the middleware said it for a short Odometry from a stranger.
        let reason = "Failed to deserialize sample bytes: unexpected end of input, , Topic = rt/odom, Type = \
                      TypeDesc { my_name: \"nav_msgs::msg::dds_::Odometry_\" }";
        let said = unreadable::<super::super::msg::Odometry>(reason);
        assert_eq!(
            said,
            "could not be read as nav_msgs/msg/Odometry (unexpected end of input): something on the domain \
             publishes another message there"
        );
    }
}
