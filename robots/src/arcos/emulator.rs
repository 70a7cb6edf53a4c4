//! The robot's side of the protocol, for tests and for users without a
//! robot: answers the handshake and CONFIG, streams SIPs, drives a simple
//! unicycle with the accelerations it is given, echoes its sonar off walls,
//! switches baud on HOSTBAUD and honours the watchdog.

use super::codec::{baud_of_code, frame, ClientCommand, ConfigPacket, Identity, Sip, SipTail, StreamDecoder};
use super::link::{is_timeout, Link};
use crate::model::RobotModel;
use crate::sim::approach;
use crate::sim::geometry::Segment;
use crate::sim::{Sonar, SonarConfig};
use rand::SeedableRng;
use std::io::{self, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use ubf_core::Pose2;

/// The emulator's settings.
#[derive(Clone, Debug)]
pub struct EmulatorConfig {
    /// The robot it pretends to be (units, limits, sonar channels).
    pub model: RobotModel,
    /// The name it gives in the SYNC2 reply.
    pub name: String,
    /// Time between SIPs.
    pub sip_period: Duration,
    /// Motors stop after this long without a packet.
    pub watchdog: Duration,
    /// Walls the sonar echoes off, metres, in the frame the robot starts in
    /// (at the origin, facing +x). None: open space, no echoes.
    pub walls: Vec<Segment>,
    /// Where the robot's internal position starts, mm: set it near the
    /// position accumulators' wrap to exercise a client's unwrapping.
    pub start_mm: (f64, f64),
}

/// Range a sonar reports without an echo, mm.
const NO_ECHO_MM: u16 = 5000;

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
    /// Whether the client closed the session.
    pub closed: bool,
}

/// A pseudo-terminal's master hangs up (a broken pipe, or EIO on a plain
/// read) while no client holds the slave end: the client has gone.
fn client_left_terminal(e: &io::Error) -> bool {
    #[cfg(unix)]
    let eio = e.raw_os_error() == Some(libc::EIO);
    #[cfg(not(unix))]
    let eio = false;
    eio || e.kind() == io::ErrorKind::BrokenPipe
}

