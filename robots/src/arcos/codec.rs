//! ARCOS packets, pure: bytes in, values out, and back.
//!
//! A packet is `0xFA 0xFB N body… ck_hi ck_lo`, where `N` counts the body
//! and the two checksum bytes. The checksum adds the body as big-endian
//! 16-bit pairs modulo 2¹⁶ and XORs a leftover odd byte into the low byte.
//! Integers in bodies are little-endian.

/// The two header bytes.
pub const HEADER: [u8; 2] = [0xFA, 0xFB];
/// Longest body a packet may carry (ARCOS drops command packets whose count
/// exceeds 204; keep to 200 with the checksum).
pub const MAX_BODY: usize = 198;

/// The checksum of a packet body.
pub fn checksum(body: &[u8]) -> u16 {
    let mut sum: u16 = 0;
    let mut pairs = body.chunks_exact(2);
    for pair in &mut pairs {
        sum = sum.wrapping_add(u16::from(pair[0]) << 8 | u16::from(pair[1]));
    }
    if let [last] = pairs.remainder() {
        sum ^= u16::from(*last);
    }
    sum
}

/// Frames a body into a packet. Bodies longer than [`MAX_BODY`] are a
/// programming error in the caller and are cut to fit.
pub fn frame(body: &[u8]) -> Vec<u8> {
    let body = &body[..body.len().min(MAX_BODY)];
    let mut packet = Vec::with_capacity(body.len() + 5);
    packet.extend_from_slice(&HEADER);
    packet.push((body.len() + 2) as u8);
    packet.extend_from_slice(body);
    packet.extend_from_slice(&checksum(body).to_be_bytes());
    packet
}

/// A command to the controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClientCommand {
    /// Synchronisation, first packet of the handshake.
    Sync0,
    /// Synchronisation, second packet.
    Sync1,
    /// Synchronisation, third packet; the reply names the robot.
    Sync2,
    /// Keep the watchdog quiet.
    Pulse,
    /// Start the servers and the SIP stream.
    Open,
    /// End the session: motors and sonar off.
    Close,
    /// Motors on or off.
    Enable(bool),
    /// Translational acceleration (+) or deceleration (−), mm/s².
    SetA(i16),
    /// Maximum velocity, mm/s.
    SetV(u16),
    /// Reset odometry to (0, 0, 0).
    SetO,
    /// Translate by ± mm.
    Move(i16),
    /// Rotate at ± °/s.
    Rotate(i16),
    /// Maximum rotational velocity, °/s.
    SetRv(u16),
    /// Translational velocity, ± mm/s.
    Vel(i16),
    /// Absolute heading, °.
    Head(i16),
    /// Relative heading, °.
    DHead(i16),
    /// Ask for a CONFIG packet.
    Config,
    /// Rotational velocity, ± °/s.
    RVel(i16),
    /// Left and right wheel velocities, each in units of the model's
    /// `Vel2Divisor` mm/s.
    Vel2(i8, i8),
    /// Rotational acceleration (+) or deceleration (−), °/s².
    SetRa(i16),
    /// Sonar on or off.
    Sonar(bool),
    /// Stop.
    Stop,
    /// Stop and disable the bump-stall: 0 off, 1 front, 2 rear, 3 both.
    BumpStall(u8),
    /// Switch the link's baud rate: 0 = 9600 … 4 = 115200.
    HostBaud(u8),
    /// Stop at maximum deceleration.
    EStop,
}

/// Argument type byte of a non-negative integer.
const ARG_POSITIVE: u8 = 0x3B;
/// Argument type byte of a negative integer (its absolute value follows).
const ARG_NEGATIVE: u8 = 0x1B;

fn with_int(number: u8, value: i32) -> Vec<u8> {
    let magnitude = value.unsigned_abs().min(u32::from(u16::MAX)) as u16;
    let kind = if value < 0 { ARG_NEGATIVE } else { ARG_POSITIVE };
    let [lo, hi] = magnitude.to_le_bytes();
    vec![number, kind, lo, hi]
}

impl ClientCommand {
    /// The command's body: its number and argument.
    pub fn body(&self) -> Vec<u8> {
        use ClientCommand::*;
        match *self {
            Sync0 => vec![0],
            Sync1 => vec![1],
            Sync2 => vec![2],
            Pulse => vec![0],
            Open => vec![1],
            Close => vec![2],
            Enable(on) => with_int(4, i32::from(on)),
            SetA(v) => with_int(5, i32::from(v)),
            SetV(v) => with_int(6, i32::from(v)),
            SetO => vec![7],
            Move(v) => with_int(8, i32::from(v)),
            Rotate(v) => with_int(9, i32::from(v)),
            SetRv(v) => with_int(10, i32::from(v)),
            Vel(v) => with_int(11, i32::from(v)),
            Head(v) => with_int(12, i32::from(v)),
            DHead(v) => with_int(13, i32::from(v)),
            Config => vec![18],
            RVel(v) => with_int(21, i32::from(v)),
            // Left in the high byte, right in the low byte, sent as one
            // signed integer the way the manual describes.
            Vel2(l, r) => with_int(32, i32::from(i16::from_be_bytes([l as u8, r as u8]))),
            SetRa(v) => with_int(23, i32::from(v)),
            Sonar(on) => with_int(28, i32::from(on)),
            Stop => vec![29],
            BumpStall(v) => with_int(44, i32::from(v)),
            HostBaud(v) => with_int(50, i32::from(v)),
            EStop => vec![55],
        }
    }

