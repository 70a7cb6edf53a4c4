//! A real pan-tilt head: a FLIR (formerly Directed Perception) PTU on a
//! serial line or a TCP bridge, driven by its ASCII protocol, behind
//! [`ubf_core::PanTilt`]; and an emulator of that protocol to try it and
//! test it without the head.
//!
//! The protocol (PTU-D46 user's manual, §4): a command or query is a few
//! letters, an optional number and a delimiter (space or carriage return).
//! A command is answered `*`, a query `* RESULT`, a failure `! MESSAGE`;
//! `!P` and `!T` arrive unasked when an axis hits its limit. Positions are
//! whole encoder steps of a resolution the unit reports (`PR`, `TR`, in
//! arc-seconds per step), within limits it reports (`PN`, `PX`, `TN`,
//! `TX`). The driver turns echo off (`ED`) and asks for terse answers
//! (`FT`), then sends `PP<steps>` to aim and `PP`/`TP` to read the encoders.
//!
//! The serial line runs at 9 600 baud, a few milliseconds a character, so
//! the head is driven from a thread of its own: [`Ptu::command`] hands the
//! newest target over and returns at once, and [`Ptu::measured`] returns the
//! newest reading, refusing one older than `stale_after_s` (a head that
//! stopped answering must not pass for one that holds still).

use crate::arcos::emulator::client_left_terminal;
use crate::arcos::link::{self, Link};
use serde::Deserialize;
use std::f64::consts::TAU;
use std::io::{self, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use ubf_core::{Aim, PanTilt, RobotError};

/// A PTU as written under the camera in a robot file:
/// `pan_tilt: (connection: "/dev/ttyUSB1")`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PtuConfig {
    /// A serial device (`/dev/ttyUSB1`) or `tcp://host:port`.
    pub connection: String,
    /// Serial baud rate (the PTU's default: 9 600).
    #[serde(default = "PtuConfig::default_baud")]
    pub baud: u32,
    /// The tilt the head holds, ° above the horizontal: −90 to 90.
    #[serde(default, deserialize_with = "tilt_deg")]
    pub tilt_deg: f64,
    /// Whether the unit's positive pan turns the head clockwise seen from
    /// above (to the right). Ours turns it counter-clockwise (to the left);
    /// `ubf drive --dry-run` turns the head left first, to check.
    #[serde(default)]
    pub invert_pan: bool,
    /// Fastest pan, °/s (sent as the unit's pan speed on connecting).
    #[serde(default = "PtuConfig::default_rate", deserialize_with = "ubf_core::config::rate_deg_s")]
    pub max_rate_deg_s: f64,
    /// A reading older than this is refused as stale, s: up to 10.
    #[serde(default = "PtuConfig::default_stale", deserialize_with = "stale_after_s")]
    pub stale_after_s: f64,
}

fn tilt_deg<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    ubf_core::config::number_in(d, -90.0..=90.0, "from -90 to 90°")
}

fn stale_after_s<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    ubf_core::config::number_in(d, 0.001..=10.0, "from 0.001 to 10 s")
}

impl PtuConfig {
    fn default_baud() -> u32 {
        9600
    }
    fn default_rate() -> f64 {
        60.0
    }
    fn default_stale() -> f64 {
        0.5
    }

    /// A head on `connection` with the defaults.
    pub fn new(connection: impl Into<String>) -> Self {
        PtuConfig {
            connection: connection.into(),
            baud: Self::default_baud(),
            tilt_deg: 0.0,
            invert_pan: false,
            max_rate_deg_s: Self::default_rate(),
            stale_after_s: Self::default_stale(),
        }
    }
}

/// Longest wait for the answer to one command or query.
const ANSWER_WAIT: Duration = Duration::from_millis(1000);
/// Longest wait for the whole handshake and the first reading: a dozen
/// exchanges, a few milliseconds each at 9 600 baud.
const HANDSHAKE_WAIT: Duration = Duration::from_secs(3);
/// How long the unit must have been silent before the driver talks.
const QUIET_BEFORE_TALKING: Duration = Duration::from_millis(100);
/// Pause between two rounds of reading the encoders.
const POLL_PERIOD: Duration = Duration::from_millis(20);
/// The coarsest step a PTU has, arc-seconds: a PTU-D46's is 185″, and
/// finer with micro-stepping.
const MOST_STEP_ARC_S: f64 = 3600.0;
/// How far beyond its limits a reading may lie, steps (an axis stopped
/// at a limit may overshoot it a little).
const LIMIT_SLACK_STEPS: f64 = 10.0;
/// How much further than its set speed allows the pan may seem to move
/// between two readings, °: an encoder step or two, and the rounding of
/// a reading taken as the axis moves.
const READING_SLACK_DEG: f64 = 2.0;
/// The most of a line from the unit an error quotes, characters.
const MOST_QUOTED_CHARS: usize = 80;

