//! The robot's side of the protocol, for tests and for users without a
//! robot: answers the handshake and a complete CONFIG, streams SIPs, drives
//! a unicycle the way an ARCOS controller does (velocity and position
//! setpoints for translation and rotation, within the SETV/SETRV limits and
//! the SETA/SETRA ramps), stalls against walls, echoes its sonar off them,
//! switches baud on HOSTBAUD and honours the watchdog.
//!
//! For safety tests it can fall silent for a while (no SIPs, as a frozen
//! controller or a cut cable would) or flood SIPs, and it reports when
//! motion commands and STOPs arrived relative to the last SIP it sent.

use super::codec::{
    baud_of_code, frame, ClientCommand, ConfigPacket, ConfigSettings, Identity, Sip, SipTail, StreamDecoder,
};
use super::link::{is_timeout, Link};
use crate::model::{ArcosParams, RobotModel};
use crate::sim::approach;
use crate::sim::geometry::{Quad, Segment};
use crate::sim::{Sonar, SonarConfig};
use rand::SeedableRng;
use std::io::{self, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use ubf_core::{wrap_angle, Pose2};

/// The emulator's settings.
#[derive(Clone, Debug)]
pub struct EmulatorConfig {
    /// The robot it pretends to be (units, limits, outline, sonar channels).
    pub model: RobotModel,
    /// The name it gives in the SYNC2 reply.
    pub name: String,
    /// Time between SIPs. Below the link's read timeout (20 ms) several
    /// SIPs go out together, up to 10 000 a second.
    pub sip_period: Duration,
    /// Motors stop after this long without a packet.
    pub watchdog: Duration,
    /// Walls the sonar echoes off and the robot stalls against, metres, in
    /// the frame the robot starts in (at the origin, facing +x). None: open
    /// space.
    pub walls: Vec<Segment>,
    /// Where the robot's internal position starts, mm: set it near the
    /// position accumulators' wrap to exercise a client's unwrapping.
    pub start_mm: (f64, f64),
    /// Freezes this long after OPEN, for the second duration: sends no
    /// SIPs and does not move, while still reading commands (and obeying
    /// them once it thaws), as a simulator paused mid-run does.
    pub silence: Option<(Duration, Duration)>,
    /// Cuts the link this long after OPEN, for the second duration:
    /// nothing is read or sent (the client's bytes wait in the link), while
    /// the robot drives on under its last command and its watchdog, as
    /// with a cable pulled and plugged back in.
    pub cut: Option<(Duration, Duration)>,
}

/// Range a sonar reports without an echo, mm.
const NO_ECHO_MM: u16 = 5000;

/// Accelerations the controller starts with before any SETA or SETRA:
/// translational mm/s², rotational °/s² (ARCOS keeps its own in FLASH;
/// these are of the Powerbot's order).
const DEFAULT_ACCEL_MM_S2: f64 = 500.0;
const DEFAULT_ROT_ACCEL_DEG_S2: f64 = 100.0;
/// Top accelerations the CONFIG reply gives, mm/s² and °/s².
const TOP_ACCEL_MM_S2: i16 = 2000;
const TOP_ROT_ACCEL_DEG_S2: i16 = 300;
/// The emulated servo loop's step, s.
const SERVO_STEP: f64 = 0.005;
/// Most SIPs sent in one pass of the loop (a flood is capped, not endless).
const MOST_SIPS_PER_PASS: u32 = 200;

impl EmulatorConfig {
    /// An emulated robot of `model` with ARCOS's defaults: a SIP every
    /// 100 ms, a 2 s watchdog, open space all round.
    pub fn new(model: RobotModel) -> Self {
        EmulatorConfig {
            model,
            name: "ubf-emulator".into(),
            sip_period: Duration::from_millis(100),
            watchdog: Duration::from_secs(2),
            walls: Vec::new(),
            start_mm: (0.0, 0.0),
            silence: None,
            cut: None,
        }
    }

    /// Puts the robot at the centre of a `length` × `width` metre room,
    /// facing along its length.
    pub fn in_room(mut self, length: f64, width: f64) -> Self {
        let (x, y) = (length / 2.0, width / 2.0);
        let corners = [(-x, -y), (x, -y), (x, y), (-x, y)];
        self.walls = (0..4).map(|i| Segment { a: corners[i], b: corners[(i + 1) % 4] }).collect();
        self
    }
}

/// What the emulator did, for tests.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EmulatorReport {
    /// Commands understood.
    pub commands: u64,
    /// Packets dropped for bad checksums.
    pub bad_checksums: u64,
    /// Bytes skipped as garbage.
    pub skipped_bytes: u64,
    /// Times the watchdog stopped the motors.
    pub watchdog_stops: u64,
    /// Final position, mm and rad.
    pub pose: (f64, f64, f64),
    /// The baud rate a HOSTBAUD switched to, if one did.
    pub host_baud: Option<u32>,
    /// The accelerations set: translational and rotational, mm/s² and °/s²
    /// (speeding up; slowing down is the same or was set apart).
    pub accelerations: Option<(i16, i16)>,
    /// The speed limits last set by SETV and SETRV, mm/s and °/s.
    pub speed_limits: Option<(u16, u16)>,
    /// Whether the client closed the session.
    pub closed: bool,
    /// Motion commands (non-zero VEL, RVEL, ROTATE, VEL2; any MOVE, HEAD,
    /// DHEAD) that arrived before the first SIP went out.
    pub motion_before_first_sip: u64,
    /// During a configured silence: seconds from the last SIP sent to the
    /// last motion command received, if any came.
    pub last_motion_after_silence_s: Option<f64>,
    /// During a configured silence: seconds from the last SIP sent to the
    /// first STOP received.
    pub stop_after_silence_s: Option<f64>,
    /// Seconds from the STOP that ended the session to ENABLE 0, if both
    /// came.
    pub stop_to_disable_s: Option<f64>,
    /// The translational speed when ENABLE 0 arrived, mm/s.
    pub speed_at_disable: Option<f64>,
    /// When the STOP that ended the session's last motion arrived: the
    /// first STOP after a motion command, as seconds since the Unix epoch
    /// (for timing a stop against an outside event, such as a signal).
    pub motion_stopped_at: Option<f64>,
    /// SIPs sent.
    pub sips: u64,
    /// SIP cycles in which a wheel was stalled.
    pub stalled_cycles: u64,
}

