//! The byte link to a controller: a serial port or a TCP socket (a robot
//! simulator at `host:8101`), behind one trait.

use std::io::{self, Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::time::Duration;

/// How long a read waits before giving the caller a chance to do other
/// work (a watchdog, a stop flag).
pub const READ_TIMEOUT: Duration = Duration::from_millis(20);

/// Longest a write may wait for a peer that has stopped reading.
pub const WRITE_TIMEOUT: Duration = Duration::from_millis(500);

/// Longest a TCP connection may take to open. A robot on the local network
/// answers in milliseconds; one that never answers (its queue full, the
/// packets dropped) would otherwise hold the connect for two minutes, deaf
/// to a stop.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(2);

/// A two-way byte link. Reads time out after [`READ_TIMEOUT`] with
/// `TimedOut` or `WouldBlock`, which callers treat as "nothing yet".
pub trait Link: Read + Write + Send {
    /// A second handle on the same link, so one thread can read while
    /// another writes.
    fn try_clone_link(&self) -> io::Result<Box<dyn Link>>;

    /// The line's baud rate, or `None` for a link without one (TCP).
    fn baud(&self) -> Option<u32>;

    /// Changes the line's baud rate (nothing to do on a link without one).
    fn set_baud(&mut self, baud: u32) -> io::Result<()>;
}

impl Link for TcpStream {
    fn try_clone_link(&self) -> io::Result<Box<dyn Link>> {
        Ok(Box::new(self.try_clone()?))
    }

    fn baud(&self) -> Option<u32> {
        None
    }

    fn set_baud(&mut self, _baud: u32) -> io::Result<()> {
        Ok(())
    }
}

#[cfg(unix)]
impl Link for serialport::TTYPort {
    fn try_clone_link(&self) -> io::Result<Box<dyn Link>> {
        Ok(Box::new(self.try_clone_native().map_err(io::Error::other)?))
    }

    fn baud(&self) -> Option<u32> {
        serialport::SerialPort::baud_rate(self).ok()
    }

    fn set_baud(&mut self, baud: u32) -> io::Result<()> {
        serialport::SerialPort::set_baud_rate(self, baud).map_err(io::Error::other)
    }
}

/// A new pseudo-terminal for an emulated robot: its master end (raw, with
/// the read timeout) and the path a client opens as the robot's serial
/// port. The slave end is left closed, so the master reads EIO until a
/// client opens it.
#[cfg(unix)]
pub fn pseudo_terminal() -> io::Result<(serialport::TTYPort, String)> {
    let (mut master, slave) = serialport::TTYPort::pair().map_err(io::Error::other)?;
    serialport::SerialPort::set_timeout(&mut master, READ_TIMEOUT).map_err(io::Error::other)?;
    let path =
        serialport::SerialPort::name(&slave).ok_or_else(|| io::Error::other("the pseudo-terminal has no name"))?;
    Ok((master, path))
}

/// Whether an I/O error only means "no bytes yet".
pub fn is_timeout(e: &io::Error) -> bool {
    matches!(e.kind(), io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted)
}

/// Opens `address`: `tcp://host:port`, or a serial device path opened at
/// `baud`.
pub fn open(address: &str, baud: u32) -> io::Result<Box<dyn Link>> {
    if let Some(host) = address.strip_prefix("tcp://") {
        let stream = connect_tcp(host)?;
        stream.set_nodelay(true)?;
        stream.set_read_timeout(Some(READ_TIMEOUT))?;
        // A peer that stops reading must not hang a STOP on its way out.
        stream.set_write_timeout(Some(WRITE_TIMEOUT))?;
        return Ok(Box::new(stream));
    }
    open_serial(address, baud)
}

/// Connects to `host` (`name:port`) at the first of its addresses that
/// answers within [`CONNECT_TIMEOUT`].
fn connect_tcp(host: &str) -> io::Result<TcpStream> {
    let mut last = None;
    for address in host.to_socket_addrs()? {
        match TcpStream::connect_timeout(&address, CONNECT_TIMEOUT) {
            Ok(stream) => return Ok(stream),
            Err(e) => last = Some(e),
        }
    }
    Err(last.unwrap_or_else(|| io::Error::new(io::ErrorKind::NotFound, format!("{host}: no address"))))
}

#[cfg(unix)]
fn open_serial(path: &str, baud: u32) -> io::Result<Box<dyn Link>> {
    let port = serialport::new(path, baud).timeout(READ_TIMEOUT).open_native().map_err(io::Error::other)?;
    Ok(Box::new(port))
}

#[cfg(not(unix))]
fn open_serial(path: &str, _baud: u32) -> io::Result<Box<dyn Link>> {
    Err(io::Error::other(format!("{path}: serial ports are supported on Unix only")))
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    #[test]
    fn a_robot_that_never_answers_the_connection_is_given_up_on() {
        // A listener whose one queued connection is taken: the next one's
        // SYN goes unanswered, which a plain connect waits two minutes for.
        let listener = socket2::Socket::new(socket2::Domain::IPV4, socket2::Type::STREAM, None).unwrap();
        listener.bind(&std::net::SocketAddr::from(([127, 0, 0, 1], 0)).into()).unwrap();
        listener.listen(0).unwrap();
        let address = listener.local_addr().unwrap().as_socket().unwrap();
        let _queued = TcpStream::connect(address).unwrap();
        let asked = std::time::Instant::now();
        let refused = open(&format!("tcp://{address}"), 0).map(drop).unwrap_err();
        let took = asked.elapsed();
        assert_eq!(refused.kind(), io::ErrorKind::TimedOut, "{refused}");
        assert!(took < CONNECT_TIMEOUT * 3, "gave up after {took:?}");
    }
}