    /// The framed packet.
    pub fn packet(&self) -> Vec<u8> {
        frame(&self.body())
    }

    /// Reads a command back from a packet body (what an emulator of the
    /// robot needs). SYNC0–2 share their numbers with PULSE, OPEN and CLOSE;
    /// bare bodies 0–2 read as the SYNCs, the caller knows which phase it
    /// is in.
    pub fn parse(body: &[u8]) -> Result<ClientCommand, DecodeError> {
        use ClientCommand::*;
        let (&number, rest) =
            body.split_first().ok_or(DecodeError::Truncated { what: "command", needed: 1, got: 0 })?;
        let int = || -> Result<i32, DecodeError> {
            match rest {
                [kind, lo, hi, ..] => {
                    let magnitude = i32::from(u16::from_le_bytes([*lo, *hi]));
                    match *kind {
                        ARG_POSITIVE => Ok(magnitude),
                        ARG_NEGATIVE => Ok(-magnitude),
                        other => Err(DecodeError::BadArgument { command: number, kind: other }),
                    }
                }
                _ => Err(DecodeError::Truncated { what: "command argument", needed: 3, got: rest.len() }),
            }
        };
        let narrow = |v: i32| v.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16;
        Ok(match number {
            0 => Sync0,
            1 => Sync1,
            2 => Sync2,
            4 => Enable(int()? != 0),
            5 => SetA(narrow(int()?)),
            6 => SetV(int()?.clamp(0, i32::from(u16::MAX)) as u16),
            7 => SetO,
            8 => Move(narrow(int()?)),
            9 => Rotate(narrow(int()?)),
            10 => SetRv(int()?.clamp(0, i32::from(u16::MAX)) as u16),
            11 => Vel(narrow(int()?)),
            12 => Head(narrow(int()?)),
            13 => DHead(narrow(int()?)),
            18 => Config,
            21 => RVel(narrow(int()?)),
            32 => {
                let [l, r] = narrow(int()?).to_be_bytes();
                Vel2(l as i8, r as i8)
            }
            23 => SetRa(narrow(int()?)),
            28 => Sonar(int()? != 0),
            29 => Stop,
            44 => BumpStall(int()?.clamp(0, 3) as u8),
            50 => HostBaud(int()?.clamp(0, 4) as u8),
            55 => EStop,
            other => return Err(DecodeError::UnknownCommand(other)),
        })
    }
}

/// What was wrong with a packet.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// The body ended before a field.
    #[error("{what}: needed {needed} more bytes, got {got}")]
    Truncated {
        /// The field.
        what: &'static str,
        /// Bytes needed.
        needed: usize,
        /// Bytes there.
        got: usize,
    },
    /// Not a packet type this codec reads.
    #[error("packet type {0:#04x} is not a SIP")]
    NotASip(u8),
    /// A packet of another type than the one asked for.
    #[error("expected packet type {expected:#04x}, got {got:#04x}")]
    UnexpectedPacket {
        /// The type asked for.
        expected: u8,
        /// The type there.
        got: u8,
    },
    /// An unknown command number.
    #[error("unknown command {0}")]
    UnknownCommand(u8),
    /// An argument type byte other than 0x3B, 0x1B or 0x2B.
    #[error("command {command}: argument type {kind:#04x}")]
    BadArgument {
        /// The command.
        command: u8,
        /// The type byte.
        kind: u8,
    },
}

/// Reads little-endian fields off a body, failing cleanly at its end.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], DecodeError> {
        let rest = &self.bytes[self.at.min(self.bytes.len())..];
        if rest.len() < n {
            return Err(DecodeError::Truncated { what, needed: n, got: rest.len() });
        }
        self.at += n;
        Ok(&rest[..n])
    }
    fn u8(&mut self, what: &'static str) -> Result<u8, DecodeError> {
        Ok(self.take(1, what)?[0])
    }
    fn u16(&mut self, what: &'static str) -> Result<u16, DecodeError> {
        let b = self.take(2, what)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }
    fn i16(&mut self, what: &'static str) -> Result<i16, DecodeError> {
        Ok(self.u16(what)? as i16)
    }
    /// A NUL-terminated string (lossy UTF-8).
    fn string(&mut self, what: &'static str) -> Result<String, DecodeError> {
        let rest = &self.bytes[self.at.min(self.bytes.len())..];
        let end = rest.iter().position(|&b| b == 0).ok_or(DecodeError::Truncated { what, needed: 1, got: 0 })?;
        self.at += end + 1;
        Ok(String::from_utf8_lossy(&rest[..end]).into_owned())
    }
    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.at)
    }
    /// An optional trailing field: present only if the body still has it.
    fn maybe<T>(&mut self, size: usize, read: impl FnOnce(&mut Self) -> Result<T, DecodeError>) -> Option<T> {
        if self.remaining() >= size {
            read(self).ok()
        } else {
            None
        }
    }
}

