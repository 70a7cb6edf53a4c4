//! The client's side: connect to a Pioneer-family controller and drive it as
//! a [`Robot`].

use super::codec::{baud_code, ClientCommand, ConfigPacket, Identity, Sip, StreamDecoder, Unwrapper, CONFIG_TYPE};
use super::link::{is_timeout, Link};
use crate::emergency::EmergencyStop;
use crate::model::RobotModel;
use std::io::{self, Read};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use ubf_core::{Bumpers, Command, Limits, LinkLoss, Pose2, RangeReading, Robot, RobotError, State, Turn};

/// How long to wait for each handshake reply.
const REPLY_TIMEOUT: Duration = Duration::from_millis(500);
/// Handshake attempts before giving up.
const ATTEMPTS: usize = 5;
/// Send a PULSE if nothing else was sent for this long (the watchdog bites
/// after about 2 s).
const PULSE_AFTER: Duration = Duration::from_millis(500);

/// The speeds below which a stopping robot counts as stopped, so its
/// motors may be switched off: mm/s and °/s.
const STOPPED_MM_S: f64 = 20.0;
const STOPPED_DEG_S: f64 = 3.0;
/// Decelerations assumed when the controller reports none: slower than any
/// Pioneer-family default, so the wait errs long. mm/s² and °/s².
const CAUTIOUS_DECEL_MM_S2: f64 = 200.0;
const CAUTIOUS_ROT_DECEL_DEG_S2: f64 = 50.0;
/// Longest braking time allowed for, s: a robot still moving after this is
/// not braking and its motors go off anyway.
const MOST_BRAKING_S: f64 = 10.0;

/// How long to wait for the CONFIG reply.
const CONFIG_TIMEOUT: Duration = Duration::from_secs(1);

/// Accelerations to set on the controller (SETA, SETRA), the same for
/// speeding up and slowing down.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Accelerations {
    /// Translational, m/s²: > 0, at most 10.
    #[serde(deserialize_with = "translation_m_s2")]
    pub translation: f64,
    /// Rotational, °/s²: > 0, at most 3600.
    #[serde(deserialize_with = "ubf_core::config::rate_deg_s")]
    pub rotation_deg: f64,
}

/// A translational acceleration, m/s²: above 0, at most 10 (1 g).
fn translation_m_s2<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    ubf_core::config::number_in(d, f64::MIN_POSITIVE..=10.0, "> 0 and at most 10 m/s²")
}

/// How to open a session.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConnectOptions {
    /// Whether to switch the motors on (off for a dry run).
    pub enable_motors: bool,
    /// Caps on translational and rotational speed, m/s and °/s, below the
    /// model's and the controller's tops; sent as SETV and SETRV.
    pub max_velocity: Option<f64>,
    /// See `max_velocity`.
    pub max_rot_velocity_deg: Option<f64>,
    /// Accelerations to set; the controller's own otherwise.
    pub accelerations: Option<Accelerations>,
    /// The pose, in the caller's world frame, that the robot's first SIP
    /// stands for: the origin for a first session, the last known pose when
    /// a lost session is reopened, so that goals keep their meaning.
    pub origin: Pose2,
    /// Margin, after STOP, beyond the time the robot needs to brake from
    /// its speed at the controller's deceleration, to wait for it to report
    /// standstill before its motors are switched off.
    pub standstill_wait: Duration,
}

impl Default for ConnectOptions {
    /// Motors on, the controller's limits and accelerations, the world
    /// frame at the robot, a 1 s margin on the braking time.
    fn default() -> Self {
        ConnectOptions {
            enable_motors: true,
            max_velocity: None,
            max_rot_velocity_deg: None,
            accelerations: None,
            origin: Pose2::default(),
            standstill_wait: Duration::from_secs(1),
        }
    }
}

/// What the reader thread leaves for the control loop: the latest SIP
/// (its sonar moved into `ranges_mm`), the odometry unwrapped over every
/// SIP, and when it came. The reader only ever overwrites it, so it never
/// waits for the control loop, however fast SIPs come.
#[derive(Debug, Default)]
struct Latest {
    sip: Option<Sip>,
    /// Unwrapped position, position units since the first SIP.
    position: (i64, i64),
    arrived: Option<Instant>,
    /// Latest range per sonar slot of the model, range units.
    ranges_mm: Vec<Option<u16>>,
    /// How the link ended, if it did.
    ended: Option<Ended>,
}

