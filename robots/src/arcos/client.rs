//! The client's side: connect to a Pioneer-family controller and drive it as
//! a [`Robot`].

use super::codec::{ClientCommand, Identity, Sip, StreamDecoder, Unwrapper};
use super::link::{is_timeout, Link};
use crate::model::RobotModel;
use crossbeam_channel::{Receiver, Sender};
use std::io::{self, Read};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use ubf_core::{Bumpers, Command, Limits, Pose2, RangeReading, Robot, RobotError, State, Turn};

/// How long to wait for each handshake reply.
const REPLY_TIMEOUT: Duration = Duration::from_millis(500);
/// Handshake attempts before giving up.
const ATTEMPTS: usize = 5;
/// Send a PULSE if nothing else was sent for this long (the watchdog bites
/// after about 2 s).
const PULSE_AFTER: Duration = Duration::from_millis(500);

/// An open session with a controller.
pub struct ArcosRobot {
    link: Box<dyn Link>,
    model: RobotModel,
    identity: Identity,
    /// SIPs with the moment they arrived.
    sips: Receiver<(Instant, Sip)>,
    stop_reader: Arc<AtomicBool>,
    reader: Option<JoinHandle<()>>,
    unwrapper: Unwrapper,
    latest: Option<Sip>,
    last_sip_at: Option<Instant>,
    last_sent: Instant,
    ranges: Vec<RangeReading>,
    /// Sonar channel number → position in `ranges`, built once.
    sonar_slot: [Option<usize>; 256],
    closed: bool,
}

fn send(link: &mut dyn Link, command: ClientCommand) -> Result<(), RobotError> {
    io::Write::write_all(link, &command.packet()).map_err(RobotError::from)
}

/// Waits for the next packet body, up to `timeout`.
fn next_body(
    link: &mut dyn Link,
    decoder: &mut StreamDecoder,
    timeout: Duration,
) -> Result<Option<Vec<u8>>, RobotError> {
    let deadline = Instant::now() + timeout;
    let mut buffer = [0u8; 256];
    loop {
        if let Some(body) = decoder.next_body() {
            return Ok(Some(body));
        }
        if Instant::now() >= deadline {
            return Ok(None);
        }
        match link.read(&mut buffer) {
            Ok(0) => return Err(RobotError::Disconnected("the link closed".into())),
            Ok(n) => decoder.push(&buffer[..n]),
            Err(e) if is_timeout(&e) => {}
            Err(e) => return Err(e.into()),
        }
    }
}

/// SYNC0, SYNC1, SYNC2 with their echoes; returns the robot's identity.
/// A SIP instead of an echo means the robot is still open from an earlier
/// session: CLOSE it and start again.
fn handshake(link: &mut dyn Link) -> Result<Identity, RobotError> {
    let mut decoder = StreamDecoder::new();
    'attempt: for _ in 0..ATTEMPTS {
        for (command, echo) in [(ClientCommand::Sync0, 0u8), (ClientCommand::Sync1, 1), (ClientCommand::Sync2, 2)] {
            send(link, command)?;
            let Some(body) = next_body(link, &mut decoder, REPLY_TIMEOUT)? else { continue 'attempt };
            match body.first() {
                Some(&first) if first == echo => {
                    if echo == 2 {
                        return Identity::parse(&body).map_err(|e| RobotError::Protocol(e.to_string()));
                    }
                }
                Some(0x32 | 0x33) => {
                    send(link, ClientCommand::Close)?;
                    std::thread::sleep(REPLY_TIMEOUT);
                    decoder = StreamDecoder::new();
                    continue 'attempt;
                }
                _ => continue 'attempt,
            }
        }
    }
    Err(RobotError::Disconnected(format!("no handshake after {ATTEMPTS} attempts")))
}

