//! What the client sends: commands, their bodies and their packets, and
//! their parsing back (what an emulator of the robot needs).

use super::decode::DecodeError;
use super::stream::frame;

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
