//! `ubf drive`, `ubf emulate-powerbot` and `ubf emulate-ptu`: the real
//! robot, and stand-ins for it and its pan-tilt head.

use super::{CliError, Exit, Outcome};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use ubf_core::Registry;
use ubf_robots::arcos::emulator::{EmulatorConfig, EmulatorReport};
use ubf_robots::arcos::link::Link;
use ubf_robots::ptu::PtuEmulatorConfig;

/// What `ubf drive` is asked to do besides driving its file.
#[derive(Debug, clap::Args)]
pub(super) struct DriveOptions {
    /// Connect and show the robot's identity, odometry and sonar without
    /// enabling the motors.
    #[arg(long)]
    pub dry_run: bool,
    /// Show the live state (link, pose, speeds, winning behaviour, hold)
    /// on stderr even when it is not a terminal (on a terminal it is
    /// always shown, on one updating line).
    #[arg(long)]
    pub status: bool,
    /// End the drive once the robot believes it is at the goal (the
    /// robot is stopped and the session closed); without it the tree
    /// holds the robot there until Ctrl-C.
    #[arg(long)]
    pub until_goal: bool,
    /// Publish the drive on ROS 2 (in `ROS_DOMAIN_ID`): `/tf`, `/odom`,
    /// `/scan`, `/ubf/tick`, `/ubf/goal`, `/ubf/pose/...`. A ROS 2 robot
    /// (`connection: "ros2"`) always publishes `/ubf/tick`, `/ubf/goal`
    /// and the poses; its own driver publishes the rest.
    #[arg(long)]
    pub ros2: bool,
    /// Serve the drive live to Foxglove on this address (e.g.
    /// `127.0.0.1:8765`; port 0 picks a free one): the topics of its
    /// MCAP log on the Foxglove WebSocket protocol. Anyone who can
    /// reach the address can watch (but not steer).
    #[arg(long, value_name = "ADDRESS")]
    pub live: Option<std::net::SocketAddr>,
    /// Watch the robot file: each edit of its tree is checked and
    /// swapped in at a tick boundary; an edit that fails its check, or
    /// changes more than the tree (the connection, the model, the
    /// goal…), is refused and the running tree goes on.
    #[arg(long)]
    pub watch: bool,
}

/// Drives the robot (or only looks at it, `dry_run`) until stopped.
pub(super) fn drive(registry: &Registry, file: &Path, options: DriveOptions) -> Outcome {
    let DriveOptions { dry_run, status, until_goal, ros2, live, watch } = options;
    use crate::drive::{DriveConfig, DriveEnd};
    let (mut config, model) = DriveConfig::load(registry, file).map_err(CliError::bad_input)?;
    config.until_goal |= until_goal;
    config.publish_ros2 |= ros2;
    config.live = live.or(config.live);
    let domain_from_env = config.ros2.as_ref().is_none_or(|r| r.domain_id.is_none());
    if domain_from_env && (config.connection == crate::drive::robot_file::ROS2_CONNECTION || config.publish_ros2) {
        ubf_robots::ros2::domain_from_env().map_err(CliError::bad_input)?;
    }
    let stop = crate::drive::install_stop_flag();
    if dry_run {
        crate::drive::dry_run(&config, &model, &stop).map_err(CliError::failed)?;
        return Ok(if stop.load(Ordering::SeqCst) { Exit::Interrupted } else { Exit::Success });
    }
    use std::io::IsTerminal;
    let status = match (std::io::stderr().is_terminal(), status) {
        (true, _) => crate::drive::Status::Line,
        (false, true) => crate::drive::Status::Lines,
        (false, false) => crate::drive::Status::Off,
    };
    let trees = watch.then(|| {
        let registry = registry.clone();
        let load: crate::watch::LoadTree =
            Box::new(move |file| Ok(DriveConfig::load(&registry, file).map_err(|e| e.to_string())?.0.root));
        crate::watch::TreeWatch::new(file, config.root.clone(), ubf_core::BuildContext::new(0), load).shared()
    });
    let outcome = crate::drive::drive(&config, &model, &stop, status, trees);
    if let Some(pose) = outcome.pose {
        let frame = match &config.pose_file {
            Some(file) => format!("the world frame kept in {}", file.display()),
            None => "the frame where it stood when the drive began".to_owned(),
        };
        let (x, y, heading) = (pose.x, pose.y, pose.theta.to_degrees());
        ubf_session::say!("the robot came to rest at ({x:.3}, {y:.3}) m, {heading:.1}° by its odometry, in {frame}");
    }
    match outcome.logs.as_slice() {
        [] => ubf_session::say!("no session opened; no log written"),
        [one] => ubf_session::say!("log in {}", one.display()),
        many => {
            let names: Vec<String> = many.iter().map(|p| p.display().to_string()).collect();
            ubf_session::say!("logs: {}", names.join(", "));
        }
    }
    match outcome.end.map_err(CliError::failed)? {
        DriveEnd::Interrupted => {
            ubf_session::say!("interrupted; stopped");
            Ok(Exit::Interrupted)
        }
        DriveEnd::Stopped => {
            ubf_session::say!("stopped");
            Ok(Exit::Success)
        }
        DriveEnd::GoalReached => {
            ubf_session::say!("at the goal; stopped");
            Ok(Exit::Success)
        }
        DriveEnd::LinkLost => Ok(Exit::Failure),
        DriveEnd::NoProgress => {
            ubf_session::say!("no progress: the robot stayed on one spot for the progress check's window; stopped");
            Ok(Exit::Failure)
        }
    }
}

