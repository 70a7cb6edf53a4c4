//! A scenario run headless on the simulated robot.

use crate::scenario::Scenario;
use serde::Serialize;
use ubf_core::{BuildContext, Controller, ControllerError, Pose2, SimClock, Stopwatch, TickSink};
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

/// What a run did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunSummary {
    /// The scenario's name.
    pub scenario: String,
    /// The seed the run used.
    pub seed: u64,
    /// Control ticks run.
    pub ticks: u64,
    /// Simulated seconds.
    pub sim_time_s: f64,
    /// Path length driven, m.
    pub distance_m: f64,
    /// Whether the robot's true position ended within the goal's tolerance.
    pub reached_goal: bool,
    /// Why the run ended.
    pub end: EndReason,
    /// Where the robot really ended.
    pub final_true_pose: Pose2,
    /// Where the robot believed it ended.
    pub final_estimated_pose: Pose2,
    /// Real seconds the run took; the only field that differs between two
    /// runs of the same scenario and seed.
    pub wall_time_s: f64,
}

/// Runs `scenario` with `seed` on the simulator until the robot believes it
/// is at the goal or time runs out. Every tick goes to `sinks`.
pub fn run(scenario: &Scenario, seed: u64, sinks: Vec<Box<dyn TickSink>>) -> Result<RunSummary, ControllerError> {
    let stopwatch = Stopwatch::start();
    let robot = SimRobot::new(scenario.robot.clone(), scenario.period_s);
    let root = scenario.root.build(&BuildContext::new(seed));
    let mut controller = Controller::new(robot, root, Box::new(SimClock::new(scenario.period_s)));
    for sink in sinks {
        controller.add_sink(sink);
    }
    controller.set_goal(scenario.goal);
    // Rounded so that 60 s at 0.1 s is 600 ticks, not 601 from 599.999….
    let max_ticks = (scenario.max_time_s / scenario.period_s - 1e-9).ceil().max(1.0) as u64;
    let mut end = EndReason::TimeLimit;
    let mut result = Ok(());
    for _ in 0..max_ticks {
        if let Err(e) = controller.tick() {
            result = Err(e);
            break;
        }
        if controller.state().goal_reached() {
            end = EndReason::GoalReached;
            break;
        }
    }
    // Shut down (and flush the sinks) even after a failed tick: nothing lost.
    let shutdown = controller.shutdown();
    result?;
    shutdown?;
    let robot = controller.robot();
    Ok(RunSummary {
        scenario: scenario.name.clone(),
        seed,
        ticks: controller.last_record().tick + 1,
        sim_time_s: controller.now(),
        distance_m: robot.distance_travelled(),
        reached_goal: scenario.goal.is_some_and(|g| g.reached_by(&robot.true_pose())),
        end,
        final_true_pose: robot.true_pose(),
        final_estimated_pose: robot.odometry_pose(),
        wall_time_s: stopwatch.elapsed_s(),
    })
}