impl ArcosRobot {
    /// Connects over `link` to a robot of `model`: handshake, checks the
    /// robot's class and subclass against the model, OPEN, speed limits,
    /// then motors on unless `enable` is false (a dry run).
    pub fn connect(mut link: Box<dyn Link>, model: RobotModel, enable: bool) -> Result<ArcosRobot, RobotError> {
        let identity = handshake(link.as_mut())?;
        if !identity.class.eq_ignore_ascii_case(&model.class)
            || !identity.subclass.eq_ignore_ascii_case(&model.subclass)
        {
            return Err(RobotError::Protocol(format!(
                "the robot is a {} {} ({}), the configuration expects a {} {}",
                identity.class, identity.subclass, identity.name, model.class, model.subclass
            )));
        }
        send(link.as_mut(), ClientCommand::Open)?;
        send(link.as_mut(), ClientCommand::SetV((model.max_velocity * 1000.0).round() as u16))?;
        send(link.as_mut(), ClientCommand::SetRv(model.max_rot_velocity_deg.round() as u16))?;
        send(link.as_mut(), ClientCommand::Enable(enable))?;
        let (sender, sips) = crossbeam_channel::bounded(256);
        let stop_reader = Arc::new(AtomicBool::new(false));
        let reader_link = link.try_clone_link()?;
        let stop = Arc::clone(&stop_reader);
        let reader = std::thread::Builder::new()
            .name("arcos-reader".into())
            .spawn(move || read_sips(reader_link, sender, stop))
            .map_err(RobotError::Io)?;
        let ranges = model
            .sonar
            .iter()
            .map(|s| RangeReading { pose_robot_sensor: s.pose(), range: None, max_range: 5.0 })
            .collect();
        let mut sonar_slot = [None; 256];
        for (slot, unit) in model.sonar.iter().enumerate() {
            sonar_slot[usize::from(unit.index)] = Some(slot);
        }
        Ok(ArcosRobot {
            sonar_slot,
            link,
            model,
            identity,
            sips,
            stop_reader,
            reader: Some(reader),
            unwrapper: Unwrapper::default(),
            latest: None,
            last_sip_at: None,
            last_sent: Instant::now(),
            ranges,
            closed: false,
        })
    }

    /// Who the robot said it is.
    pub fn identity(&self) -> &Identity {
        &self.identity
    }

    /// The latest SIP, in robot units.
    pub fn latest_sip(&self) -> Option<&Sip> {
        self.latest.as_ref()
    }

    fn send(&mut self, command: ClientCommand) -> Result<(), RobotError> {
        self.last_sent = Instant::now();
        send(self.link.as_mut(), command)
    }

    /// Sends a PULSE if nothing has gone out for half a second.
    pub fn keep_alive(&mut self) -> Result<(), RobotError> {
        if self.last_sent.elapsed() >= PULSE_AFTER {
            self.send(ClientCommand::Pulse)?;
        }
        Ok(())
    }
}

/// The reader thread: packets into SIPs on a channel, until told to stop or
/// the link fails (then the channel closes and the robot sees a
/// disconnection).
fn read_sips(mut link: Box<dyn Link>, sender: Sender<(Instant, Sip)>, stop: Arc<AtomicBool>) {
    let mut decoder = StreamDecoder::new();
    let mut buffer = [0u8; 512];
    while !stop.load(Ordering::Relaxed) {
        match link.read(&mut buffer) {
            Ok(0) => return,
            Ok(n) => decoder.push(&buffer[..n]),
            Err(e) if is_timeout(&e) => continue,
            Err(_) => return,
        }
        while let Some(body) = decoder.next_body() {
            if let Ok(sip) = Sip::parse(&body) {
                if sender.send((Instant::now(), sip)).is_err() {
                    return;
                }
            }
        }
    }
}