/// What went wrong with the head: the fault a [`RobotError::PanTilt`]
/// carries, behind the head's connection.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PtuError {
    /// Its link could not be opened.
    #[error("opening its link: {0}")]
    Open(#[source] io::Error),
    /// Its thread could not be started.
    #[error("starting its thread: {0}")]
    Thread(#[source] io::Error),
    /// A command could not be written.
    #[error("writing `{command}`: {source}")]
    Write {
        /// The command.
        command: String,
        /// Why.
        source: io::Error,
    },
    /// Reading the link failed.
    #[error("reading: {0}")]
    Read(#[source] io::Error),
    /// The other end closed the link.
    #[error("the link closed")]
    Closed,
    /// No answer came in time.
    #[error("no answer to `{command}` within {within_ms} ms")]
    NoAnswer {
        /// The command or query.
        command: String,
        /// How long it was waited for, ms.
        within_ms: u128,
    },
    /// What came back is not lines: another device on the line.
    #[error("no line end in {bytes} bytes after `{command}`: is this a PTU?")]
    NoLineEnd {
        /// The command or query.
        command: String,
        /// Bytes that came without one.
        bytes: usize,
    },
    /// The unit refused a command or query.
    #[error("`{command}` refused: {message}")]
    Refused {
        /// The command or query.
        command: String,
        /// The unit's message.
        message: String,
    },
    /// A query's answer holds no number.
    #[error("`{query}` answered `{answer}`, not a number")]
    NotANumber {
        /// The query.
        query: String,
        /// Its answer.
        answer: String,
    },
    /// The unit reported a resolution no PTU has: angles computed with it
    /// would be nonsense.
    #[error("unusable resolution: {0:?} (a PTU's step is {MOST_STEP_ARC_S}\" at most, and more than 0)")]
    UnusableResolution(PtuAxes),
    /// The unit reported a minimum above a maximum.
    #[error("limits out of order (minimum above maximum): {0:?}")]
    LimitsOutOfOrder(PtuAxes),
    /// The unit reported limits beyond a full turn either way.
    #[error("limits beyond a full turn either way: {0:?}")]
    LimitsBeyondATurn(PtuAxes),
    /// A reading no head can give: outside the unit's own limits, or a pan
    /// that moved faster than the speed it was set to. Steered by, it
    /// would point the camera's views anywhere.
    #[error("`{query}` read {reading}: {why}")]
    Implausible {
        /// The query.
        query: &'static str,
        /// What it read, steps.
        reading: String,
        /// Why no head reads that.
        why: String,
    },
    /// An answer came that nothing asked for: something else is on the
    /// line, or the unit answered one query twice, and answers can no
    /// longer be told apart.
    #[error("an answer nobody asked for came before `{command}`: `{answer}`; is something else on the line?")]
    Unasked {
        /// The command or query about to be sent.
        command: String,
        /// What came.
        answer: String,
    },
    /// The newest reading is too old to trust: the head may have stopped
    /// answering, which must not pass for holding still.
    #[error("no reading for {for_s:.2} s (stale after {after_s} s)")]
    Stale {
        /// Age of the newest reading, s.
        for_s: f64,
        /// The age a reading is refused at, s.
        after_s: f64,
    },
    /// The unit kept sending before any command was sent to it.
    #[error("it kept sending for {within_ms} ms before anything was asked of it: is this a PTU?")]
    NeverQuiet {
        /// How long it was given, ms.
        within_ms: u128,
    },
    /// No reading has come yet.
    #[error("no reading yet")]
    NoReadingYet,
}

/// One answer of the unit.
#[derive(Clone, Debug, PartialEq)]
enum Answer {
    /// `*` and what follows it (empty for a command).
    Done(String),
    /// `!` and the unit's message.
    Refused(String),
}

/// What a line from the unit says: an answer, or nothing to wait on (an
/// empty line, a banner, unasked limit notices `!P` and `!T`, as a reset
/// sends them: `!T!T!P!P*`).
fn parse_line(line: &str) -> Option<Answer> {
    let line = line.trim();
    let notices = line.strip_suffix('*').unwrap_or(line);
    if notices.starts_with('!') && notices.split('!').skip(1).all(|n| n == "P" || n == "T") {
        return None;
    }
    // An echoed command comes before the marker: `PP-500 *`.
    let at = line.find(['*', '!'])?;
    let rest = line[at + 1..].trim().to_owned();
    Some(if line.as_bytes()[at] == b'*' { Answer::Done(rest) } else { Answer::Refused(rest) })
}

/// The first number in `text`: `-500` in `Current Pan position is -500`,
/// `185.1428` in `185.1428 seconds arc per Pan position`.
fn first_number(text: &str) -> Option<f64> {
    let bytes = text.as_bytes();
    let start = (0..bytes.len()).find(|&i| {
        bytes[i].is_ascii_digit() || (bytes[i] == b'-' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit))
    })?;
    let end =
        (start + 1..bytes.len()).find(|&i| !(bytes[i].is_ascii_digit() || bytes[i] == b'.')).unwrap_or(bytes.len());
    text[start..end].parse().ok()
}

/// Refuses `steps` read by `query` if it lies outside `limits`.
fn within_limits(query: &'static str, steps: f64, limits: [i64; 2]) -> Result<(), PtuError> {
    let (low, high) = (limits[0] as f64 - LIMIT_SLACK_STEPS, limits[1] as f64 + LIMIT_SLACK_STEPS);
    match (low..=high).contains(&steps) {
        true => Ok(()),
        false => Err(PtuError::Implausible {
            query,
            reading: ubf_core::config::shown(steps),
            why: format!("outside the limits the unit reported, {} to {} steps", limits[0], limits[1]),
        }),
    }
}

/// What the unit said, as it is shown in an error: control characters
/// escaped (a terminal would obey them), and cut short.
fn printable(bytes: &[u8]) -> String {
    crate::printable::text_cut(bytes.trim_ascii(), MOST_QUOTED_CHARS)
}

/// The unit's side of the conversation: one command at a time, each
/// waited on.
struct Conversation {
    link: Box<dyn Link>,
    /// Bytes read and not yet a whole line.
    pending: Vec<u8>,
    /// When every answer must have come by (the handshake's), if ever.
    until: Option<Instant>,
}

impl Conversation {
    /// Sends `text` and a delimiter, and waits for the answer.
    fn ask(&mut self, text: &str) -> Result<Answer, PtuError> {
        // Whole lines already read are not this query's answer: were one
        // of them an answer, the next would be taken for this one's.
        while let Some(line) = self.next_line() {
            if parse_line(&String::from_utf8_lossy(&line)).is_some() {
                return Err(PtuError::Unasked { command: text.to_owned(), answer: printable(&line) });
            }
        }
        let written = |source| PtuError::Write { command: text.to_owned(), source };
        self.link.write_all(format!("{text} ").as_bytes()).map_err(written)?;
        self.link.flush().map_err(written)?;
        let started = Instant::now();
        let deadline = self.until.map_or(started + ANSWER_WAIT, |until| until.min(started + ANSWER_WAIT));
        loop {
            while let Some(line) = self.next_line() {
                if let Some(answer) = parse_line(&String::from_utf8_lossy(&line)) {
                    return Ok(answer);
                }
            }
            if self.pending.len() > 4096 {
                return Err(PtuError::NoLineEnd { command: text.to_owned(), bytes: self.pending.len() });
            }
            if Instant::now() > deadline {
                let within_ms = (deadline - started).as_millis();
                return Err(PtuError::NoAnswer { command: text.to_owned(), within_ms });
            }
            let mut buffer = [0u8; 256];
            match self.link.read(&mut buffer) {
                Ok(0) => return Err(PtuError::Closed),
                Ok(n) => self.pending.extend_from_slice(&buffer[..n]),
                Err(e) if link::is_timeout(&e) => {}
                Err(e) => return Err(PtuError::Read(e)),
            }
        }
    }

    /// The first whole line read and not yet taken, its end included.
    fn next_line(&mut self) -> Option<Vec<u8>> {
        let end = self.pending.iter().position(|b| *b == b'\r' || *b == b'\n')?;
        Some(self.pending.drain(..=end).collect())
    }

    /// A command that must be done.
    fn command(&mut self, text: &str) -> Result<(), PtuError> {
        match self.ask(text)? {
            Answer::Done(_) => Ok(()),
            Answer::Refused(message) => Err(refused(text, &message)),
        }
    }

    /// A query whose answer is a number.
    fn number(&mut self, text: &str) -> Result<f64, PtuError> {
        match self.ask(text)? {
            Answer::Done(answer) => first_number(&answer)
                .filter(|n| n.is_finite())
                .ok_or_else(|| PtuError::NotANumber { query: text.to_owned(), answer: printable(answer.as_bytes()) }),
            Answer::Refused(message) => Err(refused(text, &message)),
        }
    }
}

/// The unit's refusal of `command`, its `message` made fit to show.
fn refused(command: &str, message: &str) -> PtuError {
    PtuError::Refused { command: command.to_owned(), message: printable(message.as_bytes()) }
}

/// What the unit reported of itself on connecting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PtuAxes {
    /// Pan per encoder step, rad.
    pub pan_step: f64,
    /// Tilt per encoder step, rad.
    pub tilt_step: f64,
    /// Pan limits, encoder steps.
    pub pan_limits: [i64; 2],
    /// Tilt limits, encoder steps.
    pub tilt_limits: [i64; 2],
}