/// How the reader's link ended: the reason kept for every later tick that
/// asks (a [`LinkLoss`] holds errors that cannot be copied).
#[derive(Clone, Copy, Debug)]
enum Ended {
    /// The other end closed it.
    Closed,
    /// A read failed with this kind of error.
    Failed(io::ErrorKind),
    /// The odometry jumped this far (m) between SIPs this far apart (s).
    Jumped(f64, f64),
}

impl From<Ended> for LinkLoss {
    fn from(ended: Ended) -> Self {
        match ended {
            Ended::Closed => LinkLoss::Closed,
            Ended::Failed(kind) => LinkLoss::ReadFailed(kind),
            Ended::Jumped(metres, seconds) => LinkLoss::ImpossibleMotion { metres, seconds },
        }
    }
}

/// What a signal handler stops an ARCOS robot with while the control loop
/// is busy or stuck: its own handle on the link, and the session's halt.
pub struct ArcosEmergencyStop {
    link: Mutex<Box<dyn Link>>,
    halt: Arc<Halt>,
}

/// A session told to stop moving from outside its control loop: once set,
/// every motion command goes out as STOP. The lock orders the loop's
/// commands and the halt's STOP on the link, so no command the loop had
/// under way can follow the STOP.
#[derive(Default)]
struct Halt {
    lock: Mutex<()>,
    halted: AtomicBool,
}

impl EmergencyStop for ArcosEmergencyStop {
    /// Sends STOP now and holds the robot still: the control loop's motion
    /// commands go out as STOP from here on.
    fn halt(&self) -> Result<(), RobotError> {
        let _order = self.halt.lock.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        self.halt.halted.store(true, Ordering::SeqCst);
        let mut link = self.link.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        send(link.as_mut(), ClientCommand::Stop)
    }

    /// Sends STOP, ENABLE 0 and CLOSE at once, without waiting for
    /// standstill.
    fn stop_now(&self) -> Result<(), RobotError> {
        self.halt.halted.store(true, Ordering::SeqCst);
        let mut link = self.link.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        for command in [ClientCommand::Stop, ClientCommand::Enable(false), ClientCommand::Close] {
            send(link.as_mut(), command)?;
        }
        Ok(())
    }

    fn stop_now_sends(&self) -> String {
        "STOP, ENABLE 0 and CLOSE".to_owned()
    }
}

/// An open session with a controller.
pub struct ArcosRobot {
    link: Box<dyn Link>,
    model: RobotModel,
    identity: Identity,
    /// The controller's CONFIG reply, if it sent one.
    config: Option<ConfigPacket>,
    /// The model's limits, lowered to the controller's tops and the caps.
    limits: Limits,
    latest: Arc<Mutex<Latest>>,
    stop_reader: Arc<AtomicBool>,
    reader: Option<JoinHandle<()>>,
    /// The latest SIP as copied by `sense`.
    sip: Option<Sip>,
    last_sip_at: Option<Instant>,
    last_sent: Instant,
    ranges: Vec<RangeReading>,
    /// Maps the controller's odometry (relative to its first SIP's
    /// position, with its own heading) into the caller's world frame.
    to_world: Option<Pose2>,
    origin: Pose2,
    /// The rotational speed limit last sent (SETRV), °/s.
    rot_limit_sent: u16,
    standstill_wait: Duration,
    /// Set from outside the control loop ([`ArcosEmergencyStop`]).
    halt: Arc<Halt>,
    /// The decelerations this session set, if any: mm/s² and °/s².
    decelerations_set: Option<(f64, f64)>,
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
            Ok(0) => return Err(LinkLoss::Closed.into()),
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
                        return Identity::parse(&body)
                            .map_err(|e| RobotError::Protocol { what: "the SYNC2 reply".into(), source: Box::new(e) });
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
    Err(LinkLoss::NoHandshake { attempts: ATTEMPTS }.into())
}

/// HOSTBAUD: tells the controller to switch to `baud`, lets the packet
/// drain at the old rate, then follows on this side. Only on a serial line.
fn switch_baud(link: &mut dyn Link, baud: u32) -> Result<(), RobotError> {
    let code = baud_code(baud).ok_or_else(|| RobotError::Setting {
        setting: "switch_to_baud",
        value: baud.to_string(),
        expected: "a rate the controller offers (9600, 19200, 38400, 57600 or 115200), or 0 to stay at `baud`",
    })?;
    send(link, ClientCommand::HostBaud(code))?;
    std::thread::sleep(Duration::from_millis(50));
    link.set_baud(baud).map_err(RobotError::from)
}