/// The optional fields after the sonar readings, parsed by remaining
/// length: a field is present only if the body still holds it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SipTail {
    /// Gripper state.
    pub grip_state: Option<u8>,
    /// Analog port selected.
    pub anport: Option<u8>,
    /// Analog reading.
    pub analog: Option<u8>,
    /// Digital inputs.
    pub digin: Option<u8>,
    /// Digital outputs.
    pub digout: Option<u8>,
    /// Battery voltage × 10.
    pub battery_x10: Option<u16>,
    /// Charging state.
    pub charge_state: Option<u8>,
    /// Rotational velocity, °/s × 10.
    pub rot_vel: Option<i16>,
    /// Fault flags.
    pub fault_flags: Option<u16>,
    /// Lateral velocity.
    pub lat_vel: Option<i16>,
    /// Temperature, °C.
    pub temperature: Option<i8>,
    /// State of charge, %.
    pub soc: Option<u8>,
}

/// A standard server information packet, in robot units.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Sip {
    /// Type 0x33 (moving) rather than 0x32 (stopped; simulators always send
    /// 0x32).
    pub moving: bool,
    /// X position accumulator, 15 significant bits.
    pub xpos: u16,
    /// Y position accumulator, 15 significant bits.
    pub ypos: u16,
    /// Heading, angle units.
    pub thpos: i16,
    /// Left wheel velocity, velocity units.
    pub l_vel: i16,
    /// Right wheel velocity.
    pub r_vel: i16,
    /// Battery, tenths of a volt.
    pub battery: u8,
    /// Bit 0 left stall, bits 1–7 rear bumpers, bit 8 right stall, bits 9–15
    /// front bumpers.
    pub stall_and_bumpers: u16,
    /// Heading setpoint.
    pub control: i16,
    /// Bit 0 motors on, bits 1–4 sonar arrays, bits 5–6 e-stop, …
    pub flags: u16,
    /// Compass, 2° units.
    pub compass: u8,
    /// Sonar readings this cycle: (channel, range units).
    pub sonar: Vec<(u8, u16)>,
    /// The optional fields that follow.
    pub tail: SipTail,
}

impl Sip {
    /// Whether the motors are on.
    pub fn motors_enabled(&self) -> bool {
        self.flags & 1 != 0
    }
    /// Whether an emergency stop is engaged.
    pub fn estop(&self) -> bool {
        self.flags & 0b110_0000 != 0
    }
    /// Left or right wheel stalled.
    pub fn stalled(&self) -> bool {
        self.stall_and_bumpers & 0x0101 != 0
    }
    /// Any front bumper pressed.
    pub fn front_bumped(&self) -> bool {
        self.stall_and_bumpers & 0xFE00 != 0
    }
    /// Any rear bumper pressed.
    pub fn rear_bumped(&self) -> bool {
        self.stall_and_bumpers & 0x00FE != 0
    }

    /// Reads a standard SIP body (type byte first).
    pub fn parse(body: &[u8]) -> Result<Sip, DecodeError> {
        let mut r = Reader { bytes: body, at: 0 };
        let kind = r.u8("type")?;
        if kind != 0x32 && kind != 0x33 {
            return Err(DecodeError::NotASip(kind));
        }
        let mut sip = Sip {
            moving: kind == 0x33,
            xpos: r.u16("XPOS")?,
            ypos: r.u16("YPOS")?,
            thpos: r.i16("THPOS")?,
            l_vel: r.i16("L VEL")?,
            r_vel: r.i16("R VEL")?,
            battery: r.u8("BATTERY")?,
            stall_and_bumpers: r.u16("STALL_AND_BUMPERS")?,
            control: r.i16("CONTROL")?,
            flags: r.u16("FLAGS")?,
            compass: r.u8("COMPASS")?,
            ..Sip::default()
        };
        let count = r.u8("SONAR COUNT")?;
        sip.sonar.reserve(usize::from(count));
        for _ in 0..count {
            sip.sonar.push((r.u8("sonar channel")?, r.u16("sonar range")?));
        }
        let t = &mut sip.tail;
        t.grip_state = r.maybe(1, |r| r.u8("GRIP_STATE"));
        t.anport = r.maybe(1, |r| r.u8("ANPORT"));
        t.analog = r.maybe(1, |r| r.u8("ANALOG"));
        t.digin = r.maybe(1, |r| r.u8("DIGIN"));
        t.digout = r.maybe(1, |r| r.u8("DIGOUT"));
        t.battery_x10 = r.maybe(2, |r| r.u16("BATTERYX10"));
        t.charge_state = r.maybe(1, |r| r.u8("CHARGESTATE"));
        t.rot_vel = r.maybe(2, |r| r.i16("ROTVEL"));
        t.fault_flags = r.maybe(2, |r| r.u16("FAULTFLAGS"));
        t.lat_vel = r.maybe(2, |r| r.i16("LATVEL"));
        t.temperature = r.maybe(1, |r| r.u8("TEMPERATURE").map(|b| b as i8));
        t.soc = r.maybe(1, |r| r.u8("SOC"));
        Ok(sip)
    }

