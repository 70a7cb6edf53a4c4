//! A ROS 2 robot's velocity commands: `geometry_msgs/msg/Twist`, or
//! `TwistStamped` for a base that reads only that (ros2_control's diff
//! drive controller from Jazzy on, Nav2 from Kilted on), from one writer
//! that the control loop and an emergency stop share.

use super::config::Ros2Config;
use super::msg::{ros_name, Header, RosMessage, Twist, TwistStamped};
use super::node::{Node, Publisher, Qos};
use crate::emergency::EmergencyStop;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, PoisonError};
use std::time::{Duration, Instant};
use ubf_core::RobotError;

/// How long to wait (briefly) for the robot's driver to acknowledge a zero
/// twist on the way out.
const STOP_ACK_WAIT: Duration = Duration::from_millis(500);

/// One writer of the commands, of the type the robot reads.
enum Writer {
    Twist(Publisher<Twist>),
    /// With the frame the twist is in. Its stamp is zero, which the diff
    /// drive controller (and what else follows tf2's conventions for
    /// commands) takes as "when received": its command timeout then runs
    /// on its own clock. Stamped with this computer's clock, a clock ahead
    /// of the robot's by seconds would keep the last command alive for
    /// those seconds after ubf stopped sending.
    Stamped(Publisher<TwistStamped>, String),
}

/// The robot's velocity commands: the writer, and whether the robot has
/// been halted from outside the control loop.
pub(super) struct CmdVel {
    writer: Mutex<Writer>,
    halted: AtomicBool,
    stamped: bool,
}

impl CmdVel {
    /// A writer of the commands on the robot's topic, stamped or not.
    pub(super) fn new(node: &Node, config: &Ros2Config, stamped: bool) -> Result<CmdVel, RobotError> {
        let writer = match stamped {
            true => Writer::Stamped(node.writer(&config.cmd_vel, Qos::Reliable)?, config.base_frame.clone()),
            false => Writer::Twist(node.writer(&config.cmd_vel, Qos::Reliable)?),
        };
        Ok(CmdVel { writer: Mutex::new(writer), halted: AtomicBool::new(false), stamped })
    }

    /// Whether the commands go as `TwistStamped`.
    pub(super) fn stamped(&self) -> bool {
        self.stamped
    }

    /// Publishes `twist`, or a zero twist once the robot has been halted;
    /// the twist sent.
    pub(super) fn publish(&self, twist: Twist) -> Result<Twist, RobotError> {
        let writer = self.writer.lock().unwrap_or_else(PoisonError::into_inner);
        let twist = if self.halted.load(Ordering::SeqCst) { Twist::default() } else { twist };
        writer.publish(twist)?;
        Ok(twist)
    }

    /// Waits (briefly) for the robot's driver to acknowledge what was
    /// published, and says on the log if it did not.
    pub(super) fn await_acknowledgement(&self) {
        let writer = self.writer.lock().unwrap_or_else(PoisonError::into_inner);
        let acknowledged = match &*writer {
            Writer::Twist(publisher) => publisher.acknowledged_within(STOP_ACK_WAIT),
            Writer::Stamped(publisher, _) => publisher.acknowledged_within(STOP_ACK_WAIT),
        };
        if !acknowledged {
            tracing::warn!(
                "the zero twist on {} was not acknowledged within {:.1} s",
                writer.name(),
                STOP_ACK_WAIT.as_secs_f64()
            );
        }
    }
}

impl Writer {
    fn publish(&self, twist: Twist) -> Result<(), RobotError> {
        match self {
            Writer::Twist(publisher) => publisher.publish(twist),
            Writer::Stamped(publisher, frame) => {
                publisher.publish(TwistStamped { header: Header::new(0.0, frame), twist })
            }
        }
    }

    fn name(&self) -> &str {
        match self {
            Writer::Twist(publisher) => publisher.name(),
            Writer::Stamped(publisher, _) => publisher.name(),
        }
    }
}

/// How long the readers of the commands must stay as they are, once one
/// has been seen, before their type is read off them: discovery reports a
/// participant's endpoints one by one.
const READERS_SETTLE: Duration = Duration::from_millis(300);

