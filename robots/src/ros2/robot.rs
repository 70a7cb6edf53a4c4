//! [`Ros2Robot`]: a ROS 2 robot driven through `/cmd_vel`, sensed through
//! `/odom` and `/scan`.

use super::cmd_vel::{self, CmdVel, Ros2EmergencyStop};
use super::config::{Ros2Config, ScanMount};
use super::msg::{LaserScan, Odometry, RosMessage, TFMessage, Twist, TwistStamped};
use super::node::{domain_from_env, Node, Publisher, Qos, Subscription};
use super::transforms::{placed, said, PublishedMounts};
use super::world_frame;
use std::sync::Arc;
use std::time::{Duration, Instant};
use ubf_core::{angle_difference, Command, Limits, LinkLoss, Pose2, RangeReading, Robot, RobotError, State, Turn};

/// Odometry (and a scan) older than this many control periods is a lost
/// link: the robot is sent a zero twist at once.
const STALE_PERIODS: f64 = 3.0;

/// How often, during a drive, discovery is looked at for the readers of
/// the commands: a base whose reader came late, of the other type, is
/// found within this.
const READERS_CHECKED_EVERY: Duration = Duration::from_secs(1);

/// A scan older than this, once scans have come, is a lost sensor: the
/// robot is stopped rather than steered by what the scanner saw last.
const STALE_SCAN: Duration = Duration::from_secs(1);

/// Turn rate per radian of heading error for heading commands, 1/s: a ROS
/// 2 base takes rates only.
const HEADING_GAIN: f64 = 2.0;

/// A ROS 2 robot. Its pose is odometry's, re-based so that the robot
/// stands at the `origin` given to [`Ros2Robot::connect`]: the frame of a
/// drive's goal is where the robot stood when the drive began.
pub struct Ros2Robot {
    config: Ros2Config,
    /// Shared with the robot's [`Ros2EmergencyStop`]s: one writer, so that
    /// the base hears their zero twists in order with the loop's.
    cmd_vel: Arc<CmdVel>,
    odom: Subscription<Odometry>,
    scan: Subscription<LaserScan>,
    mounts: ScanMounts,
    limits: Limits,
    stale_after: Duration,
    /// Odometry's first pose and the world pose it stands for.
    first_odom: Pose2,
    origin: Pose2,
    latest_odom: (Odometry, Instant),
    /// The last usable scan, where its scanner sat, and when it came.
    latest_scan: Option<(LaserScan, ScanMount, Instant)>,
    /// Why the scans have said nothing of obstacles, since when: each is
    /// taken as no scan, so that the robot stops as for a silent scanner
    /// if no usable one follows.
    unusable_scans: Option<(String, Instant)>,
    /// Whether the reason kept in `unusable_scans` has been said.
    unusable_said: bool,
    /// When the readers of the commands were last looked at.
    readers_checked_at: Instant,
    /// Publishes where the drive's world frame sits in the robot's
    /// odometry frame, for as long as the robot is driven.
    _world_in_odom: Publisher<TFMessage>,
    stopped: bool,
    /// Last, so that it is dropped after its readers and writer.
    node: Node,
}