    /// Writes the SIP's body (what an emulator sends). The tail fields are
    /// written up to the last one present.
    pub fn body(&self) -> Vec<u8> {
        let mut b = vec![if self.moving { 0x33 } else { 0x32 }];
        b.extend_from_slice(&self.xpos.to_le_bytes());
        b.extend_from_slice(&self.ypos.to_le_bytes());
        b.extend_from_slice(&self.thpos.to_le_bytes());
        b.extend_from_slice(&self.l_vel.to_le_bytes());
        b.extend_from_slice(&self.r_vel.to_le_bytes());
        b.push(self.battery);
        b.extend_from_slice(&self.stall_and_bumpers.to_le_bytes());
        b.extend_from_slice(&self.control.to_le_bytes());
        b.extend_from_slice(&self.flags.to_le_bytes());
        b.push(self.compass);
        // A full sonar ring does not fit one packet; send what fits.
        let fits = self.sonar.len().min((MAX_BODY - b.len() - 1) / 3).min(255);
        b.push(fits as u8);
        for &(channel, range) in &self.sonar[..fits] {
            b.push(channel);
            b.extend_from_slice(&range.to_le_bytes());
        }
        let t = &self.tail;
        let fields: [Option<Vec<u8>>; 12] = [
            t.grip_state.map(|v| vec![v]),
            t.anport.map(|v| vec![v]),
            t.analog.map(|v| vec![v]),
            t.digin.map(|v| vec![v]),
            t.digout.map(|v| vec![v]),
            t.battery_x10.map(|v| v.to_le_bytes().to_vec()),
            t.charge_state.map(|v| vec![v]),
            t.rot_vel.map(|v| v.to_le_bytes().to_vec()),
            t.fault_flags.map(|v| v.to_le_bytes().to_vec()),
            t.lat_vel.map(|v| v.to_le_bytes().to_vec()),
            t.temperature.map(|v| vec![v as u8]),
            t.soc.map(|v| vec![v]),
        ];
        if let Some(last) = fields.iter().rposition(Option::is_some) {
            // Absent fields before the last present one are sent as zeros.
            let sizes = [1, 1, 1, 1, 1, 2, 1, 2, 2, 2, 1, 1];
            for (field, size) in fields.iter().zip(sizes).take(last + 1) {
                match field {
                    Some(bytes) => b.extend_from_slice(bytes),
                    None => b.extend(std::iter::repeat_n(0, size)),
                }
            }
        }
        b
    }
}

/// The reply to SYNC2: the robot's name, class and subclass.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Identity {
    /// The robot's name.
    pub name: String,
    /// Its class, e.g. `Pioneer`.
    pub class: String,
    /// Its subclass, e.g. `powerbot`.
    pub subclass: String,
}

impl Identity {
    /// Reads a SYNC2 reply body: the echoed 2, then three NUL-terminated
    /// strings (a missing terminator ends at the body's end).
    pub fn parse(body: &[u8]) -> Result<Identity, DecodeError> {
        let rest = body.strip_prefix(&[2]).ok_or(DecodeError::Truncated { what: "SYNC2 echo", needed: 1, got: 0 })?;
        let mut parts = rest.split(|&b| b == 0).map(|s| String::from_utf8_lossy(s).into_owned());
        let mut next = |what| parts.next().ok_or(DecodeError::Truncated { what, needed: 1, got: 0 });
        Ok(Identity { name: next("name")?, class: next("class")?, subclass: next("subclass")? })
    }

    /// Writes a SYNC2 reply body.
    pub fn body(&self) -> Vec<u8> {
        let mut b = vec![2];
        for s in [&self.name, &self.class, &self.subclass] {
            b.extend(s.bytes().filter(|&c| c != 0));
            b.push(0);
        }
        b
    }
}

/// Packet type of a CONFIG reply.
pub const CONFIG_TYPE: u8 = 0x20;

/// The reply to CONFIG (packet type 0x20): the controller's identity, its
/// top speeds and accelerations, its SIP cycle and its serial settings
/// (every controller generation sends these), then its current settings
/// ([`ConfigSettings`]).
///
/// Field order follows the operations manuals' CONFIGpac tables.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ConfigPacket {
    /// The robot type, e.g. `Pioneer`.
    pub robot_type: String,
    /// The model, e.g. `powerbot`.
    pub subtype: String,
    /// The robot's serial number.
    pub serial_number: String,
    /// Obsolete four-motor flag.
    pub four_motors: u8,
    /// Top rotational speed, °/s.
    pub rot_vel_top: i16,
    /// Top translational speed, mm/s.
    pub trans_vel_top: i16,
    /// Top rotational (de)acceleration, °/s².
    pub rot_acc_top: i16,
    /// Top translational (de)acceleration, mm/s².
    pub trans_acc_top: i16,
    /// Maximum motor PWM.
    pub pwm_max: i16,
    /// The name given to the robot.
    pub name: String,
    /// Time between SIPs, ms.
    pub sip_cycle_ms: u8,
    /// The host serial port's baud code (0 = 9600 … 4 = 115200).
    pub host_baud: u8,
    /// The first auxiliary serial port's baud code.
    pub aux_baud: u8,
    /// The current settings that follow; fields an older firmware does not
    /// send read as zero (or empty).
    pub settings: ConfigSettings,
    /// Bytes after the last field this codec knows, unparsed.
    pub rest: Vec<u8>,
}

/// One CONFIG field's wire format.
trait ConfigField: Sized {
    /// Reads the field, or `None` if the body has ended.
    fn read(r: &mut Reader) -> Option<Self>;
    fn write(&self, b: &mut Vec<u8>);
}

impl ConfigField for u8 {
    fn read(r: &mut Reader) -> Option<Self> {
        r.maybe(1, |r| r.u8(""))
    }
    fn write(&self, b: &mut Vec<u8>) {
        b.push(*self);
    }
}

impl ConfigField for u16 {
    fn read(r: &mut Reader) -> Option<Self> {
        r.maybe(2, |r| r.u16(""))
    }
    fn write(&self, b: &mut Vec<u8>) {
        b.extend(self.to_le_bytes());
    }
}