/// Whether to send `TwistStamped`: as the robot file says, else as the
/// robot reads its commands, which discovery shows (waiting up to the
/// connect timeout for a reader): `TwistStamped` if they are read as that
/// and not as `Twist`, else `Twist`. Read as both, which type the base
/// reads cannot be told, and the drive does not start.
pub(super) fn choose_stamped(node: &mut Node, config: &Ros2Config) -> Result<bool, RobotError> {
    if let Some(stamped) = config.cmd_vel_stamped {
        return Ok(stamped);
    }
    let deadline = Instant::now() + config.connect_timeout();
    let mut readers = node.reader_types(&config.cmd_vel);
    while readers.is_empty() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(10));
        readers = node.reader_types(&config.cmd_vel);
    }
    if !readers.is_empty() {
        std::thread::sleep(READERS_SETTLE);
        readers = node.reader_types(&config.cmd_vel);
    }
    let topic = node.resolve(&config.cmd_vel);
    match (readers.contains(&Twist::dds_name()), readers.contains(&TwistStamped::dds_name())) {
        (true, true) => Err(RobotError::Protocol {
            what: "the velocity commands".into(),
            source: format!(
                "{topic} is read as both {} and {}, so which the robot reads cannot be told: set `cmd_vel_stamped` \
                 in the robot file's `ros2: (...)`",
                Twist::NAME,
                TwistStamped::NAME
            )
            .into(),
        }),
        (false, true) => {
            tracing::info!("commands go as {}, which the robot reads", TwistStamped::NAME);
            Ok(true)
        }
        _ => {
            if readers.is_empty() {
                tracing::warn!("nothing reads {topic} yet: commands go as {}", Twist::NAME);
            }
            Ok(false)
        }
    }
}

/// What the commands go as, to [`why_unread`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Sent {
    Twist,
    Stamped,
    /// Not chosen yet: either would do.
    Either,
}

/// Why the commands would reach none of the readers discovery has seen on
/// them, if they would not: every reader reads another type than the one
/// sent. Moving nothing, the drive would only end on its progress check.
pub(super) fn why_unread(node: &mut Node, config: &Ros2Config, sent: Sent) -> Option<String> {
    let readers = node.reader_types(&config.cmd_vel);
    let (twist, stamped) = (Twist::dds_name(), TwistStamped::dds_name());
    let sent_types = match sent {
        Sent::Twist => vec![&twist],
        Sent::Stamped => vec![&stamped],
        Sent::Either => vec![&twist, &stamped],
    };
    if readers.is_empty() || readers.iter().any(|read| sent_types.contains(&read)) {
        return None;
    }
    let topic = node.resolve(&config.cmd_vel);
    let other = match sent {
        Sent::Twist if readers.contains(&stamped) => Some(true),
        Sent::Stamped if readers.contains(&twist) => Some(false),
        _ => None,
    };
    let hint = match (other, config.cmd_vel_stamped) {
        (Some(other), Some(_)) => format!(
            "set `cmd_vel_stamped: {other}` in the robot file's `ros2: (...)`, or leave it unset to read the type \
             off the robot"
        ),
        (Some(other), None) => format!(
            "the robot's reader came after the type was chosen (raise `connect_timeout_s`, or set \
             `cmd_vel_stamped: {other}` in the robot file's `ros2: (...)`)"
        ),
        (None, _) => "is another robot's driver on this domain?".to_owned(),
    };
    let read: Vec<String> = readers.iter().map(|read| ros_name(read)).collect();
    let sent: Vec<String> = sent_types.iter().map(|sent| ros_name(sent)).collect();
    Some(format!("{topic} is read as {}, and ubf sends {}: {hint}", read.join(", "), sent.join(" or ")))
}

/// What a signal handler stops a ROS 2 robot with while the control loop
/// is busy or stuck: a zero twist on the robot's own writer.
pub struct Ros2EmergencyStop {
    pub(super) cmd_vel: std::sync::Arc<CmdVel>,
}

impl EmergencyStop for Ros2EmergencyStop {
    /// Publishes a zero twist now, and every twist the control loop
    /// publishes after it is a zero twist too.
    fn halt(&self) -> Result<(), RobotError> {
        let writer = self.cmd_vel.writer.lock().unwrap_or_else(PoisonError::into_inner);
        self.cmd_vel.halted.store(true, Ordering::SeqCst);
        writer.publish(Twist::default())
    }

    /// Halts, and waits (briefly) for the driver to acknowledge the zero
    /// twist: a writer that leaves first may take it along.
    fn stop_now(&self) -> Result<(), RobotError> {
        self.halt()?;
        self.cmd_vel.await_acknowledgement();
        Ok(())
    }

    fn stop_now_sends(&self) -> String {
        let writer = self.cmd_vel.writer.lock().unwrap_or_else(PoisonError::into_inner);
        format!("a zero twist on {}", writer.name())
    }
}
