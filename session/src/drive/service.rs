//! Telling systemd how a drive run as a service is doing (`Type=notify`):
//! ready once the robot is reached, alive on every tick while the control
//! loop turns (so `WatchdogSec=` restarts a hung controller), stopping on
//! the way out. Outside systemd (no `NOTIFY_SOCKET`) every call does
//! nothing.
//!
//! The protocol is one datagram per message to the socket systemd names.
//! It is sent without blocking, unlike the usual client libraries': the
//! tick loop must never wait for systemd, and a queue systemd has not yet
//! read (ten datagrams by default) would otherwise stall it. A message that
//! does not fit is dropped; a missed watchdog pet is made up on the next
//! tick.

use std::os::unix::net::{SocketAddr, UnixDatagram};
use std::time::{Duration, Instant};
use ubf_core::{TickRecord, TickSink};

/// Longest the stop sequence may take without a tick, µs: braking from
/// the top speed (at most 10 s allowed for) and its margins.
const STOP_SEQUENCE_USEC: u64 = 25_000_000;

/// The robot is reached and the drive under way.
pub(super) fn ready() {
    notify("READY=1");
}

/// A session is ending: the stop sequence (braking, motors off) runs
/// without ticks, so the watchdog is given time for it. The next session's
/// [`Watchdog`] sets it back.
pub(super) fn stop_sequence() {
    if Watchdog::from_env().is_some() {
        notify(&format!("WATCHDOG=1\nWATCHDOG_USEC={STOP_SEQUENCE_USEC}"));
    }
}

/// The drive is stopping the robot and closing down.
pub(super) fn stopping() {
    notify("STOPPING=1");
}

/// Sends `message` to the socket `NOTIFY_SOCKET` names (a path, or an
/// abstract name after `@`), without waiting.
fn notify(message: &str) {
    let Some(name) = std::env::var_os("NOTIFY_SOCKET") else { return };
    let sent = notify_socket(&name).and_then(|address| {
        let socket = UnixDatagram::unbound()?;
        socket.set_nonblocking(true)?;
        socket.send_to_addr(message.as_bytes(), &address)
    });
    match sent {
        Ok(_) => {}
        Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
            tracing::debug!("systemd has not read its notifications yet; {message:?} dropped");
        }
        Err(e) => tracing::warn!("telling systemd {message:?}: {e}"),
    }
}

/// The address of the socket systemd named.
fn notify_socket(name: &std::ffi::OsStr) -> std::io::Result<SocketAddr> {
    use std::os::unix::ffi::OsStrExt;
    match name.as_bytes().strip_prefix(b"@") {
        Some(abstract_name) => {
            use std::os::linux::net::SocketAddrExt;
            SocketAddr::from_abstract_name(abstract_name)
        }
        None => SocketAddr::from_pathname(name),
    }
}

/// A sink that pets systemd's watchdog from the tick loop, at most twice
/// per watchdog period: if the loop hangs, the pets stop and systemd
/// restarts the service.
pub(super) struct Watchdog {
    every: Duration,
    last: Option<Instant>,
    /// The period systemd asked for, µs.
    usec: u64,
}

impl Watchdog {
    /// The watchdog systemd asked for, if any: `WATCHDOG_USEC`, for this
    /// process (`WATCHDOG_PID`, when given, is ours).
    fn from_env() -> Option<Watchdog> {
        let usec: u64 = std::env::var("WATCHDOG_USEC").ok()?.parse().ok().filter(|&u| u > 0)?;
        let ours = std::env::var("WATCHDOG_PID").map_or(true, |pid| pid.parse() == Ok(std::process::id()));
        ours.then(|| Watchdog { every: Duration::from_micros(usec / 2), last: None, usec })
    }

    /// The watchdog for a session's ticks: the period systemd asked for,
    /// restored after an earlier session's stop sequence lengthened it.
    pub(super) fn for_session() -> Option<Watchdog> {
        let watchdog = Watchdog::from_env()?;
        notify(&format!("WATCHDOG_USEC={}", watchdog.usec));
        Some(watchdog)
    }
}

impl TickSink for Watchdog {
    fn record(&mut self, _: &TickRecord) -> std::io::Result<()> {
        if self.last.is_none_or(|at| at.elapsed() >= self.every) {
            self.last = Some(Instant::now());
            notify("WATCHDOG=1");
        }
        Ok(())
    }
}
