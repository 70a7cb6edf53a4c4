//! `ubf drive ROBOT.ron`: the behaviour tree on a real robot (or anything
//! speaking its protocol), stopped safely.
//!
//! - [`robot_file`]: the robot file and its loader;
//! - the sessions (here): connect, drive, reconnect, log, stop;
//! - `camera`: the camera opened and the robot equipped with it;
//! - `status`: the live state on stderr; `dry_run`: a look with the
//!   motors off.

mod camera;
mod dry_run;
mod log;
mod loop_watch;
mod pose_file;
pub mod robot_file;
mod service;
mod status;

pub use camera::CameraError;
pub use dry_run::dry_run;
pub use log::DriveReport;
pub use pose_file::PoseFileError;
pub use robot_file::{
    CameraSourceChoice, DriveCamera, DriveConfig, ModelChoice, OnLinkLoss, RectifyFiles, RectifyFilesError,
    RobotFileError, ROS2_CONNECTION,
};
pub use status::Status;

use crate::json_topics::WorldMessage;
use crate::ros2_view::Shown;
use crate::watch::SharedTreeWatch;
use status::StatusLine;
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use ubf_core::{
    BuildContext, Controller, ControllerError, Ends, Pose2, Robot, RobotError, SafetyGuard, Session, SessionEnd,
    TracingSink, WallClock,
};
use ubf_robots::arcos::client::ArcosRobot;
use ubf_robots::arcos::link;
use ubf_robots::emergency::EmergencyStop;
use ubf_robots::model::RobotModel;
use ubf_robots::ros2::Ros2Robot;