impl Ros2Robot {
    /// Joins the robot's DDS domain and waits for its first odometry. The
    /// robot's pose then reads `origin`. A wait that times out says what
    /// discovery saw: a topic of another type, or a QoS that cannot match.
    pub fn connect(config: &Ros2Config, limits: Limits, period_s: f64, origin: Pose2) -> Result<Ros2Robot, RobotError> {
        let domain = match config.domain_id {
            Some(domain) => domain,
            None => domain_from_env()?,
        };
        let mut node = Node::join(domain, &config.namespace)?;
        // A type written is sent at once, so that the robot's reader has
        // matched the writer by the first odometry; one read off the robot
        // once its odometry (and so its driver) has been heard, and its
        // first commands may then go unheard until the reader matches: a
        // tick or two, while a drive starts from rest.
        let written = config.cmd_vel_stamped.map(|stamped| CmdVel::new(&node, config, stamped)).transpose()?;
        let mut odom = node.reader::<Odometry>(&config.odom, config.odom_qos)?.single_writer();
        let mut scan = node.reader::<LaserScan>(&config.scan, config.scan_qos)?.single_writer();
        let mut mounts = ScanMounts::new(config, &node)?;
        let deadline = Instant::now() + config.connect_timeout();
        let first = loop {
            if let Some(odometry) = odom.take_latest()? {
                usable_odometry(&odometry, odom.topic())?;
                break odometry;
            }
            if Instant::now() >= deadline {
                let topic = node.resolve(&config.odom);
                let diagnosis = odom
                    .unreadable()
                    .map(|why| format!("what came on {topic} {why}"))
                    .or_else(|| node.why_unheard::<Odometry>(&config.odom, config.odom_qos))
                    .or_else(|| cmd_vel::why_unread(&mut node, config, sent_as(config.cmd_vel_stamped)))
                    .unwrap_or_else(|| {
                        format!(
                            "nothing was published on {topic} in domain {domain}: is the robot's driver running, in \
                             this ROS_DOMAIN_ID, publishing nav_msgs/msg/Odometry?"
                        )
                    });
                let within_s = config.connect_timeout_s;
                return Err(LinkLoss::TopicUnheard { what: "odometry", topic, within_s, diagnosis }.into());
            }
            node.watch_discovery();
            std::thread::sleep(Duration::from_millis(10));
        };
        let cmd_vel = match written {
            Some(written) => written,
            None => {
                let stamped = cmd_vel::choose_stamped(&mut node, config)?;
                CmdVel::new(&node, config, stamped)?
            }
        };
        commands_read(&mut node, config, &cmd_vel)?;
        // A scan nobody can hear is said, not left to look like open space.
        if let Some(why) = node.why_unheard::<LaserScan>(&config.scan, config.scan_qos) {
            tracing::warn!("{why}; AvoidCollision sees no scan");
        }
        let latest_scan = first_scan(&mut node, &mut scan, &mut mounts, config)?;
        let first_odom = first.pose.pose.to_pose2();
        let world_in_odom = node.writer::<TFMessage>(&config.tf_static, Qos::Latched)?;
        world_in_odom.publish(world_frame::in_odom(&first, origin, &config.namespace))?;
        Ok(Ros2Robot {
            node,
            config: config.clone(),
            cmd_vel: Arc::new(cmd_vel),
            odom,
            scan,
            mounts,
            limits,
            stale_after: Duration::from_secs_f64(STALE_PERIODS * period_s),
            first_odom,
            origin,
            latest_odom: (first, Instant::now()),
            latest_scan,
            unusable_scans: None,
            unusable_said: false,
            readers_checked_at: Instant::now(),
            _world_in_odom: world_in_odom,
            stopped: false,
        })
    }

    /// The DDS domain joined.
    pub fn domain(&self) -> u16 {
        self.node.domain()
    }

    /// What the operator should know of how the robot is driven and read:
    /// the commands' type, and where the scanner was found to sit.
    pub fn describe(&self) -> String {
        let commands = if self.cmd_vel.stamped() { TwistStamped::NAME } else { Twist::NAME };
        let scanner = match (&self.latest_scan, &self.mounts) {
            (None, _) => "no scan yet".to_owned(),
            (Some((_, mount, _)), ScanMounts::Written(_)) => format!("scanner at {} (`scan_mount`)", placed(mount)),
            (Some((scan, mount, _)), ScanMounts::Published(mounts)) => {
                format!("scanner ({}) at {}, by {}", said(&scan.header.frame_id), placed(mount), mounts.topic())
            }
        };
        format!("commands as {commands}, {scanner}")
    }

    /// The pose odometry gives, in the drive's world frame.
    fn world_pose(&self, odometry: &Odometry) -> Pose2 {
        world_frame::world_pose(&odometry.pose.pose.to_pose2(), &self.first_odom, &self.origin)
    }