/// Emulates a Powerbot on a TCP address, or on a new pseudo-terminal; its
/// link cut only in the first `cuts` sessions, if given.
pub(super) fn emulate(listen: &str, pty: bool, config: &EmulatorConfig, cuts: Option<u32>) -> Outcome {
    use ubf_robots::arcos::emulator::serve;
    let sessions = std::sync::atomic::AtomicU32::new(0);
    let client = |link: Box<dyn Link>, stop: &Arc<AtomicBool>| {
        let mut config = config.clone();
        if cuts.is_some_and(|cuts| sessions.load(Ordering::Relaxed) >= cuts) {
            config.cut = None;
        }
        let served = serve(link, &config, stop);
        if served.as_ref().is_ok_and(|report| report.commands > 0) {
            sessions.fetch_add(1, Ordering::Relaxed);
        }
        served.map(|report| (report.commands, emulator_report(&report)))
    };
    serve_clients("a Powerbot", listen, pty, client)
}

/// Emulates a FLIR PTU pan-tilt head on a TCP address, or on a new
/// pseudo-terminal.
pub(super) fn emulate_ptu(listen: &str, pty: bool, config: &PtuEmulatorConfig) -> Outcome {
    use ubf_robots::ptu::serve_ptu;
    let client = |link: Box<dyn Link>, stop: &Arc<AtomicBool>| {
        serve_ptu(link, config, stop).map(|r| {
            let line = format!(
                "client gone: {} commands, pan {:.2}°, tilt {:.2}°",
                r.commands,
                r.pan.to_degrees(),
                r.tilt.to_degrees()
            );
            (r.commands, line)
        })
    };
    serve_clients("a pan-tilt unit", listen, pty, client)
}

/// Serves clients one after another with `client` (which answers how many
/// commands it took and a line to print) until Ctrl-C or SIGTERM (exit
/// code 130, as for every command they end): on a TCP address, or on a new
/// pseudo-terminal whose path is printed.
fn serve_clients(
    what: &str,
    listen: &str,
    pty: bool,
    client: impl Fn(Box<dyn Link>, &Arc<AtomicBool>) -> std::io::Result<(u64, String)>,
) -> Outcome {
    let stop = crate::drive::install_stop_flag();
    // Nobody reading the output is no reason to stop emulating: a closed
    // pipe is ignored.
    let say = |line: &str| {
        use std::io::Write;
        let _ = writeln!(std::io::stdout(), "{line}");
    };
    if pty {
        let (master, path) = open_pty()?;
        say(&format!("emulating {what} on {path}"));
        while !stop.load(Ordering::SeqCst) {
            let link = master.try_clone_link().map_err(CliError::failed)?;
            match client(link, &stop) {
                // Nobody on the other end yet.
                Ok((0, _)) => std::thread::sleep(Duration::from_millis(100)),
                Ok((_, line)) => say(&line),
                Err(e) => {
                    ubf_session::say!("client error: {e}");
                    std::thread::sleep(Duration::from_millis(100));
                }
            }
        }
        return Ok(Exit::Interrupted);
    }
    let listener =
        std::net::TcpListener::bind(listen).map_err(|e| CliError::bad_input(format!("listening on {listen}: {e}")))?;
    match listener.local_addr() {
        Ok(address) => say(&format!("emulating {what} on tcp://{address}")),
        Err(e) => ubf_session::say!("warning: {e}"),
    }
    // Poll for clients so that Ctrl-C or SIGTERM ends a waiting emulator.
    listener.set_nonblocking(true).map_err(CliError::failed)?;
    while !stop.load(Ordering::SeqCst) {
        let stream = match listener.accept() {
            Ok((stream, _)) => stream,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_millis(50));
                continue;
            }
            Err(e) => {
                ubf_session::say!("error: accepting a client: {e}");
                continue;
            }
        };
        let _ = stream.set_nonblocking(false);
        let _ = stream.set_read_timeout(Some(ubf_robots::arcos::link::READ_TIMEOUT));
        match client(Box::new(stream), &stop) {
            Ok((_, line)) => say(&line),
            Err(e) => ubf_session::say!("client error: {e}"),
        }
    }
    Ok(Exit::Interrupted)
}