/// Why `ubf drive` (or its dry run) ended in failure. A robot that was
/// reached has been stopped and its session closed before this is
/// reported.
#[derive(Debug, thiserror::Error)]
pub enum DriveError {
    /// The camera could not be used (checked before the motors go on).
    #[error("camera: {0}")]
    Camera(#[from] CameraError),
    /// The robot could not be reached or did not complete the handshake.
    #[error("{connection}: {source}")]
    Connect {
        /// The serial device or address tried.
        connection: String,
        /// What went wrong.
        source: RobotError,
    },
    /// The session's log could not be created.
    #[error("{}: {source}", path.display())]
    Log {
        /// The log asked for.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// Publishing on ROS 2 could not start.
    #[error(transparent)]
    Ros2(RobotError),
    /// The live view could not be served (checked before the motors go
    /// on).
    #[error(transparent)]
    Live(#[from] crate::live::LiveError),
    /// A log writer's thread could not be started.
    #[error("starting the log writer: {0}")]
    LogWriter(std::io::Error),
    /// The robot failed while driving (the dry run: while watching).
    #[error(transparent)]
    Robot(#[from] RobotError),
    /// The tree failed: a behaviour panicked with `on_behavior_panic: Stop`,
    /// or a sink failed.
    #[error(transparent)]
    Controller(ControllerError),
    /// A bug: the session panicked outside the behaviours.
    #[error("internal error: {0}")]
    Panic(String),
    /// The dry run needs a robot whose motors can stay off while it is
    /// watched; a ROS 2 robot's driver owns its motors.
    #[error(
        "--dry-run watches an ARCOS robot with its motors off; a ROS 2 robot's motors belong to its driver: use \
         `ros2 topic echo /odom` to watch it"
    )]
    NoDryRun,
    /// The pose file could not be read, or written.
    #[error(transparent)]
    PoseFile(#[from] PoseFileError),
    /// The dry run's report could not be written.
    #[error("writing: {0}")]
    Output(std::io::Error),
}

/// What Ctrl-C or SIGTERM reaches the robot with, while a session is open:
/// its emergency stop.
static ON_INTERRUPT: Mutex<Option<Box<dyn EmergencyStop>>> = Mutex::new(None);

/// A second interrupt sooner than this after the first is the same one sent
/// twice: GNU `timeout` sends its SIGTERM to the process and to its process
/// group, which the process is in.
const SAME_INTERRUPT: Duration = Duration::from_millis(250);

/// Set by Ctrl-C or SIGTERM, which also stops the open session's robot at
/// once, if any (the control loop may be in the middle of a tick), and
/// holds it still while the loop runs the orderly stop. A second one, at
/// least 0.25 s later, does not wait for that: it stops the
/// robot for good (an ARCOS robot: STOP, ENABLE 0 and CLOSE; a ROS 2 robot:
/// a zero twist) and exits with status 130.
pub fn install_stop_flag() -> Arc<AtomicBool> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let mut first: Option<Instant> = None;
    // A second handler cannot be installed; then only the time limit stops.
    let _ = ctrlc::set_handler(move || {
        match first {
            None => {
                flag.store(true, Ordering::SeqCst);
                if let Ok(guard) = ON_INTERRUPT.try_lock() {
                    if let Some(emergency) = guard.as_ref() {
                        let _ = emergency.halt();
                    }
                }
                // Timed from when the halt is done: a signal sent twice at
                // once waited behind it.
                first = Some(Instant::now());
                return;
            }
            Some(at) if at.elapsed() < SAME_INTERRUPT => return,
            Some(_) => {}
        }
        let mut stopped = None;
        if let Ok(guard) = ON_INTERRUPT.try_lock() {
            if let Some(emergency) = guard.as_ref() {
                stopped = Some(emergency.stop_now().map(|()| emergency.stop_now_sends()));
            }
        }
        match stopped {
            Some(Ok(sent)) => crate::say!("interrupted twice: robot sent {sent}; exiting now"),
            Some(Err(e)) => crate::say!("interrupted twice: stopping the robot failed ({e}); exiting now"),
            None => crate::say!("interrupted twice: exiting now"),
        }
        std::process::exit(130);
    });
    stop
}

/// Registers (or clears) what an interrupt stops.
fn arm_interrupt(emergency: Option<Box<dyn EmergencyStop>>) {
    *ON_INTERRUPT.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = emergency;
}

/// How a drive ended.
#[derive(Debug, PartialEq, Eq)]
pub enum DriveEnd {
    /// Ctrl-C or SIGTERM.
    Interrupted,
    /// The time limit, or a tree that ended by itself.
    Stopped,
    /// At the goal, with `until_goal`.
    GoalReached,
    /// The link was lost and the configuration says exit.
    LinkLost,
    /// The robot got nowhere for the `progress` check's window.
    NoProgress,
}

/// What a drive leaves: how it ended and the logs it wrote, one per
/// session, in order.
#[derive(Debug)]
pub struct DriveOutcome {
    /// How it ended, or why it failed.
    pub end: Result<DriveEnd, DriveError>,
    /// The sessions' logs.
    pub logs: Vec<PathBuf>,
    /// Where the robot came to rest by its odometry, in the drive's world
    /// frame (where it stood when the drive began), if a session opened.
    pub pose: Option<Pose2>,
}

/// Runs the tree against the robot until `stop` is set (or the time limit),
/// reconnecting after a lost link if configured, with the world frame (and
/// so the goal) carried over from the last pose. Every tick goes to the
/// session's log; on the way out the robot gets STOP, ENABLE 0 and CLOSE and
/// the log is flushed, whatever ended the session (a panic included).
pub fn drive(
    config: &DriveConfig,
    model: &RobotModel,
    stop: &AtomicBool,
    status: Status,
    trees: Option<SharedTreeWatch>,
) -> DriveOutcome {
    let mut logs = Vec::new();
    let mut pose = None;
    let end = drive_sessions(config, model, stop, status, trees, &mut logs, &mut pose);
    service::stopping();
    DriveOutcome { end, logs, pose }
}

fn drive_sessions(
    config: &DriveConfig,
    model: &RobotModel,
    stop: &AtomicBool,
    status: Status,
    trees: Option<SharedTreeWatch>,
    logs: &mut Vec<PathBuf>,
    settled: &mut Option<Pose2>,
) -> Result<DriveEnd, DriveError> {
    let started = Instant::now();
    let out_of_time = || config.max_time_s.is_some_and(|t| started.elapsed().as_secs_f64() >= t);
    // One server for every session, so that a viewer stays connected
    // across a reconnect to the robot.
    let live = match config.live {
        Some(address) => {
            let report = ("ubf.DriveReport", crate::json_topics::json_schema::<log::DriveReport>());
            let server = crate::live::LiveServer::serve(address, report)?;
            server.announce();
            Some(server)
        }
        None => None,
    };
    let mut pose = Pose2::default();
    if let Some(file) = &config.pose_file {
        if let Some(saved) = pose_file::read(file)? {
            crate::say!(
                "resuming in the world frame of {}: the robot at ({:.3}, {:.3}) m, {:.1}°",
                file.display(),
                saved.x,
                saved.y,
                saved.theta.to_degrees()
            );
            pose = saved;
        }
    }
    loop {
        if stop.load(Ordering::SeqCst) {
            return Ok(DriveEnd::Interrupted);
        }
        if out_of_time() {
            return Ok(DriveEnd::Stopped);
        }
        let camera = config.open_camera()?;
        // Opening the camera (its pan-tilt head's handshake) takes time: a
        // signal that came meanwhile must not be followed by the motors on.
        if stop.load(Ordering::SeqCst) {
            return Ok(DriveEnd::Interrupted);
        }
        let Connected { robot, name, emergency } = match connect_driving(config, model, pose) {
            Ok(connected) => connected,
            Err(e) => {
                tracing::warn!("connecting: {e}");
                if config.on_link_loss == OnLinkLoss::Exit {
                    return Err(e);
                }
                std::thread::sleep(Duration::from_secs(1));
                continue;
            }
        };
        crate::say!("connected to {name}");
        service::ready();
        arm_interrupt(emergency);
        // From here the motors are on: every path out goes through shutdown
        // (a robot dropped on the way out shuts itself down).
        let robot = match config.equip(robot, camera, pose) {
            Ok(robot) => SafetyGuard::new(robot, config.safety),
            Err(e) => {
                arm_interrupt(None);
                return Err(e.into());
            }
        };
        // A drive that reconnects starts again with the tree that ran
        // last, an edit included.
        let root = trees.as_ref().map_or_else(|| config.root.clone(), SharedTreeWatch::current);
        let root = root.build(&BuildContext::new(0));
        let mut controller = Controller::new(robot, root, Box::new(WallClock::new(config.period_s)));
        controller.set_goal(config.goal);
        controller.set_on_behavior_panic(config.on_behavior_panic);
        controller.add_sink(Box::new(TracingSink));
        if let Some(watchdog) = service::Watchdog::for_session() {
            controller.add_sink(Box::new(watchdog));
        }
        // Ticks silent as long as a lost link is given stop the robot.
        let loop_watch = loop_watch::LoopWatch::start(Duration::from_secs_f64(config.safety.link_lost_after_s));
        match &loop_watch {
            Ok(watch) => controller.add_sink(watch.sink()),
            Err(e) => tracing::warn!(
                "the control loop's watch did not start ({e}); a hung loop stops the robot only by Ctrl-C"
            ),
        }
        if let Some(file) = &config.pose_file {
            let sink = pose_file::PoseFileSink::new(file.clone());
            match ubf_core::BackgroundSink::spawn(format!("pose file {}", file.display()), sink, 4) {
                Ok(sink) => controller.add_sink(Box::new(sink)),
                Err(e) => tracing::warn!("pose file {}: {e}", file.display()),
            }
        }
        if status != Status::Off {
            controller.add_sink(Box::new(StatusLine::new(status)));
        }
        if let Some(server) = &live {
            // A view that cannot start is a warning: it is for watching.
            match server.view(log::run_message(model, pose, config.goal), WorldMessage::default()) {
                Ok(view) => controller.add_sink(Box::new(view)),
                Err(e) => tracing::warn!("{e}; this session is not shown live"),
            }
        }
        let ending = log::SessionEnding::default();
        let attached = log::attach_logs(&mut controller, config, model, logs, &ending)
            .and_then(|()| attach_ros2(&mut controller, config));
        let ends = Ends {
            at_goal: config.until_goal,
            progress: config.progress,
            max_ticks: None,
            max_time_s: config.max_time_s.map(|limit| limit - started.elapsed().as_secs_f64()),
        };
        let mut session = Session::new(controller, ends);
        if let Some(trees) = &trees {
            session.watch_trees(Box::new(trees.clone()));
        }
        let ended = match &attached {
            Ok(()) => session.run(stop, |_| ControlFlow::Continue(())),
            Err(_) => SessionEnd::Done,
        };
        if let Ok(watch) = &loop_watch {
            watch.disarm();
        }
        let (end, failure) = ended.describe();
        ending.set(end, failure);
        service::stop_sequence();
        // Whatever happened: stop the robot, close the session and flush
        // the logs.
        let (mut controller, shutdown) = session.finish();
        pose = controller.settled_pose();
        *settled = Some(pose);
        if let Some(scale) = controller.state().egomotion.wheel_scale {
            // The pose steered by takes only part of the measured scale
            // (weighed against the noise model's `scale_sigma`), so wheels
            // off in scale still stop the robot a little short or long of
            // its goals until the robot's own distance is calibrated.
            crate::say!(
                "the camera measured the wheels: {scale}; calibrate the robot's distance by it if other drives agree"
            );
        }
        if let Some(file) = &config.pose_file {
            if let Err(e) = pose_file::write(file, &pose) {
                tracing::warn!("pose file {}: {e}", file.display());
            }
        }
        if let Err(e) = shutdown {
            tracing::warn!("shutting down: {e}");
        }
        arm_interrupt(None);
        attached?;
        match ended {
            SessionEnd::Interrupted => return Ok(DriveEnd::Interrupted),
            SessionEnd::TimeLimit | SessionEnd::Done => return Ok(DriveEnd::Stopped),
            SessionEnd::GoalReached => return Ok(DriveEnd::GoalReached),
            SessionEnd::NoProgress => return Ok(DriveEnd::NoProgress),
            SessionEnd::Panicked(why) => return Err(DriveError::Panic(why)),
            // Only a lost link is worth a new session: for a camera or a
            // head that fails, reconnecting would enable the motors again
            // for a device that still fails.
            SessionEnd::Failed(ControllerError::Robot(why)) if !why.is_link_loss() => return Err(why.into()),
            SessionEnd::Failed(ControllerError::Robot(why)) => {
                crate::say!("link lost: {why}");
                if config.on_link_loss == OnLinkLoss::Exit {
                    return Ok(DriveEnd::LinkLost);
                }
                std::thread::sleep(Duration::from_secs(1));
            }
            SessionEnd::Failed(why) => return Err(DriveError::Controller(why)),
        }
    }
}

/// Publishes the session on ROS 2 where asked, and always for a ROS 2
/// robot: its tree and goal, and for another robot its pose and sensors
/// too (a ROS 2 robot's driver publishes those).
fn attach_ros2<R: Robot>(controller: &mut Controller<R>, config: &DriveConfig) -> Result<(), DriveError> {
    let ros2_robot = config.connection == ROS2_CONNECTION;
    if !(config.publish_ros2 || ros2_robot) {
        return Ok(());
    }
    let (domain, namespace) = config.ros2.as_ref().map_or((None, ""), |r| (r.domain_id, r.namespace.as_str()));
    let shown = Shown { robot: !ros2_robot, images: config.log_images, tree: true };
    // Beside a ROS 2 robot, whose driver publishes its own `odom`, ubf's
    // world is a frame of its own, which the robot places in it.
    let world = match ros2_robot {
        true => ubf_robots::ros2::world_frame(namespace),
        false => crate::ros2_view::ODOM_FRAME.to_owned(),
    };
    let publisher =
        crate::ros2_publish::background_publisher(shown, domain, namespace, &world).map_err(DriveError::Ros2)?;
    controller.add_sink(Box::new(publisher));
    Ok(())
}

/// A robot reached for a session, motors on.
struct Connected {
    robot: Box<dyn Robot>,
    /// Who answered, for the operator.
    name: String,
    /// What an interrupt stops the robot with, where it has one.
    emergency: Option<Box<dyn EmergencyStop>>,
}

/// Reaches the robot the configuration names, ready to drive, with its
/// pose reading `pose`: a ROS 2 robot (`connection: "ros2"`), or an ARCOS
/// controller with its motors enabled.
fn connect_driving(config: &DriveConfig, model: &RobotModel, pose: Pose2) -> Result<Connected, DriveError> {
    if config.connection == ROS2_CONNECTION {
        let limits = config.limits(model);
        let ros2 = config.ros2.clone().unwrap_or_default();
        let robot = Ros2Robot::connect(&ros2, limits, config.period_s, pose)
            .map_err(|source| DriveError::Connect { connection: config.connection.clone(), source })?;
        let name = format!("a ROS 2 robot in domain {} ({}): {}", robot.domain(), model.name, robot.describe());
        let emergency: Box<dyn EmergencyStop> = Box::new(robot.emergency_stop());
        return Ok(Connected { robot: Box::new(robot), name, emergency: Some(emergency) });
    }
    let robot = connect(config, model, true, pose)?;
    let id = robot.identity();
    let name = format!("{} ({} {})", id.name, id.class, id.subclass);
    let emergency = robot.emergency_stop().ok().map(|e| Box::new(e) as Box<dyn EmergencyStop>);
    Ok(Connected { robot: Box::new(robot), name, emergency })
}

/// Opens the link and completes the handshake, motors on or off, with
/// odometry starting at `pose`.
pub(super) fn connect(
    config: &DriveConfig,
    model: &RobotModel,
    motors: bool,
    pose: Pose2,
) -> Result<ArcosRobot, DriveError> {
    link::open(&config.connection, config.baud)
        .map_err(RobotError::from)
        .and_then(|link| ArcosRobot::connect(link, model.clone(), &config.connect_options(motors, pose)))
        .map_err(|source| DriveError::Connect { connection: config.connection.clone(), source })
}