impl ConfigField for i16 {
    fn read(r: &mut Reader) -> Option<Self> {
        r.maybe(2, |r| r.i16(""))
    }
    fn write(&self, b: &mut Vec<u8>) {
        b.extend(self.to_le_bytes());
    }
}

impl ConfigField for i8 {
    fn read(r: &mut Reader) -> Option<Self> {
        r.maybe(1, |r| r.u8("")).map(|v| v as i8)
    }
    fn write(&self, b: &mut Vec<u8>) {
        b.push(*self as u8);
    }
}

impl ConfigField for u32 {
    fn read(r: &mut Reader) -> Option<Self> {
        let lo = u16::read(r)?;
        let hi = u16::read(r)?;
        Some(u32::from(lo) | u32::from(hi) << 16)
    }
    fn write(&self, b: &mut Vec<u8>) {
        b.extend(self.to_le_bytes());
    }
}

impl ConfigField for String {
    fn read(r: &mut Reader) -> Option<Self> {
        r.string("").ok()
    }
    fn write(&self, b: &mut Vec<u8>) {
        b.extend(self.bytes().filter(|&c| c != 0));
        b.push(0);
    }
}

/// Declares [`ConfigSettings`] once: its fields in wire order, and the
/// reader and writer that follow that order.
macro_rules! config_settings {
    ($($(#[doc = $doc:literal])* $field:ident: $ty:ty,)*) => {
        /// The CONFIG fields after the head: accessories, current speed
        /// limits and accelerations, PID gains and firmware details, in
        /// the manuals' order. Later firmware appended fields; a body that
        /// ends early leaves the rest at zero.
        #[derive(Clone, Debug, Default, PartialEq, Eq)]
        pub struct ConfigSettings {
            $($(#[doc = $doc])* pub $field: $ty,)*
        }

        impl ConfigSettings {
            /// Reads as many fields as the body holds.
            fn read(r: &mut Reader) -> ConfigSettings {
                let mut s = ConfigSettings::default();
                $(match <$ty as ConfigField>::read(r) {
                    Some(v) => s.$field = v,
                    None => return s,
                })*
                s
            }

            fn write(&self, b: &mut Vec<u8>) {
                $(ConfigField::write(&self.$field, b);)*
            }
        }
    };
}

config_settings! {
    /// Has a gripper.
    has_gripper: u16,
    /// Has front sonar.
    front_sonar: u16,
    /// Has rear sonar (a single byte, as the manual says).
    rear_sonar: u8,
    /// Low-battery alarm, tenths of a volt.
    low_battery_dv: u16,
    /// Encoder counts per wheel revolution.
    rev_count: u16,
    /// Watchdog time, ms.
    watchdog_ms: u16,
    /// Whether standard motor packets are sent (P2MPACS).
    normal_mpacs: u8,
    /// Stall PWM limit.
    stall_val: u16,
    /// Idle time after a stall, ms.
    stall_count: u16,
    /// Joystick translational speed, mm/s.
    joy_vel: u16,
    /// Joystick rotational speed, °/s.
    joy_rot_vel: u16,
    /// Current rotational speed limit (SETRV), °/s.
    rot_vel_max: u16,
    /// Current translational speed limit (SETV), mm/s.
    trans_vel_max: u16,
    /// Current rotational acceleration, °/s².
    rot_accel: u16,
    /// Current rotational deceleration, °/s².
    rot_decel: u16,
    /// Rotational PID: proportional.
    rot_kp: u16,
    /// Rotational PID: derivative.
    rot_kv: u16,
    /// Rotational PID: integral.
    rot_ki: u16,
    /// Current translational acceleration, mm/s².
    trans_accel: u16,
    /// Current translational deceleration, mm/s².
    trans_decel: u16,
    /// Translational PID: proportional.
    trans_kp: u16,
    /// Translational PID: derivative.
    trans_kv: u16,
    /// Translational PID: integral.
    trans_ki: u16,
    /// Front bumper segments.
    front_bumps: u8,
    /// Rear bumper segments.
    rear_bumps: u8,
    /// Charger type.
    charger: u8,
    /// Sonar cycle, ms.
    sonar_cycle_ms: u8,
    /// 2 if the controller returns to 9600 baud when a session ends.
    autobaud: u8,
    /// Gyro type (1: has a gyro).
    gyro_type: u8,
    /// Odometry drift correction.
    drift_factor: i16,
    /// Second auxiliary port's baud code.
    aux2_baud: u8,
    /// Third auxiliary port's baud code.
    aux3_baud: u8,
    /// Encoder ticks per mm.
    ticks_mm: u16,
    /// Voltage below which the controller shuts down, tenths of a volt.
    shutdown_voltage_dv: u16,
    /// Firmware version.
    firmware_version: String,
    /// Gyro clockwise correction.
    gyro_cw: u16,
    /// Gyro counter-clockwise correction.
    gyro_ccw: u16,
    /// Kinematics delay, ms.
    kinematics_delay_ms: u8,
    /// Top lateral speed, mm/s.
    lat_vel_top: u16,
    /// Top lateral acceleration, mm/s².
    lat_accel_top: u16,
    /// Current lateral speed limit, mm/s.
    lat_vel_max: u16,
    /// Current lateral acceleration, mm/s².
    lat_accel: u16,
    /// Current lateral deceleration, mm/s².
    lat_decel: u16,
    /// Powerbot charge threshold.
    charge_threshold: u16,
    /// Power distribution board port.
    pdb_port: u8,
    /// Gyro rate limit, °/s.
    gyro_rate_limit: u16,
    /// High-temperature shutdown, °C.
    high_temperature_shutdown: i8,
    /// Power bits.
    power_bits: u16,
    /// Battery type.
    battery_type: u8,
    /// Warning state of charge, %.
    state_of_charge_low: u16,
    /// Shutdown state of charge, %.
    state_of_charge_shutdown: u16,
    /// Boot loader version.
    bootloader_version: String,
    /// Configuration flags.
    config_flags: u32,
    /// Gyro firmware version.
    gyro_fw_version: i16,
}

impl ConfigPacket {
    /// Reads a CONFIG body (starting with its type byte).
    pub fn parse(body: &[u8]) -> Result<ConfigPacket, DecodeError> {
        let mut r = Reader { bytes: body, at: 0 };
        match r.u8("packet type")? {
            CONFIG_TYPE => {}
            other => return Err(DecodeError::UnexpectedPacket { expected: CONFIG_TYPE, got: other }),
        }
        Ok(ConfigPacket {
            robot_type: r.string("robot type")?,
            subtype: r.string("subtype")?,
            serial_number: r.string("serial number")?,
            four_motors: r.u8("four-motor flag")?,
            rot_vel_top: r.i16("top rotational speed")?,
            trans_vel_top: r.i16("top translational speed")?,
            rot_acc_top: r.i16("top rotational acceleration")?,
            trans_acc_top: r.i16("top translational acceleration")?,
            pwm_max: r.i16("PWM maximum")?,
            name: r.string("name")?,
            sip_cycle_ms: r.u8("SIP cycle")?,
            host_baud: r.u8("host baud")?,
            aux_baud: r.u8("aux baud")?,
            settings: ConfigSettings::read(&mut r),
            rest: r.take(r.remaining(), "rest")?.to_vec(),
        })
    }

    /// Writes a CONFIG body.
    pub fn body(&self) -> Vec<u8> {
        let mut b = vec![CONFIG_TYPE];
        let string = |b: &mut Vec<u8>, s: &str| {
            b.extend(s.bytes().filter(|&c| c != 0));
            b.push(0);
        };
        string(&mut b, &self.robot_type);
        string(&mut b, &self.subtype);
        string(&mut b, &self.serial_number);
        b.push(self.four_motors);
        for v in [self.rot_vel_top, self.trans_vel_top, self.rot_acc_top, self.trans_acc_top, self.pwm_max] {
            b.extend(v.to_le_bytes());
        }
        string(&mut b, &self.name);
        b.extend([self.sip_cycle_ms, self.host_baud, self.aux_baud]);
        self.settings.write(&mut b);
        b.extend(&self.rest);
        b
    }
}

/// The baud rates HOSTBAUD can select, by code.
const BAUD_RATES: [u32; 5] = [9600, 19200, 38400, 57600, 115200];

/// HOSTBAUD's code for `baud`, if the controller offers it.
pub fn baud_code(baud: u32) -> Option<u8> {
    BAUD_RATES.iter().position(|&b| b == baud).map(|i| i as u8)
}

/// The baud rate HOSTBAUD's `code` selects.
pub fn baud_of_code(code: u8) -> Option<u32> {
    BAUD_RATES.get(usize::from(code)).copied()
}

/// Keeps odometry continuous across the 15-bit wrap of the position
/// accumulators, over any distance and into negative coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Unwrapper {
    last: Option<(u16, u16)>,
    x: i64,
    y: i64,
}

impl Unwrapper {
    /// Takes a SIP's raw positions; returns the continuous position in
    /// position units since the first SIP.
    pub fn update(&mut self, xpos: u16, ypos: u16) -> (i64, i64) {
        let (x, y) = (xpos & 0x7FFF, ypos & 0x7FFF);
        if let Some((lx, ly)) = self.last {
            self.x += wrapped_difference(x, lx);
            self.y += wrapped_difference(y, ly);
        }
        self.last = Some((x, y));
        (self.x, self.y)
    }
}

/// `new − old` on a 15-bit circle: a jump of more than half the range is a
/// wrap.
fn wrapped_difference(new: u16, old: u16) -> i64 {
    let d = (i64::from(new) - i64::from(old)).rem_euclid(0x8000);
    if d >= 0x4000 {
        d - 0x8000
    } else {
        d
    }
}

/// Counts of what a [`StreamDecoder`] threw away.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DecoderStats {
    /// Whole packets delivered.
    pub packets: u64,
    /// Packets dropped for a wrong checksum.
    pub bad_checksums: u64,
    /// Bytes skipped while looking for a header.
    pub skipped_bytes: u64,
}

/// Cuts a byte stream into packet bodies: resynchronises after garbage,
/// drops packets with bad checksums (counting them), and never holds more
/// than one packet's worth of bytes beyond what was last pushed.
#[derive(Clone, Debug, Default)]
pub struct StreamDecoder {
    buffer: Vec<u8>,
    stats: DecoderStats,
}

impl StreamDecoder {
    /// An empty decoder.
    pub fn new() -> Self {
        Self::default()
    }

    /// What it has delivered and dropped so far.
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Adds bytes read from the link.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buffer.extend_from_slice(bytes);
    }

    /// The next whole, valid packet body, if the bytes so far hold one.
    pub fn next_body(&mut self) -> Option<Vec<u8>> {
        loop {
            // Find a header; everything before it is garbage.
            let start = self.buffer.windows(2).position(|w| w == HEADER);
            let Some(start) = start else {
                // Keep a trailing 0xFA: it may begin a header.
                let keep = usize::from(self.buffer.last() == Some(&HEADER[0]));
                let skipped = self.buffer.len() - keep;
                self.stats.skipped_bytes += skipped as u64;
                self.buffer.drain(..skipped);
                return None;
            };
            if start > 0 {
                self.stats.skipped_bytes += start as u64;
                self.buffer.drain(..start);
            }
            let &count = self.buffer.get(2)?;
            let count = usize::from(count);
            if count < 2 {
                // No room for a checksum: not a packet header after all.
                self.stats.skipped_bytes += 1;
                self.buffer.drain(..1);
                continue;
            }
            if self.buffer.len() < 3 + count {
                return None;
            }
            let body = &self.buffer[3..1 + count];
            let sent = u16::from_be_bytes([self.buffer[1 + count], self.buffer[2 + count]]);
            if checksum(body) == sent {
                let body = body.to_vec();
                self.buffer.drain(..3 + count);
                self.stats.packets += 1;
                return Some(body);
            }
            // A bad packet, or a false header inside garbage: drop one byte
            // and look again, so a real header within is not lost.
            self.stats.bad_checksums += 1;
            self.buffer.drain(..1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_worked_frames_of_the_protocol_description() {
        assert_eq!(ClientCommand::Enable(true).packet(), [0xFA, 0xFB, 0x06, 0x04, 0x3B, 0x01, 0x00, 0x05, 0x3B]);
        assert_eq!(ClientCommand::Vel(300).packet(), [0xFA, 0xFB, 0x06, 0x0B, 0x3B, 0x2C, 0x01, 0x37, 0x3C]);
        assert_eq!(ClientCommand::RVel(-20).packet(), [0xFA, 0xFB, 0x06, 0x15, 0x1B, 0x14, 0x00, 0x29, 0x1B]);
        assert_eq!(ClientCommand::Sync1.packet(), [0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01]);
        assert_eq!(ClientCommand::Open.packet(), [0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01]);
        assert_eq!(ClientCommand::Sync0.packet(), [0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00]);
    }

    #[test]
    fn commands_round_trip() {
        use ClientCommand::*;
        for c in [
            Enable(false),
            SetA(-300),
            SetV(900),
            SetO,
            Move(-1200),
            Rotate(45),
            SetRv(100),
            Vel(-250),
            Head(90),
            DHead(-30),
            Config,
            RVel(20),
            Vel2(-5, 12),
            Vel2(-128, -1),
            Vel2(127, 0),
            SetRa(100),
            Sonar(true),
            Stop,
            BumpStall(3),
            HostBaud(2),
            EStop,
        ] {
            assert_eq!(ClientCommand::parse(&c.body()), Ok(c), "{c:?}");
        }
        assert_eq!(ClientCommand::parse(&[99]), Err(DecodeError::UnknownCommand(99)));
        assert!(matches!(ClientCommand::parse(&[11, 0x3B]), Err(DecodeError::Truncated { .. })));
        assert!(matches!(ClientCommand::parse(&[11, 0x77, 0, 0]), Err(DecodeError::BadArgument { .. })));
    }

    fn sample_sip() -> Sip {
        Sip {
            moving: true,
            xpos: 0x7FF0,
            ypos: 12,
            thpos: -1024,
            l_vel: 300,
            r_vel: -300,
            battery: 125,
            stall_and_bumpers: 0x0201,
            control: 5,
            flags: 0b100001,
            compass: 45,
            sonar: vec![(0, 1500), (7, 300)],
            tail: SipTail { grip_state: Some(1), battery_x10: Some(1251), rot_vel: Some(-55), ..SipTail::default() },
        }
    }

    #[test]
    fn sips_round_trip_with_their_tail() {
        let sip = sample_sip();
        let parsed = Sip::parse(&sip.body()).unwrap();
        // Fields before the last present one come back as zeros.
        assert_eq!(parsed.tail.anport, Some(0));
        assert_eq!(parsed.tail.fault_flags, None);
        assert_eq!((parsed.tail.battery_x10, parsed.tail.rot_vel), (Some(1251), Some(-55)));
        assert_eq!(Sip { tail: SipTail::default(), ..parsed.clone() }, Sip { tail: SipTail::default(), ..sip });
        assert!(parsed.motors_enabled() && parsed.estop() && parsed.stalled() && parsed.front_bumped());
        assert!(!parsed.rear_bumped());
    }

    #[test]
    fn a_sip_without_a_tail_and_a_truncated_one() {
        let mut sip = sample_sip();
        sip.tail = SipTail::default();
        assert_eq!(Sip::parse(&sip.body()).unwrap().tail, SipTail::default());
        let body = sip.body();
        assert!(matches!(Sip::parse(&body[..body.len() - 2]), Err(DecodeError::Truncated { .. })));
        assert_eq!(Sip::parse(&[0x20, 1, 2]), Err(DecodeError::NotASip(0x20)));
    }

    #[test]
    fn config_packets_round_trip_and_fail_cleanly_when_cut() {
        let config = ConfigPacket {
            robot_type: "Pioneer".into(),
            subtype: "powerbot".into(),
            serial_number: "PB-0042".into(),
            four_motors: 0,
            rot_vel_top: 360,
            trans_vel_top: 2000,
            rot_acc_top: 300,
            trans_acc_top: 1000,
            pwm_max: 1000,
            name: "bertha".into(),
            sip_cycle_ms: 100,
            host_baud: 2,
            aux_baud: 0,
            settings: ConfigSettings {
                watchdog_ms: 2000,
                trans_vel_max: 1500,
                rot_decel: 100,
                firmware_version: "1.9".into(),
                high_temperature_shutdown: -5,
                config_flags: 0x1234_5678,
                gyro_fw_version: -2,
                ..ConfigSettings::default()
            },
            rest: vec![1, 2, 3],
        };
        let body = config.body();
        assert_eq!(ConfigPacket::parse(&body), Ok(config.clone()));
        let mut settings = Vec::new();
        config.settings.write(&mut settings);
        let head = body.len() - settings.len() - config.rest.len();
        // Every cut short of the head is a clean error naming the field it
        // ran out in; a cut in the settings (an older firmware) keeps what
        // arrived and zeroes the rest.
        for end in 0..head {
            assert!(ConfigPacket::parse(&body[..end]).is_err(), "{end}");
        }
        let older = ConfigPacket::parse(&body[..head + 20]).unwrap();
        assert_eq!(older.settings.watchdog_ms, 2000);
        assert_eq!(older.settings.trans_vel_max, 0);
        assert!(older.rest.is_empty());
        let err = ConfigPacket::parse(&body[..30]).unwrap_err();
        assert!(err.to_string().contains("top"), "{err}");
        assert!(matches!(ConfigPacket::parse(&[0x32]), Err(DecodeError::UnexpectedPacket { .. })));
        assert_eq!(baud_code(38400), Some(2));
        assert_eq!(baud_of_code(4), Some(115200));
        assert_eq!(baud_code(14400), None);
    }

    #[test]
    fn identity_round_trips() {
        let id = Identity { name: "AMRISim".into(), class: "Pioneer".into(), subclass: "powerbot".into() };
        assert_eq!(Identity::parse(&id.body()).unwrap(), id);
        assert!(Identity::parse(&[1, 0]).is_err());
    }

    #[test]
    fn positions_unwrap_past_the_wrap_and_below_zero() {
        let mut u = Unwrapper::default();
        u.update(0x7FF0, 5);
        assert_eq!(u.update(0x0010, 3), (0x20, -2));
        // Backwards across zero into negative coordinates.
        let mut v = Unwrapper::default();
        v.update(10, 10);
        assert_eq!(v.update(0x7FF6, 10), (-20, 0));
        // The top bit is not part of the position.
        assert_eq!(v.update(0xFFF6, 10), (-20, 0));
    }

    #[test]
    fn the_decoder_resynchronises_and_counts() {
        let mut d = StreamDecoder::new();
        let good = ClientCommand::Vel(300).packet();
        let mut corrupt = ClientCommand::Vel(100).packet();
        *corrupt.last_mut().unwrap() ^= 0xFF;
        let mut stream = vec![0x00, 0xFA, 0x13, 0xFA];
        stream.extend(&corrupt);
        stream.extend(&good);
        // Byte by byte, as a serial line delivers.
        let mut bodies = Vec::new();
        for b in stream {
            d.push(&[b]);
            while let Some(body) = d.next_body() {
                bodies.push(body);
            }
        }
        assert_eq!(bodies, [ClientCommand::Vel(300).body()]);
        assert_eq!(d.stats().packets, 1);
        assert_eq!(d.stats().bad_checksums, 1);
        assert!(d.stats().skipped_bytes >= 3);
    }

    /// Feeds `chunks` to a decoder and every parser: no panic, bounded memory.
    fn feed(chunks: &[Vec<u8>]) -> Result<(), proptest::test_runner::TestCaseError> {
        let mut d = StreamDecoder::new();
        for chunk in chunks {
            d.push(chunk);
            while let Some(body) = d.next_body() {
                let _ = Sip::parse(&body);
                let _ = ClientCommand::parse(&body);
                let _ = Identity::parse(&body);
                let _ = ConfigPacket::parse(&body);
            }
            prop_assert!(d.buffer.len() <= 3 + 255 + chunk.len());
        }
        Ok(())
    }

    /// The fuzz run: a million random streams through the decoder and every
    /// parser. `cargo test --release -p ubf-robots -- --ignored million`.
    #[test]
    #[ignore = "a million cases: run it on purpose, in release"]
    fn a_million_random_streams() {
        use proptest::test_runner::{Config, TestRunner};
        let mut runner = TestRunner::new(Config { cases: 1_000_000, failure_persistence: None, ..Config::default() });
        runner
            .run(&proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..64), 0..16), |chunks| {
                feed(&chunks)
            })
            .unwrap();
    }

    proptest! {
        #[test]
        fn arbitrary_bytes_never_panic_and_memory_stays_bounded(chunks in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..64), 0..64)) {
            feed(&chunks)?;
        }

        #[test]
        fn framed_bodies_come_back_whole_amid_garbage(body in proptest::collection::vec(any::<u8>(), 0..MAX_BODY), junk in proptest::collection::vec(any::<u8>(), 0..40)) {
            let mut d = StreamDecoder::new();
            d.push(&junk.iter().map(|b| if *b == 0xFA { 0 } else { *b }).collect::<Vec<_>>());
            d.push(&frame(&body));
            prop_assert_eq!(d.next_body(), Some(body));
        }
    }
}