    /// A handle that stops the robot from another thread (Ctrl-C) even
    /// while this one is busy.
    pub fn emergency_stop(&self) -> Ros2EmergencyStop {
        Ros2EmergencyStop { cmd_vel: Arc::clone(&self.cmd_vel) }
    }

    /// Publishes `twist`, or a zero twist once the robot has been halted.
    fn publish(&mut self, twist: Twist) -> Result<(), RobotError> {
        self.stopped = self.cmd_vel.publish(twist)? == Twist::default();
        Ok(())
    }

    /// Sends a zero twist and says why the link is lost: `topic`, which
    /// carries `what`, has been silent for `silent`.
    fn lost(&mut self, what: &'static str, topic: &str, silent: Duration) -> RobotError {
        let _ = self.publish(Twist::default());
        LinkLoss::TopicSilent { what, topic: self.node.resolve(topic), for_s: silent.as_secs_f64() }.into()
    }
}

/// What commands of a type written (or not) go as.
fn sent_as(stamped: Option<bool>) -> cmd_vel::Sent {
    match stamped {
        Some(true) => cmd_vel::Sent::Stamped,
        Some(false) => cmd_vel::Sent::Twist,
        None => cmd_vel::Sent::Either,
    }
}

/// Refuses commands that nothing reads (every reader of them reads another
/// type): the robot would never move, and the drive would seem to run. A
/// type read off the robot is a lost link, so that a reconnection reads it
/// again (a controller that came up late); a type written is a fault.
fn commands_read(node: &mut Node, config: &Ros2Config, cmd_vel: &CmdVel) -> Result<(), RobotError> {
    let Some(why) = cmd_vel::why_unread(node, config, sent_as(Some(cmd_vel.stamped()))) else { return Ok(()) };
    let what = format!("publishing {}", node.resolve(&config.cmd_vel));
    Err(match config.cmd_vel_stamped {
        Some(_) => RobotError::Protocol { what, source: why.into() },
        None => LinkLoss::SendFailed { what, source: why.into() }.into(),
    })
}

/// Refuses odometry that is no pose (on `topic`), which steered by would
/// send the robot anywhere.
fn usable_odometry(odometry: &Odometry, topic: &str) -> Result<(), RobotError> {
    match odometry.pose.pose.why_unusable() {
        Some(why) => Err(RobotError::Protocol { what: format!("the odometry on {topic}"), source: why.into() }),
        None => Ok(()),
    }
}

/// Where the scanner sits: as the robot file writes it, or where the
/// robot's static transforms put the frame each scan names.
enum ScanMounts {
    Written(ScanMount),
    /// Boxed: a reader is large beside a written mount.
    Published(Box<PublishedMounts>),
}

impl ScanMounts {
    fn new(config: &Ros2Config, node: &Node) -> Result<ScanMounts, RobotError> {
        Ok(match config.scan_mount {
            Some(mount) => ScanMounts::Written(mount),
            None => ScanMounts::Published(Box::new(PublishedMounts::new(config, node)?)),
        })
    }

    /// Takes in the static transforms published since the last call.
    fn update(&mut self) -> Result<(), RobotError> {
        match self {
            ScanMounts::Written(_) => Ok(()),
            ScanMounts::Published(mounts) => mounts.update(),
        }
    }

    /// Where `scan`'s scanner sits, or why the scan says nothing of
    /// obstacles: its own fault, or a scanner whose place is not known.
    fn usable(&mut self, scan: &LaserScan) -> Result<ScanMount, String> {
        if let Some(why) = scan.why_unusable() {
            return Err(why);
        }
        match self {
            ScanMounts::Written(mount) => Ok(*mount),
            ScanMounts::Published(mounts) => mounts.of(&scan.header.frame_id),
        }
    }
}

/// How long after the first odometry discovery may take to show the
/// robot's scanner, if it has one.
const SCANNER_SEEN_WITHIN: Duration = Duration::from_millis(300);