impl Robot for ArcosRobot {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        let a = self.model.arcos;
        let mut disconnected = false;
        loop {
            match self.sips.try_recv() {
                Ok((arrived, sip)) => {
                    // Every SIP goes through the unwrapper, or a wrap between
                    // two ticks would be missed.
                    let (x, y) = self.unwrapper.update(sip.xpos, sip.ypos);
                    state.pose = Pose2::new(
                        x as f64 * a.dist_conv_factor / 1000.0,
                        y as f64 * a.dist_conv_factor / 1000.0,
                        f64::from(sip.thpos) * a.angle_conv_factor,
                    );
                    for &(channel, range) in &sip.sonar {
                        if let Some(i) = self.sonar_slot[usize::from(channel)] {
                            let metres = f64::from(range) * a.range_conv_factor / 1000.0;
                            self.ranges[i].range = (metres < self.ranges[i].max_range).then_some(metres);
                        }
                    }
                    self.latest = Some(sip);
                    self.last_sip_at = Some(arrived);
                }
                Err(crossbeam_channel::TryRecvError::Empty) => break,
                Err(crossbeam_channel::TryRecvError::Disconnected) => {
                    disconnected = true;
                    break;
                }
            }
        }
        let Some(sip) = &self.latest else {
            state.sensor_age = f64::INFINITY;
            return if disconnected { Err(RobotError::Disconnected("no SIP ever arrived".into())) } else { Ok(()) };
        };
        let (l, r) = (f64::from(sip.l_vel) * a.vel_conv_factor, f64::from(sip.r_vel) * a.vel_conv_factor);
        state.velocity = (l + r) / 2000.0;
        state.rot_velocity = match sip.tail.rot_vel {
            Some(tenths_deg) => (f64::from(tenths_deg) / 10.0).to_radians(),
            None => (r - l) / 2.0 * a.diff_conv_factor,
        };
        state.ranges.clone_from(&self.ranges);
        state.bumpers = Bumpers { front: sip.front_bumped(), rear: sip.rear_bumped() };
        state.stalled = sip.stalled();
        state.motors_enabled = sip.motors_enabled();
        state.estop = sip.estop();
        state.battery_volts = Some(sip.tail.battery_x10.map_or(f64::from(sip.battery) / 10.0, |b| f64::from(b) / 10.0));
        state.sensor_age = self.last_sip_at.map_or(f64::INFINITY, |t| t.elapsed().as_secs_f64());
        if disconnected {
            return Err(RobotError::Disconnected("the reader stopped: link lost".into()));
        }
        Ok(())
    }

    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        let limits = self.limits();
        match *command {
            Command::Stop => self.send(ClientCommand::Stop),
            Command::Drive { velocity, turn } => {
                let mm_s = (velocity.clamp(-limits.max_velocity, limits.max_velocity) * 1000.0).round() as i16;
                self.send(ClientCommand::Vel(mm_s))?;
                match turn {
                    Turn::Rate(rate) => {
                        let deg_s = rate.clamp(-limits.max_rot_velocity, limits.max_rot_velocity).to_degrees();
                        self.send(ClientCommand::RVel(deg_s.round() as i16))
                    }
                    Turn::Heading { heading, .. } => {
                        self.send(ClientCommand::Head(heading.to_degrees().round() as i16))
                    }
                }
            }
        }
    }

    fn shutdown(&mut self) -> Result<(), RobotError> {
        if self.closed {
            return Ok(());
        }
        self.closed = true;
        let result = self
            .send(ClientCommand::Stop)
            .and_then(|_| self.send(ClientCommand::Enable(false)))
            .and_then(|_| self.send(ClientCommand::Close));
        self.stop_reader.store(true, Ordering::Relaxed);
        if let Some(reader) = self.reader.take() {
            let _ = reader.join();
        }
        result
    }

    fn limits(&self) -> Limits {
        Limits::new(self.model.max_velocity, self.model.max_rot_velocity_deg.to_radians())
    }
}

impl Drop for ArcosRobot {
    /// A session is never left open: motors off and CLOSE, even on a panic.
    fn drop(&mut self) {
        let _ = self.shutdown();
    }
}
