//! The CONFIG packet (the controller's identity, limits and current
//! settings) and the baud codes HOSTBAUD and CONFIG speak in.

use super::decode::{DecodeError, Reader};

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
        let mut r = Reader::new(body);
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