/// A pseudo-terminal's master hangs up (a broken pipe, or EIO on a plain
/// read) while no client holds the slave end: the client has gone.
pub(crate) fn client_left_terminal(e: &io::Error) -> bool {
    #[cfg(unix)]
    let eio = e.raw_os_error() == Some(libc::EIO);
    #[cfg(not(unix))]
    let eio = false;
    eio || e.kind() == io::ErrorKind::BrokenPipe
}

/// ARCOS's translation setpoint: a velocity (VEL, VEL2) or a distance
/// still to go (MOVE).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Translation {
    /// mm/s.
    Velocity(f64),
    /// mm still to go.
    Distance(f64),
}

/// ARCOS's rotation setpoint: a rate (RVEL, ROTATE, VEL2) or a heading
/// (HEAD, DHEAD).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Rotation {
    /// rad/s.
    Rate(f64),
    /// rad, in the odometry frame.
    Heading(f64),
}

/// The emulated motor controller: setpoints, limits, ramps and the
/// speeds they produce.
#[derive(Clone, Debug)]
struct Motors {
    translation: Translation,
    rotation: Rotation,
    /// Actual speeds, mm/s and rad/s.
    v: f64,
    w: f64,
    /// The robot's tops, mm/s and rad/s.
    top_v: f64,
    top_w: f64,
    /// The working limits (SETV, SETRV), mm/s and rad/s.
    max_v: f64,
    max_w: f64,
    /// Accelerations and decelerations, mm/s² and rad/s².
    acc: f64,
    dec: f64,
    rot_acc: f64,
    rot_dec: f64,
}

impl Motors {
    fn new(model: &RobotModel) -> Self {
        let (top_v, top_w) = (model.max_velocity * 1000.0, model.max_rot_velocity_deg.to_radians());
        let rot = DEFAULT_ROT_ACCEL_DEG_S2.to_radians();
        Motors {
            translation: Translation::Velocity(0.0),
            rotation: Rotation::Rate(0.0),
            v: 0.0,
            w: 0.0,
            top_v,
            top_w,
            max_v: top_v,
            max_w: top_w,
            acc: DEFAULT_ACCEL_MM_S2,
            dec: DEFAULT_ACCEL_MM_S2,
            rot_acc: rot,
            rot_dec: rot,
        }
    }

