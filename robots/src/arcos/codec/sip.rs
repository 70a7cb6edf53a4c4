//! What the controller sends: the server information packets (SIPs) of
//! every cycle, and the reply to SYNC2 that names the robot.

use super::decode::{DecodeError, Reader};
use super::stream::MAX_BODY;

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
        let mut r = Reader::new(body);
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
        let mut parts = rest.split(|&b| b == 0).map(crate::printable::text);
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

#[cfg(test)]
mod tests {
    use super::*;

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
    fn identity_round_trips() {
        let id = Identity { name: "AMRISim".into(), class: "Pioneer".into(), subclass: "powerbot".into() };
        assert_eq!(Identity::parse(&id.body()).unwrap(), id);
        assert!(Identity::parse(&[1, 0]).is_err());
    }

    #[test]
    fn a_name_with_control_characters_is_read_escaped() {
        // A terminal would clear itself; a log would show a forged line.
        let body = b"\x02\x1b[2J\nerror: fake\0Pioneer\0powerbot\0";
        assert_eq!(Identity::parse(body).unwrap().name, "\\u{1b}[2J\\nerror: fake");
    }
}
