//! Why a robot could not sense or act. The kinds are typed so that a caller
//! can tell a lost link, which reopening may mend, from a fault that a new
//! session would only meet again (and enable the motors for); what a user
//! reads is each kind's message, a sentence.

use std::error::Error;

/// Why a robot could not sense or act. More kinds may come; match with a
/// catch-all arm.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RobotError {
    /// The link to the robot is gone: a cable, a socket, a robot that fell
    /// silent. Reopening the link may help ([`RobotError::is_link_loss`]).
    #[error("robot disconnected: {reason}")]
    Disconnected {
        /// What happened to the link.
        #[source]
        reason: LinkLoss,
    },
    /// Reading or writing the link failed.
    #[error("robot I/O: {0}")]
    Io(#[from] std::io::Error),
    /// The robot sent something that cannot be read.
    #[error("robot protocol: {what}: {source}")]
    Protocol {
        /// What was malformed: a packet (`CONFIG`), a topic's message.
        what: String,
        /// What the decoder found wrong with it.
        source: Box<dyn Error + Send + Sync>,
    },
    /// The robot that answered is not the one the configuration describes.
    #[error("the robot is a {found}, the configuration expects a {expected}")]
    WrongRobot {
        /// The robot that answered, as it names itself.
        found: String,
        /// The robot the configuration names.
        expected: String,
    },
    /// A setting the robot is reached with has a value it cannot take.
    #[error("{setting} is `{value}`; it must be {expected}")]
    Setting {
        /// The setting (`ROS_DOMAIN_ID`, a model's `switch_to_baud`).
        setting: &'static str,
        /// The value it has.
        value: String,
        /// The values it may take, as a phrase.
        expected: &'static str,
    },
    /// The middleware the robot is reached through (DDS, for ROS 2) could
    /// not set up what talking to it needs.
    #[error("{what}: {source}")]
    Middleware {
        /// What was being set up (`ROS 2 topic /odom`).
        what: String,
        /// The middleware's error.
        source: Box<dyn Error + Send + Sync>,
    },
    /// The camera failed (an unreadable pair, a device gone): a camera
    /// fault, not a lost link, so nothing reconnects to the robot, and its
    /// motors are never enabled again, because of it.
    #[error("camera: {0}")]
    Camera(#[source] Box<dyn Error + Send + Sync>),
    /// The pan-tilt unit the camera rides on failed (its link, a reading
    /// gone stale): like a camera fault, not a lost link to the robot.
    #[error("pan-tilt unit on {unit}: {fault}")]
    PanTilt {
        /// Where the unit is connected: a serial device, an address.
        unit: String,
        /// What its driver found wrong.
        #[source]
        fault: Box<dyn Error + Send + Sync>,
    },
}

impl RobotError {
    /// Whether the link to the robot itself was lost, so that reopening it
    /// may help: not a fault of the camera or another device it carries,
    /// for which a new session would only enable the motors again.
    pub fn is_link_loss(&self) -> bool {
        matches!(self, RobotError::Disconnected { .. } | RobotError::Io(_))
    }
}

/// The fastest any ground robot this drives moves, with room to spare
/// (a Powerbot's top speed is 2 m/s), m/s.
const MOST_ROBOT_SPEED_M_S: f64 = 5.0;

/// The least time a reading's motion is counted over, s: readings that
/// arrive bunched (a busy machine, a buffer flushed) each still carry a
/// cycle's motion (0.1 s on ARCOS), and a reading or two lost between them
/// (a checksum failed) carried theirs. Still short enough to catch a jump
/// of metres.
const LEAST_READING_GAP_S: f64 = 0.3;

impl LinkLoss {
    /// The odometry's move of `metres` between readings `seconds` apart,
    /// if it is further than any robot drives ([`LinkLoss::ImpossibleMotion`]):
    /// steered by, such data would drive the robot anywhere, or fake a goal
    /// reached.
    pub fn impossible_motion(metres: f64, seconds: f64) -> Option<LinkLoss> {
        let possible = metres <= MOST_ROBOT_SPEED_M_S * seconds.max(LEAST_READING_GAP_S);
        (!possible).then_some(LinkLoss::ImpossibleMotion { metres, seconds })
    }
}

impl From<LinkLoss> for RobotError {
    fn from(reason: LinkLoss) -> Self {
        RobotError::Disconnected { reason }
    }
}

/// What happened to a link that was lost. More kinds may come; match with
/// a catch-all arm.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LinkLoss {
    /// No sensor data came for this long: the robot, or its link, fell
    /// silent.
    #[error("no sensor data for {for_s:.2} s")]
    NoSensorData {
        /// Seconds since the last reading.
        for_s: f64,
    },
    /// No sensor data came since the session began, this long ago.
    #[error("no sensor data in the first {within_s:.2} s")]
    NoSensorDataYet {
        /// Seconds since the session began.
        within_s: f64,
    },
    /// The other end closed the link: the robot's controller, or whatever
    /// stands in for it, went away.
    #[error("the link closed")]
    Closed,
    /// Reading the link failed: a serial device unplugged, a connection
    /// reset.
    #[error("reading the link failed: {0}")]
    ReadFailed(std::io::ErrorKind),
    /// The robot's odometry moved further between two readings than any
    /// robot drives: its data are corrupt, whatever else the link says.
    #[error("the odometry jumped {metres:.2} m in {seconds:.2} s, faster than any robot drives: its data are corrupt")]
    ImpossibleMotion {
        /// How far it jumped.
        metres: f64,
        /// Between readings this far apart.
        seconds: f64,
    },
    /// The robot did not answer the handshake.
    #[error("no handshake after {attempts} attempts")]
    NoHandshake {
        /// Handshakes tried.
        attempts: usize,
    },
    /// The robot answered the handshake, then sent nothing after a command.
    #[error("no packet after {command}")]
    NoReply {
        /// The command that went unanswered (`OPEN`).
        command: &'static str,
    },
    /// The link was lost right after both sides switched to a faster baud
    /// rate, which the robot may not manage.
    #[error("{lost} after switching to {baud} baud; if the robot cannot, set switch_to_baud: 0 in its model")]
    AfterBaudSwitch {
        /// The rate switched to.
        baud: u32,
        /// How the link was lost.
        lost: Box<LinkLoss>,
    },
    /// A topic the robot publishes on fell silent.
    #[error("no {what} on {topic} for {for_s:.2} s")]
    TopicSilent {
        /// What the topic carries (`odometry`).
        what: &'static str,
        /// The topic.
        topic: String,
        /// Seconds since its last message.
        for_s: f64,
    },
    /// A topic the robot should publish on was never heard.
    #[error("no {what} on {topic} within {within_s:.1} s: {diagnosis}")]
    TopicUnheard {
        /// What the topic carries (`odometry`).
        what: &'static str,
        /// The topic.
        topic: String,
        /// Seconds waited.
        within_s: f64,
        /// What discovery saw, as a sentence: a writer of another type, a
        /// QoS that cannot match, or nobody.
        diagnosis: String,
    },
    /// Sending to the robot failed.
    #[error("{what}: {source}")]
    SendFailed {
        /// What was being sent (`publishing /cmd_vel`).
        what: String,
        /// The middleware's error.
        source: Box<dyn Error + Send + Sync>,
    },
}