/// A pan read, and when it was asked for: the earliest the unit can have
/// measured it.
#[derive(Clone, Copy, Debug)]
struct PanRead {
    asked: Instant,
    pan: f64,
}

/// Readings and targets shared with the unit's thread.
#[derive(Debug, Default)]
struct Shared {
    /// The newest target not yet sent.
    target: Option<Aim>,
    /// The newest reading and when it was taken.
    reading: Option<(Instant, Aim)>,
    /// Why the thread stopped, if it did (shared: every later command and
    /// reading reports it).
    failure: Option<Arc<PtuError>>,
}

/// A PTU head, driven from a thread of its own.
pub struct Ptu {
    config: PtuConfig,
    axes: PtuAxes,
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Ptu {
    /// Opens the head's link, sets it up (echo off, terse answers, pan
    /// speed, the held tilt) and reads its resolution, limits and angles;
    /// then keeps reading its encoders until dropped.
    pub fn connect(config: PtuConfig) -> Result<Ptu, RobotError> {
        let failed = |fault: PtuError| RobotError::PanTilt { unit: config.connection.clone(), fault: Box::new(fault) };
        let link = link::open(&config.connection, config.baud).map_err(|e| failed(PtuError::Open(e)))?;
        // Bounded as a whole, not only answer by answer: a head that
        // answers each query just in time must not hold the drive (deaf to
        // Ctrl-C until it has connected) for a dozen seconds.
        let until = Some(Instant::now() + HANDSHAKE_WAIT);
        let mut talk = Conversation { link, pending: Vec::new(), until };
        let axes = Self::handshake(&mut talk, &config).map_err(failed)?;
        let (first, pan_read) = Self::read(&mut talk, &axes, &config, None).map_err(failed)?;
        talk.until = None;
        let shared = Arc::new(Mutex::new(Shared { reading: Some(first), ..Shared::default() }));
        let stop = Arc::new(AtomicBool::new(false));
        let (for_thread, flag, settings) = (Arc::clone(&shared), Arc::clone(&stop), config.clone());
        let thread = std::thread::Builder::new()
            .name("pan-tilt".into())
            .spawn(move || Self::run(talk, axes, settings, pan_read, &for_thread, &flag))
            .map_err(|e| failed(PtuError::Thread(e)))?;
        Ok(Ptu { config, axes, shared, stop, thread: Some(thread) })
    }

    /// What the unit reported of itself.
    pub fn axes(&self) -> PtuAxes {
        self.axes
    }

    fn handshake(talk: &mut Conversation, config: &PtuConfig) -> Result<PtuAxes, PtuError> {
        // Whatever the unit says before it falls quiet (a power-up banner,
        // a reset's limit notices, at 9 600 baud longer than a moment) is
        // not ours.
        let mut scratch = [0u8; 256];
        let mut quiet_until = Instant::now() + QUIET_BEFORE_TALKING;
        while Instant::now() < quiet_until {
            if talk.until.is_some_and(|until| Instant::now() > until) {
                return Err(PtuError::NeverQuiet { within_ms: HANDSHAKE_WAIT.as_millis() });
            }
            match talk.link.read(&mut scratch) {
                Ok(0) => return Err(PtuError::Closed),
                Ok(_) => quiet_until = Instant::now() + QUIET_BEFORE_TALKING,
                Err(e) if link::is_timeout(&e) => {}
                Err(e) => return Err(PtuError::Read(e)),
            }
        }
        talk.command("ED")?;
        talk.command("FT")?;
        // Positions run as sent (a unit saved in slaved mode waits for an
        // `A` before moving), each axis under position control (one saved
        // in velocity mode would take a position for a speed). A unit too
        // old to know `CI` has no other mode.
        talk.command("I")?;
        let _ = talk.ask("CI")?;
        let arc_seconds = |s: f64| (s / 3600.0).to_radians();
        let whole = |v: f64| v.round() as i64;
        let axes = PtuAxes {
            pan_step: arc_seconds(talk.number("PR")?),
            tilt_step: arc_seconds(talk.number("TR")?),
            pan_limits: [whole(talk.number("PN")?), whole(talk.number("PX")?)],
            tilt_limits: [whole(talk.number("TN")?), whole(talk.number("TX")?)],
        };
        let usable = |step: f64| step > 0.0 && step <= arc_seconds(MOST_STEP_ARC_S);
        if !(usable(axes.pan_step) && usable(axes.tilt_step)) {
            return Err(PtuError::UnusableResolution(axes));
        }
        if axes.pan_limits[0] > axes.pan_limits[1] || axes.tilt_limits[0] > axes.tilt_limits[1] {
            return Err(PtuError::LimitsOutOfOrder(axes));
        }
        let within_a_turn = |limits: [i64; 2], step: f64| limits.iter().all(|&l| (l as f64 * step).abs() <= TAU);
        if !(within_a_turn(axes.pan_limits, axes.pan_step) && within_a_turn(axes.tilt_limits, axes.tilt_step)) {
            return Err(PtuError::LimitsBeyondATurn(axes));
        }
        talk.command(&format!("PS{}", Self::pan_speed_steps(config, &axes)))?;
        let tilt = Self::steps(config.tilt_deg.to_radians(), axes.tilt_step, axes.tilt_limits);
        talk.command(&format!("TP{tilt}"))?;
        Ok(axes)
    }

    /// `angle` in whole steps, within `limits`.
    fn steps(angle: f64, step: f64, limits: [i64; 2]) -> i64 {
        ((angle / step).round() as i64).clamp(limits[0], limits[1])
    }

    /// The sign that turns our pan (counter-clockwise) into the unit's.
    fn pan_sign(config: &PtuConfig) -> f64 {
        if config.invert_pan {
            -1.0
        } else {
            1.0
        }
    }

    /// The head's angles, and when the pan was read: halfway through its
    /// query, the best guess at when the unit answered; and that pan, with
    /// when it was asked for, for the next reading's check.
    ///
    /// A reading outside the unit's limits, or a pan that moved further
    /// since the `last` than the speed sent allows between that query's
    /// asking and this one's answer (and 2°), is refused.
    fn read(
        talk: &mut Conversation,
        axes: &PtuAxes,
        config: &PtuConfig,
        last: Option<PanRead>,
    ) -> Result<((Instant, Aim), PanRead), PtuError> {
        let asked = Instant::now();
        let pan_steps = talk.number("PP")?;
        let answered = Instant::now();
        let read_at = asked + (answered - asked) / 2;
        let tilt_steps = talk.number("TP")?;
        within_limits("PP", pan_steps, axes.pan_limits)?;
        within_limits("TP", tilt_steps, axes.tilt_limits)?;
        let aim = Aim { pan: pan_steps * axes.pan_step * Self::pan_sign(config), tilt: tilt_steps * axes.tilt_step };
        if let Some(last) = last {
            let seconds = (answered - last.asked).as_secs_f64();
            let speed = Self::pan_speed_steps(config, axes) * axes.pan_step;
            let moved = (aim.pan - last.pan).abs();
            if moved > speed * seconds + READING_SLACK_DEG.to_radians() {
                let why = format!(
                    "the pan moved {:.1}° in {seconds:.2} s, faster than the {:.1}°/s it was set to",
                    moved.to_degrees(),
                    speed.to_degrees()
                );
                let reading = ubf_core::config::shown(pan_steps);
                return Err(PtuError::Implausible { query: "PP", reading, why });
            }
        }
        Ok(((read_at, aim), PanRead { asked, pan: aim.pan }))
    }

    /// The pan speed sent to the unit, steps a second: the fastest set,
    /// in whole steps.
    fn pan_speed_steps(config: &PtuConfig, axes: &PtuAxes) -> f64 {
        (config.max_rate_deg_s.to_radians() / axes.pan_step).round().max(1.0)
    }

    /// The unit's thread: sends the newest target, reads the encoders,
    /// again, until stopped or the unit fails; then halts the head.
    fn run(
        mut talk: Conversation,
        axes: PtuAxes,
        config: PtuConfig,
        mut last: PanRead,
        shared: &Mutex<Shared>,
        stop: &AtomicBool,
    ) {
        let lock = || shared.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        while !stop.load(Ordering::Relaxed) {
            let target = lock().target.take();
            let sent = target.map_or(Ok(()), |aim| {
                let pan = Self::steps(aim.pan * Self::pan_sign(&config), axes.pan_step, axes.pan_limits);
                talk.command(&format!("PP{pan}"))
            });
            match sent.and_then(|()| Self::read(&mut talk, &axes, &config, Some(last))) {
                Ok((reading, pan_read)) => {
                    last = pan_read;
                    lock().reading = Some(reading);
                }
                Err(e) => {
                    lock().failure = Some(Arc::new(e));
                    return;
                }
            }
            std::thread::sleep(POLL_PERIOD);
        }
        // On the way out the head stops where it is.
        let _ = talk.command("H");
    }

    /// The state shared with the thread; a panicked thread leaves it usable.
    fn shared(&self) -> std::sync::MutexGuard<'_, Shared> {
        self.shared.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// `fault`, as the error of the head on this connection.
    fn fault(&self, fault: impl std::error::Error + Send + Sync + 'static) -> RobotError {
        RobotError::PanTilt { unit: self.config.connection.clone(), fault: Box::new(fault) }
    }

    fn failure(&self) -> Option<RobotError> {
        let failure = self.shared().failure.clone();
        failure.map(|e| self.fault(e))
    }
}

impl PanTilt for Ptu {
    fn command(&mut self, aim: Aim) -> Result<(), RobotError> {
        if let Some(failure) = self.failure() {
            return Err(failure);
        }
        self.shared().target = Some(aim);
        Ok(())
    }