/// A new pseudo-terminal's master end, and the path a client opens.
#[cfg(unix)]
fn open_pty() -> Result<(Box<dyn Link>, String), CliError> {
    let (master, path) = ubf_robots::arcos::link::pseudo_terminal()
        .map_err(|e| CliError::failed(format!("opening a pseudo-terminal: {e}")))?;
    Ok((Box::new(master), path))
}

#[cfg(not(unix))]
fn open_pty() -> Result<(Box<dyn Link>, String), CliError> {
    Err(CliError::failed("pseudo-terminals are supported on Unix only"))
}

/// What the emulator saw of a client, one line, the timings as
/// `name=value` (`-` when it did not happen).
fn emulator_report(report: &EmulatorReport) -> String {
    let show = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{v:.3}"));
    let limits = report.speed_limits.map_or("-".to_owned(), |(v, w)| format!("{v},{w}"));
    format!(
        "client gone: {} commands, closed {}, pose ({:.3}, {:.3}) m; sips={} motion_before_first_sip={} \
         last_motion_after_silence_s={} stop_after_silence_s={} stop_to_disable_s={} speed_at_disable_mm_s={} \
         motion_stopped_at={} speed_limits={limits} stalled_cycles={} host_baud={}",
        report.commands,
        report.closed,
        report.pose.0 / 1000.0,
        report.pose.1 / 1000.0,
        report.sips,
        report.motion_before_first_sip,
        show(report.last_motion_after_silence_s),
        show(report.stop_after_silence_s),
        show(report.stop_to_disable_s),
        show(report.speed_at_disable),
        report.motion_stopped_at.map_or("-".to_owned(), |t| format!("{t:.4}")),
        report.stalled_cycles,
        report.host_baud.map_or("-".to_owned(), |b| b.to_string()),
    )
}

/// `LENGTHxWIDTH` in metres, both positive.
pub(super) fn parse_room(text: &str) -> Result<(f64, f64), String> {
    let parse = |s: &str| s.trim().parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0);
    match text.split_once(['x', 'X']).map(|(l, w)| (parse(l), parse(w))) {
        Some((Some(length), Some(width))) => Ok((length, width)),
        _ => Err(format!("expected LENGTHxWIDTH in metres, both positive, e.g. 8x4; got {text:?}")),
    }
}

/// Milliseconds between SIPs, 0.1 to 1000.
pub(super) fn parse_sip_period(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(ms) if (0.1..=1000.0).contains(&ms) => Ok(ms),
        _ => Err(format!("expected milliseconds from 0.1 to 1000; got {text:?}")),
    }
}

/// `AFTER:FOR` in seconds, each 0 to a day.
pub(super) fn parse_silence(text: &str) -> Result<(f64, f64), String> {
    let parse = |s: &str| s.trim().parse::<f64>().ok().filter(|v| v.is_finite() && (0.0..=86_400.0).contains(v));
    match text.split_once(':').map(|(a, f)| (parse(a), parse(f))) {
        Some((Some(after), Some(span))) => Ok((after, span)),
        _ => Err(format!("expected AFTER:FOR in seconds, e.g. 3:2; got {text:?}")),
    }
}