#[cfg(test)]
mod tests {
    use super::{LinkLoss, RobotError};

    #[test]
    fn a_lost_link_and_only_a_lost_link_may_be_reopened() {
        let lost = RobotError::from(LinkLoss::NoSensorData { for_s: 1.314 });
        assert!(lost.is_link_loss());
        assert_eq!(lost.to_string(), "robot disconnected: no sensor data for 1.31 s");
        assert!(RobotError::Io(std::io::ErrorKind::BrokenPipe.into()).is_link_loss());
        let camera = RobotError::Camera("an unreadable pair".into());
        assert!(!camera.is_link_loss());
        assert_eq!(camera.to_string(), "camera: an unreadable pair");
        let head = RobotError::PanTilt { unit: "/dev/ttyUSB1".into(), fault: "no reading yet".into() };
        assert!(!head.is_link_loss());
        assert_eq!(head.to_string(), "pan-tilt unit on /dev/ttyUSB1: no reading yet");
    }

    #[test]
    fn a_loss_after_a_baud_switch_says_how_to_avoid_it() {
        let lost = LinkLoss::AfterBaudSwitch { baud: 38400, lost: Box::new(LinkLoss::NoReply { command: "OPEN" }) };
        assert_eq!(
            lost.to_string(),
            "no packet after OPEN after switching to 38400 baud; if the robot cannot, set switch_to_baud: 0 in its model"
        );
    }
}