    fn measured(&mut self) -> Result<Aim, RobotError> {
        self.measured_at().map(|(_, aim)| aim)
    }

    fn measured_at(&mut self) -> Result<(Instant, Aim), RobotError> {
        if let Some(failure) = self.failure() {
            return Err(failure);
        }
        let reading = self.shared().reading;
        match reading {
            Some((at, aim)) if at.elapsed().as_secs_f64() <= self.config.stale_after_s => Ok((at, aim)),
            Some((at, _)) => {
                let (for_s, after_s) = (at.elapsed().as_secs_f64(), self.config.stale_after_s);
                Err(self.fault(PtuError::Stale { for_s, after_s }))
            }
            None => Err(self.fault(PtuError::NoReadingYet)),
        }
    }
}

impl Drop for Ptu {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(handle) = self.thread.take() {
            let _ = handle.join();
        }
    }
}

/// The emulated head's make-up: a PTU-D46's resolution and limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PtuEmulatorConfig {
    /// Arc-seconds per step, both axes.
    pub arc_seconds_per_step: f64,
    /// Pan limits, steps.
    pub pan_limits: [i64; 2],
    /// Tilt limits, steps.
    pub tilt_limits: [i64; 2],
    /// Whether positive pan steps turn the head clockwise (its truth, which
    /// a client's `invert_pan` must match).
    pub clockwise_positive: bool,
}

