//! A scenario run headless on the simulated robot, and what it leaves
//! behind: `report.json`, `trajectory.csv` and `plot.png`.

use crate::plot::{self, PlotError, RunPlot};
use crate::scenario::Scenario;
use crate::trajectory::TrajectoryWriter;
use serde::Serialize;
use std::path::{Path, PathBuf};
use ubf_core::{BuildContext, Controller, ControllerError, Pose2, SimClock, Stopwatch};
use ubf_robots::sim::SimRobot;

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EndReason {
    /// The robot believed it was at the goal.
    GoalReached,
    /// `max_time_s` ran out first.
    TimeLimit,
}

/// What a run did: `report.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunReport {
    /// The scenario's name.
    pub scenario: String,
    /// The seed the run used.
    pub seed: u64,
    /// Control ticks run.
    pub ticks: u64,
    /// Simulated seconds.
    pub sim_time_s: f64,
    /// True path length driven, m.
    pub distance_m: f64,
    /// Whether the robot's true position ended within the goal's tolerance.
    pub reached_goal: bool,
    /// Times the robot came into contact with a wall, a box or a person.
    pub collisions: u32,
    /// Why the run ended.
    pub end: EndReason,
    /// Where the robot really ended.
    pub final_true_pose: Pose2,
    /// Where the robot believed it ended.
    pub final_estimated_pose: Pose2,
    /// Distance between the two, m.
    pub estimate_error_m: f64,
    /// Real seconds the run took: the only field that differs between two
    /// runs of the same scenario and seed.
    pub wall_time_s: f64,
}

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
}

fn output_error(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::Output { path: path.to_owned(), source }
}

/// Runs `scenario` with `seed` on the simulator until the robot believes it
/// is at the goal or time runs out. With `out`, writes `report.json`,
/// `trajectory.csv` and `plot.png` there (creating the directory).
pub fn run(scenario: &Scenario, seed: u64, out: Option<&Path>) -> Result<RunReport, RunError> {
    let stopwatch = Stopwatch::start();
    let robot = SimRobot::new(&scenario.robot, &scenario.world, scenario.period_s, seed);
    let root = scenario.root.build(&BuildContext::new(seed));
    let mut controller = Controller::new(robot, root, Box::new(SimClock::new(scenario.period_s)));
    controller.set_goal(scenario.goal);

    let mut trajectory = match out {
        Some(dir) => {
            std::fs::create_dir_all(dir).map_err(output_error(dir))?;
            let path = dir.join("trajectory.csv");
            Some((TrajectoryWriter::create(&path, controller.layout()).map_err(output_error(&path))?, path))
        }
        None => None,
    };
    let mut true_path = Vec::new();
    let mut estimated_path = Vec::new();
    let mut decisions = Vec::new();
    let mut last_winner = None;

    // Rounded so that 60 s at 0.1 s is 600 ticks, not 601 from 599.999….
    let max_ticks = (scenario.max_time_s / scenario.period_s - 1e-9).ceil().max(1.0) as u64;
    let mut end = EndReason::TimeLimit;
    let mut failure = None;
    for _ in 0..max_ticks {
        if let Err(e) = controller.tick() {
            failure = Some(RunError::from(e));
            break;
        }
        let (truth, odometry) = (controller.robot().true_pose(), controller.robot().odometry_pose());
        if let Some((writer, path)) = &mut trajectory {
            if let Err(e) = writer.write(controller.last_record(), controller.layout(), &truth, &odometry) {
                failure = Some(output_error(path)(e));
                break;
            }
        }
        if out.is_some() {
            true_path.push((truth.x, truth.y));
            estimated_path.push((odometry.x, odometry.y));
            let winner = controller.layout().winning_leaf(controller.last_record());
            if winner != last_winner && last_winner.is_some() {
                decisions.push((truth.x, truth.y));
            }
            last_winner = winner;
        }
        if controller.state().goal_reached() {
            end = EndReason::GoalReached;
            break;
        }
    }
    // Shut down and flush even after a failure: nothing is lost.
    let shutdown = controller.shutdown();
    if let Some((writer, path)) = trajectory {
        writer.finish().map_err(output_error(&path))?;
    }
    if let Some(e) = failure {
        return Err(e);
    }
    shutdown?;

    let robot = controller.robot();
    let (truth, estimate) = (robot.true_pose(), robot.odometry_pose());
    let report = RunReport {
        scenario: scenario.name.clone(),
        seed,
        ticks: controller.last_record().tick + 1,
        sim_time_s: controller.now(),
        distance_m: robot.distance_travelled(),
        reached_goal: scenario.goal.is_some_and(|g| g.reached_by(&truth)),
        collisions: robot.collisions(),
        end,
        final_true_pose: truth,
        final_estimated_pose: estimate,
        estimate_error_m: truth.distance_to(estimate.x, estimate.y),
        wall_time_s: stopwatch.elapsed_s(),
    };
    if let Some(dir) = out {
        write_report(&report, &dir.join("report.json"))?;
        let title = format!("{} (seed {seed})", scenario.name);
        let picture = RunPlot {
            title: &title,
            world: robot.world(),
            true_path: &true_path,
            estimated_path: &estimated_path,
            decisions: &decisions,
            goal: scenario.goal,
        };
        plot::draw(&picture, &dir.join("plot.png"))?;
    }
    Ok(report)
}

/// Writes a report as pretty JSON.
pub fn write_report(report: &RunReport, path: &Path) -> Result<(), RunError> {
    let text = serde_json::to_string_pretty(report).expect("a report always serialises");
    std::fs::write(path, text + "\n").map_err(output_error(path))
}
