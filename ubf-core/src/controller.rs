//! The control loop: sense → state → root behaviour → action → command → act.

use crate::{
    Action, Behavior, BehaviorPanic, Clock, Command, Goal, NodeOutcome, Robot, RobotError, State, TickRecord, TickSink,
    TreeLayout,
};

/// What the controller does when a behaviour panics. Either way the tick
/// that caught it sends STOP.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
pub enum OnBehaviorPanic {
    /// End: the tick returns [`ControllerError::BehaviorPanicked`].
    #[default]
    Stop,
    /// Log it and carry on without the behaviour (its composite keeps it
    /// silent from then on).
    SkipBehavior,
}

/// Why the controller stopped.
#[derive(Debug, thiserror::Error)]
pub enum ControllerError {
    /// The robot failed to sense, act or shut down.
    #[error(transparent)]
    Robot(#[from] RobotError),
    /// A behaviour panicked; the robot was sent STOP.
    #[error(transparent)]
    BehaviorPanicked(#[from] BehaviorPanic),
    /// A tick sink failed to write.
    #[error("recording ticks: {0}")]
    Sink(#[from] std::io::Error),
}

/// Drives a robot with a behaviour tree, one tick at a time.
///
/// Each [`Controller::tick`]: read the clock, sense, ask the root behaviour,
/// turn its action into a command within the robot's limits, act, record,
/// and wait for the next tick. After the first tick a tick allocates nothing
/// (the state and the record reuse their buffers).
pub struct Controller<R: Robot> {
    robot: R,
    root: Box<dyn Behavior>,
    clock: Box<dyn Clock>,
    sinks: Vec<Box<dyn TickSink>>,
    layout: TreeLayout,
    /// The latest tick's record; its state is the one the behaviours see.
    record: TickRecord,
    ticks: u64,
    on_panic: OnBehaviorPanic,
    /// The root itself panicked: with [`OnBehaviorPanic::SkipBehavior`]
    /// nothing is left to ask, so every tick stops.
    root_faulted: bool,
}

impl<R: Robot> Controller<R> {
    /// A controller for `robot` running `root` on `clock`.
    pub fn new(robot: R, root: Box<dyn Behavior>, clock: Box<dyn Clock>) -> Self {
        let layout = TreeLayout::of(root.as_ref());
        let record = TickRecord { nodes: vec![NodeOutcome::default(); layout.nodes.len()], ..TickRecord::default() };
        Controller {
            robot,
            root,
            clock,
            sinks: Vec::new(),
            layout,
            record,
            ticks: 0,
            on_panic: OnBehaviorPanic::default(),
            root_faulted: false,
        }
    }

    /// Chooses what a behaviour's panic does (by default it ends the run).
    pub fn set_on_behavior_panic(&mut self, policy: OnBehaviorPanic) {
        self.on_panic = policy;
    }

    /// Adds a sink that receives every tick's record.
    pub fn add_sink(&mut self, sink: Box<dyn TickSink>) {
        self.sinks.push(sink);
    }

    /// Sets (or clears) the goal every behaviour sees in the state.
    pub fn set_goal(&mut self, goal: Option<Goal>) {
        self.record.state.goal = goal;
    }

    /// The tree's shape.
    pub fn layout(&self) -> &TreeLayout {
        &self.layout
    }

    /// The state as of the latest tick.
    pub fn state(&self) -> &State {
        &self.record.state
    }

    /// The latest tick's record.
    pub fn last_record(&self) -> &TickRecord {
        &self.record
    }

    /// The robot.
    pub fn robot(&self) -> &R {
        &self.robot
    }

    /// The robot, mutably (for a simulator's fault injection, say).
    pub fn robot_mut(&mut self) -> &mut R {
        &mut self.robot
    }

    /// The clock's time, s.
    pub fn now(&self) -> f64 {
        self.clock.now()
    }

    /// Runs one tick and returns its record.
    pub fn tick(&mut self) -> Result<&TickRecord, ControllerError> {
        if self.ticks == 0 {
            for sink in &mut self.sinks {
                sink.start(&self.layout)?;
            }
        }
        self.record.state.time = self.clock.now();
        self.robot.sense(&mut self.record.state)?;
        let action = match self.ask_root() {
            Ok(action) => action,
            Err(panic) => {
                self.robot.act(&Command::Stop)?;
                tracing::error!("{panic}; the robot was sent STOP");
                if self.on_panic == OnBehaviorPanic::Stop {
                    return Err(panic.into());
                }
                Action::stop(1.0)
            }
        };
        let command = Command::from_action(&action, &self.robot.limits());
        self.robot.act(&command)?;
        if let Some(pan) = action.motion.camera_pan.filter(|p| p.is_finite() && action.is_voting()) {
            self.robot.aim_camera(pan)?;
        }
        self.fill_record(action, command);
        for sink in &mut self.sinks {
            sink.record(&self.record)?;
        }
        self.ticks += 1;
        self.clock.wait_for_next_tick();
        Ok(&self.record)
    }

    /// The root's action, with a panic anywhere in the tree caught and
    /// named by its path.
    fn ask_root(&mut self) -> Result<Action, BehaviorPanic> {
        if self.root_faulted {
            return Ok(Action::stop(1.0));
        }
        let (root, state) = (&mut self.root, &self.record.state);
        crate::catch_reported(|| root.gen_action(state)).map_err(|payload| {
            let panic = BehaviorPanic::caught(root.name(), payload);
            // A leaf root has no composite to silence it.
            self.root_faulted = root.as_composite().is_none();
            panic
        })
    }

    fn fill_record(&mut self, action: Action, command: Command) {
        let r = &mut self.record;
        r.tick = self.ticks;
        r.truth = self.robot.ground_truth();
        r.hold = self.robot.hold();
        r.command = command;
        r.nodes[0] = NodeOutcome { action, weight: 1.0, won: action.is_voting() };
        let mut next = 1;
        record_children(self.root.as_ref(), &mut r.nodes, &mut next);
    }

    /// Stops the robot, shuts it down and flushes every sink. Every step is
    /// tried even if an earlier one fails; the first error is returned.
    pub fn shutdown(&mut self) -> Result<(), ControllerError> {
        let mut first_error: Option<ControllerError> = None;
        if let Err(e) = self.robot.act(&Command::Stop).and_then(|_| self.robot.shutdown()) {
            first_error.get_or_insert(e.into());
        }
        for sink in &mut self.sinks {
            if let Err(e) = sink.finish() {
                first_error.get_or_insert(e.into());
            }
        }
        first_error.map_or(Ok(()), Err)
    }

    /// Where the robot came to rest, by its own account, after
    /// [`Controller::shutdown`]: it senses once more, since a robot brakes
    /// after STOP and readings that arrived while it did (a link that came
    /// back during the wait) are not in the last tick's state. A robot that
    /// can no longer say, or fails to, leaves whatever pose it did set, else
    /// the last tick's.
    pub fn settled_pose(&mut self) -> crate::Pose2 {
        let mut state = self.state().clone();
        // A stale or lost link is an error here, not news: the pose the
        // robot set before saying so is still its latest.
        let _ = self.robot.sense(&mut state);
        state.pose
    }

    /// Replaces the tree between two ticks (a file edited while running):
    /// the next tick asks `root`, and every sink is told the new layout.
    /// Gives back the tree it replaces.
    pub fn replace_root(&mut self, root: Box<dyn Behavior>) -> Result<Box<dyn Behavior>, ControllerError> {
        self.layout = TreeLayout::of(root.as_ref());
        self.record.nodes = vec![NodeOutcome::default(); self.layout.nodes.len()];
        self.root_faulted = false;
        let old = std::mem::replace(&mut self.root, root);
        // Before the first tick the sinks have not started: they will
        // start with this layout.
        if self.ticks > 0 {
            for sink in &mut self.sinks {
                sink.tree_changed(&self.layout)?;
            }
        }
        Ok(old)
    }

    /// Gives back the robot and the root behaviour.
    pub fn into_parts(self) -> (R, Box<dyn Behavior>) {
        (self.robot, self.root)
    }
}

/// Writes the children of `behavior` (if a composite) in pre-order.
fn record_children(behavior: &dyn Behavior, nodes: &mut [NodeOutcome], next: &mut usize) {
    let Some(composite) = behavior.as_composite() else {
        return;
    };
    let winner = composite.last_winner();
    for (i, ((_, child), bid)) in composite.children().zip(composite.last_bids()).enumerate() {
        nodes[*next] = NodeOutcome { action: bid.action, weight: bid.weight, won: winner == Some(i) };
        *next += 1;
        record_children(child, nodes, next);
    }
}
