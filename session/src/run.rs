//! A scenario run headless on the simulated robot, and what it leaves
//! behind: `report.json`, `trajectory.csv` and `plot.png`.

use crate::json_topics::{RunMessage, WorldMessage};
use crate::mcap_log::McapLog;
use crate::plot::{self, PlotError};
pub use crate::report::{EndReason, RunReport};
use crate::ros2_log::Ros2Log;
use crate::ros2_publish::background_publisher;
use crate::ros2_view::{Shown, ODOM_FRAME};
use crate::scenario::Scenario;
use crate::trajectory::{Columns, TrajectoryWriter};
use std::net::SocketAddr;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex, PoisonError};
use ubf_behaviors::decision::{DecisionCosts, EndPointPredictor};
use ubf_core::{
    BuildContext, Clock, Controller, ControllerError, Ends, PacedClock, Pose2, Session, SessionEnd, SimClock,
    Stopwatch, TickRecord, TracingSink, TreeSource, Wraps,
};
use ubf_perception::egomotion::Tracker;
use ubf_robots::egomotion::EgomotionRobot;
use ubf_robots::sim::SimRobot;
use ubf_robots::wall_compass::WallCompassRobot;

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The controller or the robot failed.
    #[error(transparent)]
    Controller(#[from] ControllerError),
    /// An output file could not be written.
    #[error("writing {}: {source}", path.display())]
    Output {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The plot could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The MCAP log could not be written.
    #[error(transparent)]
    Log(#[from] crate::mcap_log::LogError),
    /// ROS 2 publishing could not start.
    #[error("ROS 2: {0}")]
    Ros2(ubf_core::RobotError),
    /// The live view could not be served.
    #[error(transparent)]
    Live(#[from] crate::live::LiveError),
    /// A bug: the run panicked outside the behaviours (the robot was
    /// stopped and the logs flushed).
    #[error("internal error: {0}")]
    Panic(String),
}

fn output_error(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::Output { path: path.to_owned(), source }
}

/// Runs `scenario` with `seed` on the simulator until the robot believes it
/// is at the goal or time runs out. With `out`, writes `report.json`,
/// `trajectory.csv`, `run.mcap` and `plot.png` there (creating the
/// directory).
pub fn run(scenario: &Scenario, seed: u64, out: Option<&Path>) -> Result<RunReport, RunError> {
    let outputs = out.map(|dir| Outputs { dir, images: false, rosbag: false });
    run_until(scenario, seed, outputs, None, &AtomicBool::new(false))
}

/// Where a run's files go, and what its log holds.
#[derive(Clone, Copy, Debug)]
pub struct Outputs<'a> {
    /// The directory for `report.json`, `trajectory.csv`, `run.mcap` and
    /// `plot.png`.
    pub dir: &'a Path,
    /// Whether the logs hold the camera's rendered pairs.
    pub images: bool,
    /// Whether the run is also logged as a rosbag2 directory,
    /// [`ROSBAG_DIR`] in `dir`, for the ROS 2 tools.
    pub rosbag: bool,
}

/// The rosbag2 directory of a run's log, in its output directory.
pub const ROSBAG_DIR: &str = "run-rosbag2";

/// What a shared sink holds, once its other holders are gone.
fn unshared<T>(shared: Arc<Mutex<T>>) -> Option<T> {
    Arc::into_inner(shared).map(|inner| inner.into_inner().unwrap_or_else(PoisonError::into_inner))
}

/// A run watched as it goes: paced at real time, and published on ROS 2,
/// served to Foxglove, or both; and its tree changed as it goes.
pub struct Live {
    /// How many times faster than real time the simulation runs.
    pub speed: f64,
    /// Whether the run is published on ROS 2 (in `ROS_DOMAIN_ID`): the
    /// simulated robot's `/tf`, `odom`, `scan` and camera images, and the
    /// tree's `ubf/tick`.
    pub ros2: bool,
    /// Where to serve the live view ([`crate::live`]), for Foxglove.
    pub foxglove: Option<SocketAddr>,
    /// Where new trees come from while the run goes on (`--watch`,
    /// [`crate::watch`]).
    pub trees: Option<Box<dyn TreeSource>>,
}

/// [`run`] with a choice of outputs, paced and published when `live`,
/// ended early (with its outputs, `end: interrupted`) once `stop` is set.
/// Pacing changes nothing a run computes: its outputs are the same bytes.
pub fn run_until(
    scenario: &Scenario,
    seed: u64,
    outputs: Option<Outputs>,
    mut live: Option<Live>,
    stop: &AtomicBool,
) -> Result<RunReport, RunError> {
    let out = outputs.map(|o| o.dir);
    let stopwatch = Stopwatch::start();
    let sim = SimRobot::new(&scenario.robot, &scenario.world, scenario.period_s, seed);
    let start_pose = sim.true_pose();
    let tracker = match (&scenario.robot.egomotion, &scenario.robot.camera) {
        (Some(config), Some(camera)) => Some(Tracker::new(*config, camera.stereo, start_pose, seed)),
        _ => None,
    };
    let run_message = RunMessage {
        scenario: scenario.name.clone(),
        seed,
        start: [start_pose.x, start_pose.y, start_pose.theta],
        outline: sim.footprint_at(&start_pose).map(|(x, y)| [x, y]),
        goal: scenario.goal.map(|g| [g.x, g.y, g.tolerance]),
    };
    let world = WorldMessage::of(sim.world());
    let robot = EgomotionRobot::new(WallCompassRobot::new(sim, scenario.robot.wall_compass), tracker);
    let root = scenario.root.build(&BuildContext::new(seed));
    let clock: Box<dyn Clock> = match &live {
        Some(live) => Box::new(PacedClock::new(scenario.period_s, live.speed)),
        None => Box::new(SimClock::new(scenario.period_s)),
    };
    let mut controller = Controller::new(robot, root, clock);
    controller.set_goal(scenario.goal);
    controller.set_on_behavior_panic(scenario.on_behavior_panic);
    controller.add_sink(Box::new(TracingSink));
    if live.as_ref().is_some_and(|l| l.ros2) {
        let publisher = background_publisher(Shown { robot: true, images: true, tree: true }, None, "", ODOM_FRAME)
            .map_err(RunError::Ros2)?;
        controller.add_sink(Box::new(publisher));
    }
    // Held until the run ends: dropping it closes the viewers' connections.
    let _live_server = match live.as_ref().and_then(|l| l.foxglove) {
        Some(address) => {
            let server = crate::live::LiveServer::serve(address, ("ubf.Report", crate::json_topics::report_schema()))?;
            server.announce();
            let view = server.view(run_message.clone(), world.clone())?;
            controller.add_sink(Box::new(view));
            Some(server)
        }
        None => None,
    };
    let log = match outputs {
        Some(Outputs { dir, images, rosbag }) => {
            std::fs::create_dir_all(dir).map_err(output_error(dir))?;
            let path = dir.join("trajectory.csv");
            let camera_pan = scenario.robot.camera.as_ref().is_some_and(|c| c.pan_tilt.is_some());
            let columns = Columns { truth: true, hold: false, camera_pan };
            controller.add_sink(Box::new(TrajectoryWriter::create(&path, columns).map_err(output_error(&path))?));
            let mut log = McapLog::create(&dir.join("run.mcap"), &run_message, &world)?;
            log.log_images(images);
            let log = Arc::new(Mutex::new(log));
            controller.add_sink(Box::new(log.clone()));
            let bag = match rosbag {
                true => {
                    let bag = Ros2Log::create(&dir.join(ROSBAG_DIR), Shown { robot: true, images, tree: true }, 0.0)?;
                    let bag = Arc::new(Mutex::new(bag));
                    controller.add_sink(Box::new(bag.clone()));
                    Some(bag)
                }
                false => None,
            };
            Some((log, bag))
        }
        None => None,
    };

    let ends =
        Ends { at_goal: true, progress: scenario.progress, max_ticks: Some(scenario.max_ticks()), max_time_s: None };
    let mut session = Session::new(controller, ends);
    if let Some(trees) = live.as_mut().and_then(|l| l.trees.take()) {
        session.watch_trees(trees);
    }
    let mut end_point = EndPointWitness::default();
    let ended = session.run(stop, |record| {
        end_point.observe(record);
        ControlFlow::Continue(())
    });
    // Shut down and flush even after a failure: nothing is lost.
    let (controller, shutdown) = session.finish();
    let (ticks, sim_time) = (controller.last_record().tick + 1, controller.now());
    let mut behavior_failure = None;
    let (end, failure) = match ended {
        SessionEnd::GoalReached => (EndReason::GoalReached, None),
        SessionEnd::TimeLimit | SessionEnd::Done => (EndReason::TimeLimit, None),
        SessionEnd::NoProgress => (EndReason::NoProgress, None),
        SessionEnd::Interrupted => (EndReason::Interrupted, None),
        // The run still ends with its report, saying what failed.
        SessionEnd::Failed(ControllerError::BehaviorPanicked(panic)) => {
            behavior_failure = Some(panic.to_string());
            (EndReason::BehaviorFailed, None)
        }
        SessionEnd::Failed(e) => (EndReason::TimeLimit, Some(RunError::from(e))),
        SessionEnd::Panicked(why) => (EndReason::TimeLimit, Some(RunError::Panic(why))),
    };
    let (robot, _) = controller.into_parts();
    // The controller, and with it its handles on the logs, is gone.
    let (log, bag) = match log {
        Some((log, bag)) => (unshared(log), bag.and_then(unshared)),
        None => (None, None),
    };
    if let Some(e) = failure.or(shutdown.err().map(RunError::from)) {
        // What was logged stays readable; the failure is what is reported.
        if let Some(log) = log {
            let _ = log.close();
        }
        if let Some(bag) = bag {
            let _ = bag.close();
        }
        return Err(e);
    }

    // What egomotion made of the run, and the position σ its own
    // covariance gives the last pose.
    let (egomotion, egomotion_sigma) = robot
        .tracker()
        .map(|t| {
            let c = t.estimator_covariance();
            (t.state(), (c[(0, 0)] + c[(1, 1)]).sqrt())
        })
        .unzip();
    let compass = robot.inner();
    let sim = compass.inner();
    // Where the robot believed it was: the pose it steered by (egomotion's
    // combined with odometry's, where it navigates), else odometry's (held
    // by the walls where the robot has a wall compass).
    let odometry = compass.odometry(sim.odometry_pose());
    let believed = robot.tracker().and_then(|t| t.navigation_pose(&odometry)).unwrap_or(odometry);
    let (truth, estimate) = (sim.true_pose(), believed);
    let endpoint_error =
        egomotion.and_then(|e| e.pose).zip(end_point.truth_at_frame).map(|(p, truth)| truth.distance_to(p.x, p.y));
    let distance = sim.distance_travelled();
    let start = scenario.robot.start.pose();
    let straight = scenario.goal.map(|g| start.distance_to(g.x, g.y)).filter(|d| *d > 0.0);
    let report = RunReport {
        scenario: scenario.name.clone(),
        seed,
        ticks,
        sim_time_s: sim_time,
        distance_m: distance,
        reached_goal: scenario.goal.is_some_and(|g| g.reached_by(&truth)),
        has_goal: scenario.goal.is_some(),
        collisions: sim.collisions(),
        end,
        failure: behavior_failure,
        final_true_pose: truth,
        final_estimated_pose: estimate,
        estimate_error_m: truth.distance_to(estimate.x, estimate.y),
        journey_cv: egomotion.map(|e| e.journey_cv),
        egomotion_steps: egomotion.map(|e| e.steps),
        egomotion_failures: egomotion.map(|e| e.failures),
        predicted_endpoint_sigma_m: egomotion
            .and(end_point.odometry_at_frame)
            .map(|p| end_point.predictor.sigma((p.x, p.y))),
        egomotion_sigma_m: egomotion_sigma,
        outages: egomotion.map(|e| e.outages),
        outage_s: egomotion.map(|e| e.outage_s),
        outage_m: egomotion.map(|e| e.outage_m),
        wheel_scale: egomotion.and_then(|e| e.wheel_scale).map(|s| s.factor),
        wheel_scale_sigma: egomotion.and_then(|e| e.wheel_scale).map(|s| s.sigma),
        endpoint_error_m: endpoint_error,
        endpoint_error_pct: endpoint_error.filter(|_| distance > 0.0).map(|e| 100.0 * e / distance),
        path_overhead_pct: straight.map(|s| 100.0 * (distance / s - 1.0)),
        time_overhead_pct: straight.map(|s| 100.0 * (sim_time / (s / scenario.robot.max_velocity) - 1.0)),
        wall_time_s: stopwatch.elapsed_s(),
    };
    if let Some(log) = log {
        // Without the wall time, so that the log is the same for the same
        // scenario and seed.
        let mut logged = serde_json::to_value(&report).expect("a report always serialises");
        if let Some(fields) = logged.as_object_mut() {
            fields.remove("wall_time_s");
        }
        if let Some(bag) = bag {
            bag.close_with_report(report.sim_time_s, &logged)?;
        }
        log.close_with_report(report.sim_time_s, &logged)?;
    }
    if let Some(dir) = out {
        write_report(&report, &dir.join("report.json"))?;
        // The plot is drawn from the log, as `ubf replay` draws it: one
        // source for both.
        let replayed = crate::replay::read(&dir.join("run.mcap"))?;
        plot::draw_replayed(&replayed, &format!("{} (seed {seed})", scenario.name), &dir.join("plot.png"))?;
    }
    Ok(report)
}

/// What the end-point error and its prediction need from the ticks: the
/// true pose and odometry when the newest stereo frame was taken (the
/// egomotion estimate describes that instant, not the last tick), and the
/// predictor fed each frame's step.
struct EndPointWitness {
    frame: u64,
    truth_at_frame: Option<Pose2>,
    odometry_at_frame: Option<Pose2>,
    predictor: EndPointPredictor,
}

impl Default for EndPointWitness {
    fn default() -> Self {
        EndPointWitness {
            frame: 0,
            truth_at_frame: None,
            odometry_at_frame: None,
            predictor: EndPointPredictor::new(DecisionCosts::levels()),
        }
    }
}

impl EndPointWitness {
    fn observe(&mut self, record: &TickRecord) {
        let state = &record.state;
        if state.stereo.number != self.frame {
            self.frame = state.stereo.number;
            self.truth_at_frame = record.truth.map(|t| t.pose);
            self.odometry_at_frame = Some(state.pose);
            self.predictor.frame(&state.pose, state.egomotion.last_step_cv);
        }
    }
}

/// Writes a report as pretty JSON, atomically ([`crate::atomic::write`]):
/// the file is whole or absent.
pub fn write_report(report: &RunReport, path: &Path) -> Result<(), RunError> {
    let text = serde_json::to_string_pretty(report).expect("a report always serialises");
    crate::atomic::write(path, (text + "\n").as_bytes()).map_err(output_error(path))
}