/// Asks for CONFIG and waits for it, passing over the SIPs that OPEN
/// started. `Ok(None)` if SIPs come but no CONFIG (not every simulator
/// answers it); an error if nothing comes at all.
fn request_config(link: &mut dyn Link) -> Result<Option<ConfigPacket>, RobotError> {
    send(link, ClientCommand::Config)?;
    let mut decoder = StreamDecoder::new();
    let deadline = Instant::now() + CONFIG_TIMEOUT;
    let mut heard = false;
    while let Some(body) = next_body(link, &mut decoder, deadline.saturating_duration_since(Instant::now()))? {
        heard = true;
        if body.first() == Some(&CONFIG_TYPE) {
            return ConfigPacket::parse(&body)
                .map(Some)
                .map_err(|e| RobotError::Protocol { what: "CONFIG".into(), source: Box::new(e) });
        }
    }
    if heard {
        Ok(None)
    } else {
        Err(LinkLoss::NoReply { command: "OPEN" }.into())
    }
}

impl ArcosRobot {
    /// Connects over `link` to a robot of `model`: handshake; the robot's
    /// class and subclass checked against the model; the baud switch the
    /// model asks for (serial lines only); OPEN; CONFIG, whose top speeds
    /// lower the model's limits; SETV, SETRV and any accelerations; then
    /// motors on unless the options say otherwise (a dry run).
    pub fn connect(
        mut link: Box<dyn Link>,
        model: RobotModel,
        options: &ConnectOptions,
    ) -> Result<ArcosRobot, RobotError> {
        let identity = handshake(link.as_mut())?;
        if !identity.class.eq_ignore_ascii_case(&model.class)
            || !identity.subclass.eq_ignore_ascii_case(&model.subclass)
        {
            return Err(RobotError::WrongRobot {
                found: format!("{} {} ({})", identity.class, identity.subclass, identity.name),
                expected: format!("{} {}", model.class, model.subclass),
            });
        }
        let target = model.arcos.switch_to_baud;
        let switched = match link.baud() {
            Some(current) if target != 0 && target != current => {
                switch_baud(link.as_mut(), target)?;
                true
            }
            _ => false,
        };
        send(link.as_mut(), ClientCommand::Open)?;
        let config = request_config(link.as_mut()).map_err(|e| match e {
            RobotError::Disconnected { reason } if switched => {
                LinkLoss::AfterBaudSwitch { baud: target, lost: Box::new(reason) }.into()
            }
            e => e,
        })?;
        let mut limits = Limits::new(model.max_velocity, model.max_rot_velocity_deg.to_radians());
        if let Some(cap) = options.max_velocity {
            limits.max_velocity = limits.max_velocity.min(cap);
        }
        if let Some(cap) = options.max_rot_velocity_deg {
            limits.max_rot_velocity = limits.max_rot_velocity.min(cap.to_radians());
        }
        if let Some(c) = &config {
            // The controller's tops bound whatever the model file says.
            if c.trans_vel_top > 0 {
                limits.max_velocity = limits.max_velocity.min(f64::from(c.trans_vel_top) / 1000.0);
            }
            if c.rot_vel_top > 0 {
                limits.max_rot_velocity = limits.max_rot_velocity.min(f64::from(c.rot_vel_top).to_radians());
            }
        } else {
            tracing::warn!("{}: no CONFIG reply; using the model's limits", identity.name);
        }
        send(link.as_mut(), ClientCommand::SetV((limits.max_velocity * 1000.0).round() as u16))?;
        let rot_limit_sent = limits.max_rot_velocity.to_degrees().round() as u16;
        send(link.as_mut(), ClientCommand::SetRv(rot_limit_sent))?;
        let mut decelerations_set = None;
        if let Some(a) = options.accelerations {
            let top = |top: Option<i16>| top.filter(|&t| t > 0).map_or(f64::from(i16::MAX), f64::from);
            let mm_s2 = (a.translation * 1000.0).min(top(config.as_ref().map(|c| c.trans_acc_top))).round() as i16;
            let deg_s2 = a.rotation_deg.min(top(config.as_ref().map(|c| c.rot_acc_top))).round() as i16;
            decelerations_set = Some((f64::from(mm_s2), f64::from(deg_s2)));
            for command in [
                ClientCommand::SetA(mm_s2),
                ClientCommand::SetA(-mm_s2),
                ClientCommand::SetRa(deg_s2),
                ClientCommand::SetRa(-deg_s2),
            ] {
                send(link.as_mut(), command)?;
            }
        }
        send(link.as_mut(), ClientCommand::Enable(options.enable_motors))?;
        let mut sonar_slot = [None; 256];
        for (slot, unit) in model.sonar.iter().enumerate() {
            sonar_slot[usize::from(unit.index)] = Some(slot);
        }
        let latest = Arc::new(Mutex::new(Latest { ranges_mm: vec![None; model.sonar.len()], ..Latest::default() }));
        let stop_reader = Arc::new(AtomicBool::new(false));
        let reader_link = link.try_clone_link()?;
        let (stop, shared) = (Arc::clone(&stop_reader), Arc::clone(&latest));
        let reader = std::thread::Builder::new()
            .name("arcos-reader".into())
            .spawn(move || read_sips(reader_link, &shared, &sonar_slot, model.arcos.dist_conv_factor, &stop))
            .map_err(RobotError::Io)?;
        let ranges = model
            .sonar
            .iter()
            .map(|s| RangeReading { pose_robot_sensor: s.pose(), range: None, max_range: 5.0 })
            .collect();
        Ok(ArcosRobot {
            link,
            model,
            identity,
            config,
            limits,
            latest,
            stop_reader,
            reader: Some(reader),
            sip: None,
            last_sip_at: None,
            last_sent: Instant::now(),
            ranges,
            to_world: None,
            origin: options.origin,
            rot_limit_sent,
            standstill_wait: options.standstill_wait,
            decelerations_set,
            halt: Arc::default(),
            closed: false,
        })
    }