    fn stop(&mut self) {
        self.translation = Translation::Velocity(0.0);
        self.rotation = Rotation::Rate(0.0);
    }

    /// The speeds the setpoints ask for now: a position setpoint asks for
    /// the most speed from which the deceleration still stops on target,
    /// and no more than lands on it within the step of `dt` seconds.
    fn targets(&self, heading: f64, dt: f64) -> (f64, f64) {
        let toward =
            |gap: f64, top: f64, dec: f64| gap.signum() * top.min((2.0 * dec * gap.abs()).sqrt()).min(gap.abs() / dt);
        let v = match self.translation {
            Translation::Velocity(v) => v.clamp(-self.max_v, self.max_v),
            Translation::Distance(d) => toward(d, self.max_v, self.dec),
        };
        let w = match self.rotation {
            Rotation::Rate(w) => w.clamp(-self.max_w, self.max_w),
            Rotation::Heading(target) => toward(wrap_angle(target - heading), self.max_w, self.rot_dec),
        };
        (v, w)
    }

    /// Ramps the speeds toward the targets over `dt` seconds.
    fn ramp(&mut self, (v_target, w_target): (f64, f64), dt: f64) {
        self.v = ramp(self.v, v_target, self.acc, self.dec, dt);
        self.w = ramp(self.w, w_target, self.rot_acc, self.rot_dec, dt);
    }

    /// Runs the servo loop for `dt` seconds from `pose` (mm, rad) in steps
    /// of at most [`SERVO_STEP`], as a controller's fast inner loop does;
    /// returns where the robot ends.
    fn run(&mut self, mut pose: Pose2, enabled: bool, dt: f64) -> Pose2 {
        let steps = (dt / SERVO_STEP).ceil().max(1.0);
        let h = dt / steps;
        for _ in 0..steps as usize {
            let targets = if enabled { self.targets(pose.theta, h) } else { (0.0, 0.0) };
            self.ramp(targets, h);
            pose = crate::sim::integrate(pose, self.v, self.w, h);
            self.advance(self.v * h, pose.theta);
        }
        pose
    }

    /// Counts down a position setpoint by the distance just driven, and
    /// ends it (and a heading setpoint) once reached and still.
    fn advance(&mut self, driven_mm: f64, heading: f64) {
        if let Translation::Distance(d) = &mut self.translation {
            *d -= driven_mm;
            if d.abs() < 1.0 && self.v.abs() < 5.0 {
                self.translation = Translation::Velocity(0.0);
            }
        }
        if let Rotation::Heading(target) = self.rotation {
            if wrap_angle(target - heading).abs() < 0.2f64.to_radians() && self.w.abs() < 0.01 {
                self.rotation = Rotation::Rate(0.0);
            }
        }
    }
}

/// Moves `speed` toward `target` by at most `accel·dt` when speeding up
/// and `decel·dt` when slowing down.
fn ramp(speed: f64, target: f64, accel: f64, decel: f64, dt: f64) -> f64 {
    let slowing = target.abs() < speed.abs() || target * speed < 0.0;
    approach(speed, target, if slowing { decel } else { accel } * dt)
}

