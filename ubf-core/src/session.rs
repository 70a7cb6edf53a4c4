//! One session: a controller ticking a robot until something ends it.
//!
//! A simulated run, a recording of camera pairs and a drive on a real
//! robot are all this loop; they differ only in their robot, their clock,
//! their sinks and which of the [`Ends`] they set.

use crate::{BehaviorPanic, Controller, ControllerError, ProgressCheck, ProgressWatch, Robot, RobotError, TickRecord};
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};

/// What, besides the operator's stop and failures, ends a session. The
/// default ends nothing: a session that runs until stopped.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ends {
    /// End once the robot believes it is at the goal.
    pub at_goal: bool,
    /// Give up once the robot stays on one spot for the check's window.
    pub progress: Option<ProgressCheck>,
    /// End after this many ticks.
    pub max_ticks: Option<u64>,
    /// End once the session's clock reaches this many seconds.
    pub max_time_s: Option<f64>,
}

/// Why a session ended.
#[derive(Debug)]
pub enum SessionEnd {
    /// The robot believes it is at the goal.
    GoalReached,
    /// The tick or time limit ran out.
    TimeLimit,
    /// The robot got nowhere for the progress check's window.
    NoProgress,
    /// The stop flag was set (Ctrl-C, SIGTERM, or the caller).
    Interrupted,
    /// The caller's own per-tick check asked to end.
    Done,
    /// The controller failed: a behaviour panicked (with
    /// `OnBehaviorPanic::Stop`), the robot failed, or a sink failed.
    Failed(ControllerError),
    /// A bug: something outside the behaviours panicked.
    Panicked(String),
}

impl SessionEnd {
    /// The ending's name as logs give it (`goal_reached`, `time_limit`,
    /// `no_progress`, `interrupted`, `done`, `link_lost`, `failed`), and
    /// what failed, if something did.
    pub fn describe(&self) -> (&'static str, Option<String>) {
        match self {
            SessionEnd::GoalReached => ("goal_reached", None),
            SessionEnd::TimeLimit => ("time_limit", None),
            SessionEnd::NoProgress => ("no_progress", None),
            SessionEnd::Interrupted => ("interrupted", None),
            SessionEnd::Done => ("done", None),
            SessionEnd::Failed(ControllerError::Robot(e)) if e.is_link_loss() => ("link_lost", Some(e.to_string())),
            SessionEnd::Failed(e) => ("failed", Some(e.to_string())),
            SessionEnd::Panicked(why) => ("failed", Some(format!("internal error: {why}"))),
        }
    }

    /// The behaviour's panic, if that is what ended the session.
    pub fn behavior_panic(&self) -> Option<&BehaviorPanic> {
        match self {
            SessionEnd::Failed(ControllerError::BehaviorPanicked(panic)) => Some(panic),
            _ => None,
        }
    }

    /// The robot's failure, if that is what ended the session.
    pub fn robot_error(&self) -> Option<&RobotError> {
        match self {
            SessionEnd::Failed(ControllerError::Robot(e)) => Some(e),
            _ => None,
        }
    }
}

/// Where a new tree may come from while a session runs: a file being
/// edited, say.
pub trait TreeSource {
    /// A tree to swap in before the next tick, if there is a new one. It is
    /// asked before every tick, so it must answer quickly when there is
    /// none.
    fn next_tree(&mut self) -> Option<Box<dyn crate::Behavior>>;
}

/// A controller and what ends its loop.
pub struct Session<R: Robot> {
    controller: Controller<R>,
    ends: Ends,
    trees: Option<Box<dyn TreeSource>>,
}

impl<R: Robot> Session<R> {
    /// A session of `controller` that ends as `ends` say.
    pub fn new(controller: Controller<R>, ends: Ends) -> Self {
        Session { controller, ends, trees: None }
    }

    /// Swaps in each tree `trees` gives, at a tick boundary, telling the
    /// sinks ([`crate::TickSink::tree_changed`]).
    pub fn watch_trees(&mut self, trees: Box<dyn TreeSource>) {
        self.trees = Some(trees);
    }

    /// The controller (its state, its record, its robot).
    pub fn controller(&self) -> &Controller<R> {
        &self.controller
    }

    /// The controller, mutably.
    pub fn controller_mut(&mut self) -> &mut Controller<R> {
        &mut self.controller
    }

    /// Ticks until `stop` is set, one of the [`Ends`] is met, `each_tick`
    /// breaks, or something fails. `stop` is looked at before each tick, so
    /// no command is sent once it is set. A panic outside the behaviours is
    /// caught and returned: the caller still shuts the robot down.
    pub fn run(&mut self, stop: &AtomicBool, mut each_tick: impl FnMut(&TickRecord) -> ControlFlow<()>) -> SessionEnd {
        let (controller, ends, trees) = (&mut self.controller, self.ends, &mut self.trees);
        let mut progress = ends.progress.map(ProgressWatch::new);
        let ticking = std::panic::AssertUnwindSafe(|| loop {
            if stop.load(Ordering::SeqCst) {
                return SessionEnd::Interrupted;
            }
            if let Some(root) = trees.as_mut().and_then(|t| t.next_tree()) {
                let time = controller.now();
                if let Err(e) = controller.replace_root(root) {
                    return SessionEnd::Failed(e);
                }
                tracing::info!(time, "tree replaced");
            }
            if ends.max_time_s.is_some_and(|limit| controller.now() >= limit) {
                return SessionEnd::TimeLimit;
            }
            let record = match controller.tick() {
                Ok(record) => record,
                Err(e) => return SessionEnd::Failed(e),
            };
            if each_tick(record).is_break() {
                return SessionEnd::Done;
            }
            if ends.at_goal && record.state.goal_reached() {
                return SessionEnd::GoalReached;
            }
            if progress.as_mut().is_some_and(|p| p.stalled(&record.state)) {
                return SessionEnd::NoProgress;
            }
            if ends.max_ticks.is_some_and(|max| record.tick + 1 >= max) {
                return SessionEnd::TimeLimit;
            }
        });
        std::panic::catch_unwind(ticking)
            .unwrap_or_else(|panic| SessionEnd::Panicked(crate::panic_message(panic.as_ref()).to_owned()))
    }

    /// Stops the robot, shuts it down and flushes every sink (each step
    /// tried even if an earlier one failed), and gives back the controller
    /// with the first error of the shutdown.
    pub fn finish(self) -> (Controller<R>, Result<(), ControllerError>) {
        let mut controller = self.controller;
        let shutdown = controller.shutdown();
        (controller, shutdown)
    }
}
