//! The robot's side of the protocol, for tests and for users without a
//! robot: answers the handshake, streams SIPs, drives a simple unicycle and
//! honours the watchdog.

use super::codec::{frame, ClientCommand, Identity, Sip, SipTail, StreamDecoder};
use super::link::{is_timeout, Link};
use crate::model::RobotModel;
use std::io::{self, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

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
    /// Range every sonar reports, mm (the emulator has no world).
    pub sonar_range_mm: u16,
    /// Where the robot's internal position starts, mm: set it near the
    /// position accumulators' wrap to exercise a client's unwrapping.
    pub start_mm: (f64, f64),
}

impl EmulatorConfig {
    /// An emulated robot of `model` with ARCOS's defaults: a SIP every
    /// 100 ms, a 2 s watchdog, open space all round.
    pub fn new(model: RobotModel) -> Self {
        EmulatorConfig {
            model,
            name: "ubf-emulator".into(),
            sip_period: Duration::from_millis(100),
            watchdog: Duration::from_secs(2),
            sonar_range_mm: 5000,
            start_mm: (0.0, 0.0),
        }
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
    /// Whether the client closed the session.
    pub closed: bool,
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
    let (mut v, mut w) = (0.0f64, 0.0f64);
    let mut enabled = false;
    let mut last_packet = Instant::now();
    let mut last_sip = Instant::now();
    let mut buffer = [0u8; 256];
    while !stop.load(Ordering::Relaxed) {
        match link.read(&mut buffer) {
            Ok(0) => break,
            Ok(n) => decoder.push(&buffer[..n]),
            Err(e) if is_timeout(&e) => {}
            Err(e) if e.kind() == io::ErrorKind::ConnectionReset => break,
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
                (Phase::Open, c) => match c {
                    ClientCommand::Enable(on) => enabled = on,
                    ClientCommand::Vel(mm_s) => v = f64::from(mm_s).clamp(-max_v, max_v),
                    ClientCommand::RVel(deg_s) => w = f64::from(deg_s).to_radians().clamp(-max_w, max_w),
                    ClientCommand::Stop | ClientCommand::EStop => (v, w) = (0.0, 0.0),
                    ClientCommand::SetO => (x, y, th) = (0.0, 0.0, 0.0),
                    _ => {}
                },
                _ => {}
            }
        }
        if phase == Phase::Open && last_sip.elapsed() >= config.sip_period {
            let dt = last_sip.elapsed().as_secs_f64();
            last_sip = Instant::now();
            if last_packet.elapsed() > config.watchdog && (v != 0.0 || w != 0.0) {
                (v, w) = (0.0, 0.0);
                report.watchdog_stops += 1;
            }
            let (vv, ww) = if enabled { (v, w) } else { (0.0, 0.0) };
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
                sonar: config.model.sonar.iter().map(|s| (s.index, config.sonar_range_mm)).collect(),
                tail: SipTail { rot_vel: Some((ww.to_degrees() * 10.0).round() as i16), ..SipTail::default() },
                ..Sip::default()
            };
            link.write_all(&frame(&sip.body()))?;
        }
    }
    let stats = decoder.stats();
    report.bad_checksums = stats.bad_checksums;
    report.skipped_bytes = stats.skipped_bytes;
    report.pose = (x, y, th);
    Ok(report)
}