/// Whether a command asks the robot to move.
fn is_motion(command: &ClientCommand) -> bool {
    use ClientCommand::*;
    match *command {
        Vel(v) | RVel(v) | Rotate(v) => v != 0,
        Vel2(l, r) => l != 0 || r != 0,
        Move(_) | Head(_) | DHead(_) => true,
        _ => false,
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Sync0,
    Sync1,
    Sync2,
    Ready,
    Open,
}

/// The CONFIG reply: every field a controller sends, the working limits
/// and accelerations as they are now.
fn config_reply(config: &EmulatorConfig, motors: &Motors, host_baud: u8) -> ConfigPacket {
    let sat = |v: f64| v.round().clamp(0.0, f64::from(u16::MAX)) as u16;
    ConfigPacket {
        robot_type: config.model.class.clone(),
        subtype: config.model.subclass.clone(),
        serial_number: "EMU-0001".into(),
        four_motors: 0,
        rot_vel_top: motors.top_w.to_degrees().round() as i16,
        trans_vel_top: motors.top_v.round() as i16,
        rot_acc_top: TOP_ROT_ACCEL_DEG_S2,
        trans_acc_top: TOP_ACCEL_MM_S2,
        pwm_max: 1000,
        name: config.name.clone(),
        sip_cycle_ms: config.sip_period.as_millis().clamp(1, 255) as u8,
        host_baud,
        aux_baud: 0,
        settings: ConfigSettings {
            front_sonar: 1,
            rear_sonar: 1,
            low_battery_dv: 230,
            rev_count: 16_570,
            watchdog_ms: config.watchdog.as_millis().min(u128::from(u16::MAX)) as u16,
            normal_mpacs: 1,
            stall_val: 200,
            stall_count: 100,
            joy_vel: 300,
            joy_rot_vel: 50,
            rot_vel_max: sat(motors.max_w.to_degrees()),
            trans_vel_max: sat(motors.max_v),
            rot_accel: sat(motors.rot_acc.to_degrees()),
            rot_decel: sat(motors.rot_dec.to_degrees()),
            rot_kp: 40,
            rot_kv: 20,
            rot_ki: 0,
            trans_accel: sat(motors.acc),
            trans_decel: sat(motors.dec),
            trans_kp: 40,
            trans_kv: 30,
            trans_ki: 0,
            front_bumps: 7,
            rear_bumps: 5,
            sonar_cycle_ms: 40,
            autobaud: 2,
            ticks_mm: 76,
            shutdown_voltage_dv: 210,
            firmware_version: "1.9".into(),
            ..ConfigSettings::default()
        },
        rest: Vec::new(),
    }
}

/// Serves one client over `link` until it closes, the link fails or `stop`
/// is set.
pub fn serve(mut link: Box<dyn Link>, config: &EmulatorConfig, stop: &Arc<AtomicBool>) -> io::Result<EmulatorReport> {
    let arcos = config.model.arcos;
    let mut decoder = StreamDecoder::new();
    let mut report = EmulatorReport::default();
    let mut phase = Phase::Sync0;
    let (mut x, mut y, mut th) = (config.start_mm.0, config.start_mm.1, 0.0f64);
    let mut motors = Motors::new(&config.model);
    let mut host_baud = 0u8;
    let mut enabled = false;
    let sonar_config = SonarConfig { noise_m: 0.0, ..SonarConfig::default() };
    let mut sonar = Sonar::new(sonar_config, config.model.sonar.clone());
    let mut sonar_rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let mut echoes = Vec::new();
    let mut last_packet = Instant::now();
    let mut last_step = Instant::now();
    let mut last_sip = Instant::now();
    let mut opened_at = Instant::now();
    let mut last_sip_sent: Option<Instant> = None;
    let mut last_stop: Option<Instant> = None;
    // A motion command came after the last STOP.
    let mut moving = false;
    let mut buffer = [0u8; 256];
    let within = |window: Option<(Duration, Duration)>, opened_at: Instant| {
        window.is_some_and(|(after, span)| {
            let t = opened_at.elapsed();
            t >= after && t < after + span
        })
    };
    let silent = |opened_at: Instant| within(config.silence, opened_at);
    while !stop.load(Ordering::Relaxed) {
        let cut_now = phase == Phase::Open && within(config.cut, opened_at);
        if cut_now {
            std::thread::sleep(Duration::from_millis(5));
        }
        match if cut_now { Ok(None) } else { link.read(&mut buffer).map(Some) } {
            Ok(None) => {}
            Ok(Some(0)) => break,
            Ok(Some(n)) => decoder.push(&buffer[..n]),
            Err(e) if is_timeout(&e) => {}
            Err(e) if e.kind() == io::ErrorKind::ConnectionReset || client_left_terminal(&e) => break,
            Err(e) => return Err(e),
        }
        while let Some(body) = decoder.next_body() {
            last_packet = Instant::now();
            let Ok(command) = ClientCommand::parse(&body) else { continue };
            report.commands += 1;
            match (phase, command) {
                (Phase::Sync0, ClientCommand::Sync0) => {
                    link.write_all(&frame(&[0]))?;
                    phase = Phase::Sync1;
                }
                (Phase::Sync1, ClientCommand::Sync1) => {
                    link.write_all(&frame(&[1]))?;
                    phase = Phase::Sync2;
                }
                (Phase::Sync2, ClientCommand::Sync2) => {
                    let id = Identity {
                        name: config.name.clone(),
                        class: config.model.class.clone(),
                        subclass: config.model.subclass.clone(),
                    };
                    link.write_all(&frame(&id.body()))?;
                    phase = Phase::Ready;
                }
                (Phase::Sync1 | Phase::Sync2, ClientCommand::Sync0) => {
                    link.write_all(&frame(&[0]))?;
                    phase = Phase::Sync1;
                }
                (Phase::Ready, ClientCommand::Sync1) => {
                    // OPEN shares SYNC1's number.
                    phase = Phase::Open;
                    opened_at = Instant::now();
                }
                (Phase::Open, ClientCommand::Sync2) => {
                    // CLOSE shares SYNC2's number.
                    report.closed = true;
                    enabled = false;
                    motors.stop();
                    phase = Phase::Sync0;
                }
                (Phase::Ready | Phase::Open, ClientCommand::HostBaud(code)) => {
                    if let Some(baud) = baud_of_code(code) {
                        // The client follows once the command has drained.
                        // A pseudo-terminal's master may refuse a rate; its
                        // bytes do not depend on one.
                        if let Err(e) = link.set_baud(baud) {
                            tracing::debug!("emulator: setting {baud} baud: {e}");
                        }
                        host_baud = code;
                        report.host_baud = Some(baud);
                    }
                }
                (Phase::Open, c) => {
                    if is_motion(&c) {
                        moving = true;
                        if report.sips == 0 {
                            report.motion_before_first_sip += 1;
                        }
                        if silent(opened_at) {
                            report.last_motion_after_silence_s = last_sip_sent.map(|t| t.elapsed().as_secs_f64());
                        }
                    }
                    obey(c, &mut motors, &mut enabled, th, &arcos, &mut report);
                    match c {
                        ClientCommand::Stop => {
                            last_stop = Some(Instant::now());
                            if std::mem::take(&mut moving) {
                                report.motion_stopped_at = std::time::SystemTime::now()
                                    .duration_since(std::time::UNIX_EPOCH)
                                    .ok()
                                    .map(|d| d.as_secs_f64());
                            }
                            if silent(opened_at) && report.stop_after_silence_s.is_none() {
                                report.stop_after_silence_s = last_sip_sent.map(|t| t.elapsed().as_secs_f64());
                            }
                        }
                        ClientCommand::Enable(false) => {
                            report.stop_to_disable_s = last_stop.map(|t| t.elapsed().as_secs_f64());
                            report.speed_at_disable = Some(motors.v);
                        }
                        ClientCommand::SetO => (x, y, th) = (0.0, 0.0, 0.0),
                        ClientCommand::Config => {
                            link.write_all(&frame(&config_reply(config, &motors, host_baud).body()))?;
                        }
                        _ => {}
                    }
                }
                _ => {}
            }
        }
        if phase != Phase::Open || last_sip.elapsed() < config.sip_period {
            continue;
        }
        let due = (last_sip.elapsed().as_nanos() / config.sip_period.as_nanos().max(1)).min(MOST_SIPS_PER_PASS.into());
        last_sip = Instant::now();
        let dt = last_step.elapsed().as_secs_f64();
        last_step = Instant::now();
        if last_packet.elapsed() > config.watchdog && motors.targets(th, dt) != (0.0, 0.0) {
            motors.stop();
            report.watchdog_stops += 1;
        }
        if silent(opened_at) {
            continue;
        }
        let before = motors.clone();
        let next = motors.run(Pose2::new(x, y, th), enabled, dt);
        let mut stall_and_bumpers = 0u16;
        if blocked(config, &next) {
            // The wheels push against the wall and do not turn.
            let forward = before.targets(th, dt.max(SERVO_STEP)).0 >= 0.0;
            stall_and_bumpers = 0x0101 | if forward { 0x0200 } else { 0x0002 };
            motors = Motors { v: 0.0, w: 0.0, ..before };
            report.stalled_cycles += 1;
        } else {
            (x, y, th) = (next.x, next.y, next.theta);
        }
        let (vv, ww) = (motors.v, motors.w);
        let wheel = ww / arcos.diff_conv_factor; // (r − l)/2 in mm/s
        let to_pos = |mm: f64| ((mm / arcos.dist_conv_factor).round() as i64).rem_euclid(0x8000) as u16;
        let sip = Sip {
            moving: vv != 0.0 || ww != 0.0,
            xpos: to_pos(x),
            ypos: to_pos(y),
            thpos: (wrap_angle(th) / arcos.angle_conv_factor).round() as i16,
            l_vel: ((vv - wheel) / arcos.vel_conv_factor).round() as i16,
            r_vel: ((vv + wheel) / arcos.vel_conv_factor).round() as i16,
            battery: 130,
            stall_and_bumpers,
            flags: u16::from(enabled),
            sonar: {
                let at = Pose2::new((x - config.start_mm.0) / 1000.0, (y - config.start_mm.1) / 1000.0, th);
                sonar.sense(&at, 1.0, &config.walls, &[], &mut sonar_rng, &mut echoes);
                let range_mm = |r: Option<f64>| {
                    r.map_or(NO_ECHO_MM, |m| ((m * 1000.0 / arcos.range_conv_factor).round() as u16).min(NO_ECHO_MM))
                };
                config.model.sonar.iter().zip(&echoes).map(|(s, e)| (s.index, range_mm(e.range))).collect()
            },
            tail: SipTail {
                battery_x10: Some(130),
                rot_vel: Some((ww.to_degrees() * 10.0).round() as i16),
                ..SipTail::default()
            },
            ..Sip::default()
        };
        if cut_now {
            continue;
        }
        let packet = frame(&sip.body());
        for _ in 0..due {
            link.write_all(&packet)?;
        }
        report.sips += due as u64;
        last_sip_sent = Some(Instant::now());
    }
    let stats = decoder.stats();
    report.bad_checksums = stats.bad_checksums;
    report.skipped_bytes = stats.skipped_bytes;
    report.pose = (x, y, th);
    report.accelerations = Some((motors.acc.round() as i16, motors.rot_acc.to_degrees().round() as i16));
    Ok(report)
}

/// One command of an open session, applied to the motors.
fn obey(
    command: ClientCommand,
    motors: &mut Motors,
    enabled: &mut bool,
    heading: f64,
    arcos: &ArcosParams,
    report: &mut EmulatorReport,
) {
    use ClientCommand::*;
    let vel2 = |units: i8| f64::from(units) * arcos.vel2_divisor;
    match command {
        Enable(on) => *enabled = on,
        Vel(mm_s) => motors.translation = Translation::Velocity(f64::from(mm_s)),
        RVel(deg_s) | Rotate(deg_s) => motors.rotation = Rotation::Rate(f64::from(deg_s).to_radians()),
        Vel2(l, r) => {
            let (l, r) = (vel2(l), vel2(r));
            motors.translation = Translation::Velocity((l + r) / 2.0);
            motors.rotation = Rotation::Rate((r - l) / 2.0 * arcos.diff_conv_factor);
        }
        Move(mm) => motors.translation = Translation::Distance(f64::from(mm)),
        Head(deg) => motors.rotation = Rotation::Heading(f64::from(deg).to_radians()),
        DHead(deg) => motors.rotation = Rotation::Heading(heading + f64::from(deg).to_radians()),
        SetV(mm_s) => motors.max_v = f64::from(mm_s).min(motors.top_v),
        SetRv(deg_s) => motors.max_w = f64::from(deg_s).to_radians().min(motors.top_w),
        Stop => motors.stop(),
        EStop => {
            motors.stop();
            (motors.v, motors.w) = (0.0, 0.0);
        }
        // Positive sets the acceleration, negative the deceleration.
        SetA(a) if a > 0 => motors.acc = f64::from(a),
        SetA(a) if a < 0 => motors.dec = -f64::from(a),
        SetRa(a) if a > 0 => motors.rot_acc = f64::from(a).to_radians(),
        SetRa(a) if a < 0 => motors.rot_dec = f64::from(a.unsigned_abs()).to_radians(),
        _ => {}
    }
    if let SetV(_) | SetRv(_) = command {
        report.speed_limits = Some((motors.max_v.round() as u16, motors.max_w.to_degrees().round() as u16));
    }
}

/// Whether the robot's outline at `pose` (mm, in the controller's frame)
/// touches a wall.
fn blocked(config: &EmulatorConfig, pose: &Pose2) -> bool {
    if config.walls.is_empty() {
        return false;
    }
    let at = Pose2::new((pose.x - config.start_mm.0) / 1000.0, (pose.y - config.start_mm.1) / 1000.0, pose.theta);
    let outline = Quad(config.model.footprint.corners().map(|(cx, cy)| at.transform_point(cx, cy)));
    config.walls.iter().any(|wall| outline.touches_segment(wall))
}