/// The robot's first scan and where its scanner sits: waited for (a
/// second, if discovery shows a scanner) and its mount looked up (within
/// the connect timeout), so that the robot never moves by a scan read from
/// the wrong place. No scan within a second, or a first scan that says
/// nothing of obstacles, is left to [`Robot::sense`].
fn first_scan(
    node: &mut Node,
    scan: &mut Subscription<LaserScan>,
    mounts: &mut ScanMounts,
    config: &Ros2Config,
) -> Result<Option<(LaserScan, ScanMount, Instant)>, RobotError> {
    let started = Instant::now();
    let mount_deadline = started + config.connect_timeout();
    // The scan, and when it came: a scanner silent since is stale from then.
    let mut first: Option<(LaserScan, Instant)> = None;
    loop {
        mounts.update()?;
        if let Some(scan) = scan.take_latest()? {
            first = Some((scan, Instant::now()));
        }
        let now = Instant::now();
        match &first {
            // No scanner seen by discovery in the time its endpoints take
            // to come (a robot without one), or one silent for a second
            // (left to `sense`).
            None if now - started >= SCANNER_SEEN_WITHIN && !node.has_writer(&config.scan) => return Ok(None),
            None if now - started >= STALE_SCAN => return Ok(None),
            None => {}
            Some((taken, _)) if taken.why_unusable().is_some() => return Ok(None),
            Some((taken, _)) => match mounts.usable(taken) {
                Ok(mount) => return Ok(first.map(|(scan, at)| (scan, mount, at))),
                Err(why) if now >= mount_deadline => {
                    return Err(RobotError::Protocol {
                        what: format!("the scan on {}", scan.topic()),
                        source: why.into(),
                    })
                }
                Err(_) => {}
            },
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The most readings a scan is taken as. Every reading is copied into each
/// log's buffers every tick: a scan of a million beams once took memory
/// at 1.5 GB/s. Scanners give a few thousand beams at most (1081 a
/// Hokuyo's 270° at 0.25°, 3600 a full turn at 0.1°).
const MOST_READINGS: usize = 4096;

/// A scan's beams as range readings from the scanner at `mount`. A scan
/// of more beams than
/// [`MOST_READINGS`] is taken in runs of neighbouring beams, one reading
/// a run: its nearest echo, where it was, which is what keeps the robot
/// off obstacles.
fn ranges_of(scan: &LaserScan, mount: &ScanMount, ranges: &mut Vec<RangeReading>) {
    ranges.clear();
    let max_range = f64::from(scan.range_max);
    let echo = |range: f32| (range.is_finite() && range >= scan.range_min && range < scan.range_max).then_some(range);
    let (beams, readings) = (scan.ranges.len(), scan.ranges.len().min(MOST_READINGS));
    for k in 0..readings {
        // Runs as even as whole beams allow: 4097 beams are 4096 readings.
        let first = k * beams / readings;
        let run = &scan.ranges[first..(k + 1) * beams / readings];
        let nearest =
            run.iter().enumerate().filter_map(|(i, &r)| Some((i, echo(r)?))).min_by(|a, b| a.1.total_cmp(&b.1));
        let (i, range) = match nearest {
            Some((i, range)) => (i, Some(f64::from(range))),
            None => (run.len() / 2, None),
        };
        let angle = f64::from(scan.angle_min) + (first + i) as f64 * f64::from(scan.angle_increment);
        ranges.push(RangeReading { pose_robot_sensor: mount.beam(angle), range, max_range });
    }
}

impl Robot for Ros2Robot {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        let now = Instant::now();
        if now - self.readers_checked_at >= READERS_CHECKED_EVERY {
            self.readers_checked_at = now;
            if let Err(unread) = commands_read(&mut self.node, &self.config, &self.cmd_vel) {
                let _ = self.publish(Twist::default());
                return Err(unread);
            }
        }
        if let Some(odometry) = self.odom.take_latest()? {
            usable_odometry(&odometry, self.odom.topic())?;
            let (last, at) = &self.latest_odom;
            let (from, to) = (last.pose.pose.position, odometry.pose.pose.position);
            let metres = (to.x - from.x).hypot(to.y - from.y);
            // Over the longer of the gaps they were taken and stamped at:
            // messages delayed in delivery, or from a simulation faster
            // than real time, arrive closer together than they were made.
            let stamped = odometry.header.stamp.seconds() - last.header.stamp.seconds();
            let seconds = (now - *at).as_secs_f64().max(if last.header.stamp.sec > 0 { stamped } else { 0.0 });
            if let Some(jump) = LinkLoss::impossible_motion(metres, seconds) {
                return Err(jump.into());
            }
            self.latest_odom = (odometry, now);
        }
        let age = now - self.latest_odom.1;
        if age > self.stale_after {
            if let Some(why) = self.odom.unreadable() {
                tracing::warn!("the odometry on {}: it {why}", self.odom.topic());
            }
            let topic = self.config.odom.clone();
            return Err(self.lost("odometry", &topic, age));
        }
        // A scan that cannot be read, like one that says nothing of
        // obstacles or whose scanner's place is not known, is taken as no
        // scan: the robot stops as for a silent scanner if no usable one
        // follows.
        self.mounts.update()?;
        let mounted = match self.scan.take_latest()? {
            Some(scan) => Some(self.mounts.usable(&scan).map(|mount| (scan, mount))),
            // Said once: the reason kept stands until a usable scan comes.
            None if self.unusable_scans.is_some() => None,
            None => self.scan.unreadable().map(|why| Err(format!("it {why}"))),
        };
        match mounted {
            Some(Err(why)) => {
                let since = self.unusable_scans.take().map_or(now, |(_, since)| since);
                self.unusable_scans = Some((why, since));
            }
            Some(Ok((scan, mount))) => {
                self.unusable_scans = None;
                self.unusable_said = false;
                self.latest_scan = Some((scan, mount, now));
            }
            None => {}
        }
        // Since the last usable scan, or the first scan if none was.
        let usable_since = self.latest_scan.as_ref().map(|(_, _, at)| *at);
        let since = usable_since.or(self.unusable_scans.as_ref().map(|(_, since)| *since));
        if let Some(since) = since.filter(|since| now - *since > STALE_SCAN.max(self.stale_after)) {
            let topic = self.config.scan.clone();
            let what = match &self.unusable_scans {
                Some((why, _)) => {
                    if !std::mem::replace(&mut self.unusable_said, true) {
                        tracing::warn!("the scan on {}: {why}", self.scan.topic());
                    }
                    "usable scan"
                }
                None => "scan",
            };
            return Err(self.lost(what, &topic, now - since));
        }
        match &self.latest_scan {
            Some((scan, mount, _)) => ranges_of(scan, mount, &mut state.ranges),
            None => state.ranges.clear(),
        }
        let odometry = &self.latest_odom.0;
        state.pose = self.world_pose(odometry);
        state.odometry = state.pose;
        state.velocity = odometry.twist.twist.linear.x;
        state.rot_velocity = odometry.twist.twist.angular.z;
        state.sensor_age = age.as_secs_f64();
        state.motors_enabled = true;
        Ok(())
    }

    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        let twist = match *command {
            Command::Stop => Twist::default(),
            Command::Drive { velocity, turn: Turn::Rate(rate) } => Twist::planar(velocity, rate),
            Command::Drive { velocity, turn: Turn::Heading { heading, max_rate } } => {
                let error = angle_difference(heading, self.world_pose(&self.latest_odom.0).theta);
                Twist::planar(velocity, (HEADING_GAIN * error).clamp(-max_rate, max_rate))
            }
        };
        self.publish(twist)
    }

    /// Sends a zero twist and waits (briefly) for the robot's driver to
    /// acknowledge it: a writer that leaves first may take it along.
    fn shutdown(&mut self) -> Result<(), RobotError> {
        self.publish(Twist::default())?;
        self.cmd_vel.await_acknowledgement();
        Ok(())
    }

    fn limits(&self) -> Limits {
        self.limits
    }
}

impl Drop for Ros2Robot {
    /// A robot dropped while moving (a panic on the way out) is stopped.
    fn drop(&mut self) {
        if !self.stopped {
            let _ = self.shutdown();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(ranges: Vec<f32>) -> LaserScan {
        let increment = std::f32::consts::TAU / ranges.len() as f32;
        LaserScan {
            angle_min: -3.0,
            angle_increment: increment,
            range_min: 0.1,
            range_max: 30.0,
            ranges,
            ..Default::default()
        }
    }

    #[test]
    fn a_scanner_s_beams_are_taken_one_for_one() {
        let mut beams = vec![5.0; 1081];
        (beams[3], beams[4]) = (f32::NAN, 0.05);
        let (scan, mut ranges) = (scan(beams), Vec::new());
        ranges_of(&scan, &ScanMount::default(), &mut ranges);
        assert_eq!(ranges.len(), 1081);
        assert_eq!((ranges[2].range, ranges[3].range, ranges[4].range), (Some(5.0), None, None));
        let bearing = -3.0 + 700.0 * f64::from(scan.angle_increment);
        assert!((ranges[700].pose_robot_sensor.theta - bearing).abs() < 1e-12);
    }

    #[test]
    fn a_scanner_off_the_centre_reads_from_where_it_sits() {
        // Four beams a quarter turn apart, from angle 0.
        let mut four = scan(vec![1.0, 2.0, 3.0, 4.0]);
        four.angle_min = 0.0;
        let mut ranges = Vec::new();
        let ahead = ScanMount { x: 0.3, y: -0.1, heading_deg: 90.0, upside_down: false };
        ranges_of(&four, &ahead, &mut ranges);
        let quarter = std::f64::consts::FRAC_PI_2;
        let sensor = ranges[1].pose_robot_sensor;
        assert_eq!((sensor.x, sensor.y), (0.3, -0.1));
        assert!((sensor.theta - 2.0 * quarter).abs() < 1e-6, "{sensor:?}");
        // Upside down, its angles run clockwise.
        ranges_of(&four, &ScanMount { upside_down: true, ..ScanMount::default() }, &mut ranges);
        assert!((ranges[1].pose_robot_sensor.theta + quarter).abs() < 1e-6);
        assert_eq!(ranges[1].range, Some(2.0));
    }

    #[test]
    fn a_scan_of_more_beams_than_the_most_readings_is_taken_as_that_many() {
        let mut ranges = Vec::new();
        for beams in [MOST_READINGS, MOST_READINGS + 1, 2 * MOST_READINGS - 1] {
            ranges_of(&scan(vec![5.0; beams]), &ScanMount::default(), &mut ranges);
            assert_eq!(ranges.len(), MOST_READINGS, "{beams} beams");
        }
    }

    #[test]
    fn a_scan_of_a_million_beams_keeps_each_run_s_nearest_echo() {
        let mut beams = vec![5.0; 1_000_000];
        beams[123_456] = 0.7;
        beams[600_000..600_600].fill(f32::INFINITY);
        let (scan, mut ranges) = (scan(beams), Vec::new());
        ranges_of(&scan, &ScanMount::default(), &mut ranges);
        assert_eq!(ranges.len(), MOST_READINGS);
        let nearest = ranges.iter().min_by(|a, b| a.range.unwrap_or(99.0).total_cmp(&b.range.unwrap_or(99.0))).unwrap();
        assert_eq!(nearest.range, Some(f64::from(0.7f32)));
        // Where that beam points, not the middle of its run.
        let bearing = -3.0 + 123_456.0 * f64::from(scan.angle_increment);
        assert!((nearest.pose_robot_sensor.theta - bearing).abs() < 1e-9);
        // A run with no echo reads none.
        assert!(ranges.iter().any(|r| r.range.is_none()));
    }
}