impl Default for PtuEmulatorConfig {
    fn default() -> Self {
        PtuEmulatorConfig {
            arc_seconds_per_step: 185.1428,
            pan_limits: [-3090, 3090],
            tilt_limits: [-907, 604],
            clockwise_positive: false,
        }
    }
}

/// The emulated head's state as its last client left it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PtuEmulatorReport {
    /// Commands and queries answered.
    pub commands: u64,
    /// The true pan at the end, counter-clockwise from ahead, rad.
    pub pan: f64,
    /// The true tilt, rad.
    pub tilt: f64,
}

/// One axis of the emulated head: where it is, where it goes, how fast.
#[derive(Clone, Copy, Debug)]
struct Axis {
    position: f64,
    target: f64,
    /// Steps per second.
    speed: f64,
    limits: [i64; 2],
}

impl Axis {
    fn advance(&mut self, seconds: f64) {
        let gap = self.target - self.position;
        self.position += gap.clamp(-self.speed * seconds, self.speed * seconds);
    }
}

/// Serves one client on `link` as a PTU would, in real time, until the
/// client goes or `stop` is set. The head starts as a PTU powers up: echo
/// on, verbose answers, both axes at 0.
pub fn serve_ptu(
    mut link: Box<dyn Link>,
    config: &PtuEmulatorConfig,
    stop: &AtomicBool,
) -> io::Result<PtuEmulatorReport> {
    let mut pan = Axis { position: 0.0, target: 0.0, speed: 1000.0, limits: config.pan_limits };
    let mut tilt = Axis { position: 0.0, target: 0.0, speed: 1000.0, limits: config.tilt_limits };
    let (mut echo, mut verbose) = (true, true);
    let mut report = PtuEmulatorReport::default();
    let mut word = Vec::new();
    let mut last = Instant::now();
    let step = (config.arc_seconds_per_step / 3600.0).to_radians();
    let ccw = if config.clockwise_positive { -1.0 } else { 1.0 };
    let finish = |report: &mut PtuEmulatorReport, pan: &Axis, tilt: &Axis| {
        report.pan = pan.position * step * ccw;
        report.tilt = tilt.position * step;
    };
    while !stop.load(Ordering::Relaxed) {
        let mut buffer = [0u8; 256];
        let n = match link.read(&mut buffer) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if link::is_timeout(&e) => 0,
            Err(e) if e.kind() == io::ErrorKind::ConnectionReset || client_left_terminal(&e) => break,
            Err(e) => return Err(e),
        };
        let now = Instant::now();
        let seconds = now.duration_since(last).as_secs_f64();
        last = now;
        pan.advance(seconds);
        tilt.advance(seconds);
        let mut out = String::new();
        for &byte in &buffer[..n] {
            if byte != b' ' && byte != b'\r' && byte != b'\n' {
                // A word longer than any command is garbage: kept short, so
                // a client that never sends a delimiter cannot fill memory.
                if word.len() < 32 {
                    word.push(byte);
                }
                continue;
            }
            if word.is_empty() {
                continue;
            }
            let text = String::from_utf8_lossy(&word).to_ascii_uppercase();
            word.clear();
            report.commands += 1;
            let answer = answer(&text, &mut pan, &mut tilt, &mut echo, &mut verbose, config);
            let echoed = if echo { format!("{text} ") } else { String::new() };
            out.push_str(&format!("{echoed}{answer}\r\n"));
        }
        if out.is_empty() {
            continue;
        }
        match link.write_all(out.as_bytes()).and_then(|()| link.flush()) {
            Ok(()) => {}
            // The client went between its command and our answer.
            Err(e) if e.kind() == io::ErrorKind::ConnectionReset || client_left_terminal(&e) => break,
            Err(e) => return Err(e),
        }
    }
    finish(&mut report, &pan, &tilt);
    Ok(report)
}