/// Moves `speed` toward `target` by at most `accel·dt` when speeding up
/// and `decel·dt` when slowing down; `None` is an instant change.
fn ramp(speed: f64, target: f64, accel: Option<f64>, decel: Option<f64>, dt: f64) -> f64 {
    let slowing = target.abs() < speed.abs() || target * speed < 0.0;
    match if slowing { decel } else { accel } {
        Some(a) => approach(speed, target, a * dt),
        None => target,
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

/// Serves one client over `link` until it closes, the link fails or `stop`
/// is set.
pub fn serve(mut link: Box<dyn Link>, config: &EmulatorConfig, stop: &Arc<AtomicBool>) -> io::Result<EmulatorReport> {
    let arcos = config.model.arcos;
    let max_v = config.model.max_velocity * 1000.0;
    let max_w = config.model.max_rot_velocity_deg.to_radians();
    let mut decoder = StreamDecoder::new();
    let mut report = EmulatorReport::default();
    let mut phase = Phase::Sync0;
    let (mut x, mut y, mut th) = (config.start_mm.0, config.start_mm.1, 0.0f64);
    // Commanded and actual speeds, mm/s and rad/s.
    let (mut v_cmd, mut w_cmd, mut v, mut w) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    // Accelerations and decelerations set by SETA and SETRA.
    let (mut acc, mut dec, mut rot_acc, mut rot_dec) = (None, None, None, None);
    let mut host_baud = 0u8;
    let mut enabled = false;
    let sonar_config = SonarConfig { noise_m: 0.0, ..SonarConfig::default() };
    let mut sonar = Sonar::new(sonar_config, config.model.sonar.clone());
    let mut sonar_rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let mut echoes = Vec::new();
    let mut last_packet = Instant::now();
    let mut last_sip = Instant::now();
    let mut buffer = [0u8; 256];
    while !stop.load(Ordering::Relaxed) {
        match link.read(&mut buffer) {
            Ok(0) => break,
            Ok(n) => decoder.push(&buffer[..n]),
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
                (Phase::Ready, ClientCommand::Sync1) => phase = Phase::Open, // OPEN shares SYNC1's number
                (Phase::Open, ClientCommand::Sync2) => {
                    // CLOSE shares SYNC2's number.
                    report.closed = true;
                    enabled = false;
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
                (Phase::Open, c) => match c {
                    ClientCommand::Enable(on) => enabled = on,
                    ClientCommand::Vel(mm_s) => v_cmd = f64::from(mm_s).clamp(-max_v, max_v),
                    ClientCommand::RVel(deg_s) => w_cmd = f64::from(deg_s).to_radians().clamp(-max_w, max_w),
                    ClientCommand::Stop => (v_cmd, w_cmd) = (0.0, 0.0),
                    ClientCommand::EStop => (v_cmd, w_cmd, v, w) = (0.0, 0.0, 0.0, 0.0),
                    ClientCommand::SetO => (x, y, th) = (0.0, 0.0, 0.0),
                    // Until both of a pair are set, one serves for both.
                    ClientCommand::SetA(a) if a > 0 => (acc, dec) = (Some(f64::from(a)), dec.or(Some(f64::from(a)))),
                    ClientCommand::SetA(a) if a < 0 => (dec, acc) = (Some(-f64::from(a)), acc.or(Some(-f64::from(a)))),
                    ClientCommand::SetRa(a) if a != 0 => {
                        let r = Some(f64::from(a.unsigned_abs()).to_radians());
                        if a > 0 {
                            (rot_acc, rot_dec) = (r, rot_dec.or(r));
                        } else {
                            (rot_dec, rot_acc) = (r, rot_acc.or(r));
                        }
                    }
                    ClientCommand::Config => {
                        let reply = ConfigPacket {
                            robot_type: config.model.class.clone(),
                            subtype: config.model.subclass.clone(),
                            serial_number: "EMU-0001".into(),
                            rot_vel_top: config.model.max_rot_velocity_deg.round() as i16,
                            trans_vel_top: max_v.round() as i16,
                            rot_acc_top: 300,
                            trans_acc_top: 2000,
                            pwm_max: 1000,
                            name: config.name.clone(),
                            sip_cycle_ms: config.sip_period.as_millis().min(255) as u8,
                            host_baud,
                            ..ConfigPacket::default()
                        };
                        link.write_all(&frame(&reply.body()))?;
                    }
                    _ => {}
                },
                _ => {}
            }
        }
        if phase == Phase::Open && last_sip.elapsed() >= config.sip_period {
            let dt = last_sip.elapsed().as_secs_f64();
            last_sip = Instant::now();
            if last_packet.elapsed() > config.watchdog && (v_cmd != 0.0 || w_cmd != 0.0) {
                (v_cmd, w_cmd) = (0.0, 0.0);
                report.watchdog_stops += 1;
            }
            let (v_target, w_target) = if enabled { (v_cmd, w_cmd) } else { (0.0, 0.0) };
            v = ramp(v, v_target, acc, dec, dt);
            w = ramp(w, w_target, rot_acc, rot_dec, dt);
            let (vv, ww) = (v, w);
            th += ww * dt;
            x += vv * dt * th.cos();
            y += vv * dt * th.sin();
            let wheel = ww / arcos.diff_conv_factor; // (r − l)/2 in mm/s
            let to_pos = |mm: f64| ((mm / arcos.dist_conv_factor).round() as i64).rem_euclid(0x8000) as u16;
            let sip = Sip {
                moving: vv != 0.0 || ww != 0.0,
                xpos: to_pos(x),
                ypos: to_pos(y),
                thpos: ((th.sin().atan2(th.cos())) / arcos.angle_conv_factor).round() as i16,
                l_vel: ((vv - wheel) / arcos.vel_conv_factor).round() as i16,
                r_vel: ((vv + wheel) / arcos.vel_conv_factor).round() as i16,
                battery: 130,
                flags: u16::from(enabled),
                sonar: {
                    let at = Pose2::new((x - config.start_mm.0) / 1000.0, (y - config.start_mm.1) / 1000.0, th);
                    sonar.sense(&at, 1.0, &config.walls, &[], &mut sonar_rng, &mut echoes);
                    let range_mm = |r: Option<f64>| {
                        r.map_or(NO_ECHO_MM, |m| {
                            ((m * 1000.0 / arcos.range_conv_factor).round() as u16).min(NO_ECHO_MM)
                        })
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
            link.write_all(&frame(&sip.body()))?;
        }
    }
    let stats = decoder.stats();
    report.bad_checksums = stats.bad_checksums;
    report.skipped_bytes = stats.skipped_bytes;
    report.pose = (x, y, th);
    report.accelerations = acc.zip(rot_acc).map(|(a, r)| (a.round() as i16, r.to_degrees().round() as i16));
    Ok(report)
}