    /// Who the robot said it is.
    pub fn identity(&self) -> &Identity {
        &self.identity
    }

    /// The controller's CONFIG reply, if it sent one.
    pub fn config(&self) -> Option<&ConfigPacket> {
        self.config.as_ref()
    }

    /// A handle that can stop the robot from another thread (a second
    /// Ctrl-C) even while this one is busy.
    pub fn emergency_stop(&self) -> Result<ArcosEmergencyStop, RobotError> {
        Ok(ArcosEmergencyStop { link: Mutex::new(self.link.try_clone_link()?), halt: Arc::clone(&self.halt) })
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

/// The reader thread: packets into the shared latest reading, until told
/// to stop or the link fails (then the reading is marked ended and the
/// robot sees a disconnection). Every SIP goes through the unwrapper here,
/// or a wrap between two ticks would be missed. Odometry that jumps
/// further than any robot drives ends the link as well
/// ([`LinkLoss::impossible_motion`]).
fn read_sips(
    mut link: Box<dyn Link>,
    latest: &Mutex<Latest>,
    sonar_slot: &[Option<usize>; 256],
    mm_per_unit: f64,
    stop: &AtomicBool,
) {
    let mut decoder = StreamDecoder::new();
    let mut unwrapper = Unwrapper::default();
    let mut last: Option<((i64, i64), Instant)> = None;
    let mut buffer = [0u8; 512];
    let end = |latest: &Mutex<Latest>, how| {
        latest.lock().unwrap_or_else(std::sync::PoisonError::into_inner).ended = Some(how);
    };
    while !stop.load(Ordering::Relaxed) {
        match link.read(&mut buffer) {
            Ok(0) => return end(latest, Ended::Closed),
            Ok(n) => decoder.push(&buffer[..n]),
            Err(e) if is_timeout(&e) => continue,
            Err(e) => return end(latest, Ended::Failed(e.kind())),
        }
        while let Some(body) = decoder.next_body() {
            let Ok(mut sip) = Sip::parse(&body) else { continue };
            let position = unwrapper.update(sip.xpos, sip.ypos);
            let now = Instant::now();
            if let Some(((x, y), at)) = last {
                let metres = ((position.0 - x) as f64).hypot((position.1 - y) as f64) * mm_per_unit / 1000.0;
                let seconds = now.duration_since(at).as_secs_f64();
                if LinkLoss::impossible_motion(metres, seconds).is_some() {
                    return end(latest, Ended::Jumped(metres, seconds));
                }
            }
            last = Some((position, now));
            let mut shared = latest.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            for (channel, range) in std::mem::take(&mut sip.sonar) {
                if let Some(slot) = sonar_slot[usize::from(channel)] {
                    shared.ranges_mm[slot] = Some(range);
                }
            }
            shared.sip = Some(sip);
            shared.position = position;
            shared.arrived = Some(now);
        }
    }
}

impl ArcosRobot {
    /// Reads the robot's speeds from the latest SIP, mm/s and °/s.
    fn speeds(&self, sip: &Sip) -> (f64, f64) {
        let a = self.model.arcos;
        let (l, r) = (f64::from(sip.l_vel) * a.vel_conv_factor, f64::from(sip.r_vel) * a.vel_conv_factor);
        let rot = match sip.tail.rot_vel {
            Some(tenths_deg) => f64::from(tenths_deg) / 10.0,
            None => ((r - l) / 2.0 * a.diff_conv_factor).to_degrees(),
        };
        ((l + r) / 2.0, rot)
    }

    /// Sends SETRV for `rad_s` if it differs from the limit last sent.
    fn set_rot_limit(&mut self, rad_s: f64) -> Result<(), RobotError> {
        let deg_s = rad_s.to_degrees().round() as u16;
        if deg_s != self.rot_limit_sent {
            self.send(ClientCommand::SetRv(deg_s))?;
            self.rot_limit_sent = deg_s;
        }
        Ok(())
    }

    /// Waits until a fresh SIP says the robot is down to a walking pace
    /// ([`STOPPED_MM_S`]), or until the speed it had at STOP could have
    /// been braked away at the controller's deceleration plus the
    /// configured margin: STOP decelerates under power, while motors
    /// switched off at speed let a 100 kg robot coast. A link whose reading
    /// side has ended (the other end half-closed it, or its bytes went bad)
    /// may still carry STOP and ENABLE 0, so the wait is then served in
    /// full, blind.
    fn wait_for_standstill(&self) {
        let asked = Instant::now();
        let (bound, speed_at_stop) = {
            let latest = self.latest.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            let (v, w) = latest.sip.as_ref().map_or((0.0, 0.0), |sip| self.speeds(sip));
            let (decel, rot_decel) = self.decelerations();
            let bound = self.standstill_wait + braking_time(v, decel).max(braking_time(w, rot_decel));
            (bound, latest.sip.as_ref().map(|_| v))
        };
        let mut fresh_speed = None;
        while asked.elapsed() < bound {
            std::thread::sleep(Duration::from_millis(10));
            let latest = self.latest.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            let fresh = latest.arrived.is_some_and(|t| t > asked);
            if let (true, Some(sip)) = (fresh, &latest.sip) {
                let (v, w) = self.speeds(sip);
                if v.abs() <= STOPPED_MM_S && w.abs() <= STOPPED_DEG_S {
                    return;
                }
                fresh_speed = Some(v);
            }
        }
        let name = &self.identity.name;
        let waited = bound.as_secs_f64();
        match (fresh_speed, speed_at_stop) {
            (Some(v), _) => {
                tracing::warn!("{name}: still at {v:.0} mm/s {waited:.1} s after STOP; switching the motors off")
            }
            (None, Some(v)) => tracing::warn!(
                "{name}: no sensor data after STOP; waited the {waited:.1} s it needs to brake from {v:.0} mm/s \
                 before switching the motors off"
            ),
            (None, None) => tracing::warn!(
                "{name}: no sensor data ever came; waited {waited:.1} s after STOP before switching the motors off"
            ),
        }
    }

    /// The decelerations STOP brakes at, mm/s² and °/s²: those the session
    /// set, else those the CONFIG reply reports, else a cautious guess.
    fn decelerations(&self) -> (f64, f64) {
        let set = self.decelerations_set;
        let reported =
            self.config.as_ref().map(|c| (f64::from(c.settings.trans_decel), f64::from(c.settings.rot_decel)));
        let (v, w) = set.or(reported).unwrap_or((0.0, 0.0));
        let known = |value: f64, guess: f64| if value > 0.0 { value } else { guess };
        (known(v, CAUTIOUS_DECEL_MM_S2), known(w, CAUTIOUS_ROT_DECEL_DEG_S2))
    }
}

/// Seconds to brake `speed` away at `deceleration` (same units per second).
fn braking_time(speed: f64, deceleration: f64) -> Duration {
    Duration::from_secs_f64((speed.abs() / deceleration).min(MOST_BRAKING_S))
}

impl Robot for ArcosRobot {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        let a = self.model.arcos;
        let (position, ended) = {
            let latest = self.latest.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            self.sip.clone_from(&latest.sip);
            self.last_sip_at = latest.arrived;
            for (reading, range) in self.ranges.iter_mut().zip(&latest.ranges_mm) {
                let metres = range.map(|r| f64::from(r) * a.range_conv_factor / 1000.0);
                reading.range = metres.filter(|&m| m < reading.max_range);
            }
            (latest.position, latest.ended)
        };
        let Some(sip) = &self.sip else {
            state.sensor_age = f64::INFINITY;
            return ended.map_or(Ok(()), |how| Err(LinkLoss::from(how).into()));
        };
        let odometry = Pose2::new(
            position.0 as f64 * a.dist_conv_factor / 1000.0,
            position.1 as f64 * a.dist_conv_factor / 1000.0,
            f64::from(sip.thpos) * a.angle_conv_factor,
        );
        // The first SIP is where the session's world frame is anchored.
        let origin = self.origin;
        let to_world = *self.to_world.get_or_insert_with(|| {
            let first = Pose2::new(0.0, 0.0, odometry.theta);
            origin.compose(&Pose2::default().relative_to(&first))
        });
        state.pose = to_world.compose(&odometry);
        state.odometry = state.pose;
        let (v, w) = self.speeds(sip);
        state.velocity = v / 1000.0;
        state.rot_velocity = w.to_radians();
        state.ranges.clone_from(&self.ranges);
        state.bumpers = Bumpers { front: sip.front_bumped(), rear: sip.rear_bumped() };
        state.stalled = sip.stalled();
        state.motors_enabled = sip.motors_enabled();
        state.estop = sip.estop();
        state.battery_volts = Some(sip.tail.battery_x10.map_or(f64::from(sip.battery) / 10.0, |b| f64::from(b) / 10.0));
        state.sensor_age = self.last_sip_at.map_or(f64::INFINITY, |t| t.elapsed().as_secs_f64());
        ended.map_or(Ok(()), |how| Err(LinkLoss::from(how).into()))
    }

    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        let halt = Arc::clone(&self.halt);
        let _order = halt.lock.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let command = if halt.halted.load(Ordering::SeqCst) { &Command::Stop } else { command };
        let limits = self.limits();
        match *command {
            Command::Stop => self.send(ClientCommand::Stop),
            Command::Drive { velocity, turn } => {
                let mm_s = (velocity.clamp(-limits.max_velocity, limits.max_velocity) * 1000.0).round() as i16;
                self.send(ClientCommand::Vel(mm_s))?;
                match turn {
                    Turn::Rate(rate) => {
                        // SETRV also bounds RVEL: undo a heading command's
                        // lower limit first.
                        self.set_rot_limit(limits.max_rot_velocity)?;
                        let deg_s = rate.clamp(-limits.max_rot_velocity, limits.max_rot_velocity).to_degrees();
                        self.send(ClientCommand::RVel(deg_s.round() as i16))
                    }
                    Turn::Heading { heading, max_rate } => {
                        // HEAD turns at the SETRV limit: the rate the command
                        // allows (NaN: no limit of its own).
                        let rate = if max_rate.is_nan() { limits.max_rot_velocity } else { max_rate };
                        self.set_rot_limit(rate.clamp(0.0, limits.max_rot_velocity))?;
                        // The controller's heading is its own; the command's
                        // is in the world frame.
                        let offset = self.to_world.map_or(0.0, |t| t.theta);
                        let controller = ubf_core::wrap_angle(heading - offset);
                        self.send(ClientCommand::Head(controller.to_degrees().round() as i16))
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
        let result = self.send(ClientCommand::Stop).and_then(|_| {
            self.wait_for_standstill();
            self.send(ClientCommand::Enable(false))?;
            self.send(ClientCommand::Close)
        });
        self.stop_reader.store(true, Ordering::Relaxed);
        // The reader wakes at least every read timeout; a link that blocks
        // longer than this is left to the process's exit.
        if let Some(reader) = self.reader.take() {
            let deadline = Instant::now() + Duration::from_millis(200);
            while !reader.is_finished() && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(5));
            }
            if reader.is_finished() {
                let _ = reader.join();
            }
        }
        result
    }

    fn limits(&self) -> Limits {
        self.limits
    }
}

impl Drop for ArcosRobot {
    /// A session is never left open: motors off and CLOSE, even on a panic.
    fn drop(&mut self) {
        let _ = self.shutdown();
    }
}