/// The answer to one command or query.
fn answer(
    text: &str,
    pan: &mut Axis,
    tilt: &mut Axis,
    echo: &mut bool,
    verbose: &mut bool,
    config: &PtuEmulatorConfig,
) -> String {
    let say =
        |verbose: bool, long: String, short: String| if verbose { format!("* {long}") } else { format!("* {short}") };
    // Two letters, then the argument; anything may arrive, so by characters.
    let name_end = text.char_indices().nth(2).map_or(text.len(), |(i, _)| i);
    let (name, argument) = text.split_at(name_end);
    let value: Option<i64> = (!argument.is_empty()).then(|| argument.parse().ok()).flatten();
    if !argument.is_empty() && value.is_none() {
        return "! Illegal Command argument".into();
    }
    if matches!(name, "H" | "HP" | "HT") && value.is_none() {
        pan.target = pan.position;
        tilt.target = tilt.position;
        return "*".into();
    }
    // The axis a pan (P…) or tilt (T…) command names.
    let (axis, axis_name) = if name.starts_with('P') { (pan, "Pan") } else { (tilt, "Tilt") };
    match (name, value) {
        ("ED", None) => {
            *echo = false;
            "*".into()
        }
        ("EE", None) => {
            *echo = true;
            "*".into()
        }
        ("FT", None) => {
            *verbose = false;
            "*".into()
        }
        ("FV", None) => {
            *verbose = true;
            "*".into()
        }
        // Immediate execution and independent position control: the only
        // modes emulated.
        ("I" | "CI", None) => "*".into(),
        ("PR" | "TR", None) => say(
            *verbose,
            format!("{} seconds arc per {axis_name} position", config.arc_seconds_per_step),
            config.arc_seconds_per_step.to_string(),
        ),
        ("PN" | "TN" | "PX" | "TX", None) => {
            let (word, limit) =
                if name.ends_with('N') { ("Minimum", axis.limits[0]) } else { ("Maximum", axis.limits[1]) };
            say(*verbose, format!("{word} {axis_name} position is {limit}"), limit.to_string())
        }
        ("PP" | "TP", None) => {
            let at = axis.position.round() as i64;
            say(*verbose, format!("Current {axis_name} position is {at}"), at.to_string())
        }
        ("PP" | "TP", Some(target)) => {
            if target > axis.limits[1] {
                format!("! Maximum allowable {axis_name} position is {}", axis.limits[1])
            } else if target < axis.limits[0] {
                format!("! Minimum allowable {axis_name} position is {}", axis.limits[0])
            } else {
                axis.target = target as f64;
                "*".into()
            }
        }
        ("PS" | "TS", Some(speed)) if speed > 0 => {
            axis.speed = speed as f64;
            "*".into()
        }
        ("PS" | "TS", None) => {
            say(*verbose, format!("Target speed is {} positions/sec", axis.speed), axis.speed.to_string())
        }
        _ => "! Illegal Command argument".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn answers_are_read_with_or_without_echo_and_verbosity() {
        assert_eq!(
            parse_line("PP * Current Pan position is -500\r"),
            Some(Answer::Done("Current Pan position is -500".into()))
        );
        assert_eq!(parse_line("* 22"), Some(Answer::Done("22".into())));
        assert_eq!(parse_line("ED *"), Some(Answer::Done(String::new())));
        assert_eq!(
            parse_line("PP9999 ! Maximum allowable Pan position is 3090"),
            Some(Answer::Refused("Maximum allowable Pan position is 3090".into()))
        );
        // Unasked limit notices and banners are not answers.
        assert_eq!(parse_line("!P"), None);
        assert_eq!(parse_line("!T!T!P!P*"), None);
        assert_eq!(parse_line("!"), Some(Answer::Refused(String::new())));
        assert_eq!(parse_line("Pan-Tilt Controller v2.14.0"), None);
        assert_eq!(first_number("Current Pan position is -500"), Some(-500.0));
        assert_eq!(first_number("185.1428 seconds arc per Pan position"), Some(185.1428));
        assert_eq!(first_number("no number"), None);
        assert_eq!(first_number("-"), None);
    }

    #[test]
    fn the_emulator_refuses_garbage_without_panicking() {
        let config = PtuEmulatorConfig::default();
        let mut pan = Axis { position: 0.0, target: 0.0, speed: 1.0, limits: config.pan_limits };
        let mut tilt = pan;
        let (mut echo, mut verbose) = (true, true);
        for garbage in ["\u{fffd}\u{fffd}", "P\u{20ac}5", "€", "PP99999999999999999999", "PPx", "Z"] {
            let said = answer(garbage, &mut pan, &mut tilt, &mut echo, &mut verbose, &config);
            assert!(said.starts_with('!'), "{garbage}: {said}");
        }
        assert_eq!(pan.target, 0.0);
    }
}
