//! The control loop: sense → state → root behaviour → action → command → act.

use crate::{Action, Behavior, BehaviorPanic, Clock, Command, Goal, Pose2, Robot, RobotError, State};

/// One node of the behaviour tree, as laid out once when the controller
/// starts. Nodes are numbered in pre-order; node 0 is the root.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeInfo {
    /// The node's name (the composite's child name, or the root's name).
    pub name: String,
    /// Slash-separated names from the root: `root/avoid/sonar`.
    pub path: String,
    /// 0 for the root.
    pub depth: usize,
    /// The parent node, `None` for the root.
    pub parent: Option<usize>,
    /// Whether the node is a composite.
    pub composite: bool,
}

/// The shape of the behaviour tree. It never changes while the controller
/// runs, so tick records refer to nodes by index instead of copying names.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TreeLayout {
    /// Every node, in pre-order.
    pub nodes: Vec<NodeInfo>,
}

impl TreeLayout {
    /// Lays out the tree under `root`.
    pub fn of(root: &dyn Behavior) -> Self {
        let mut layout = TreeLayout::default();
        layout.push(root, root.name().to_owned(), None);
        layout
    }

    fn push(&mut self, behavior: &dyn Behavior, name: String, parent: Option<usize>) {
        let (depth, path) = match parent {
            Some(p) => (self.nodes[p].depth + 1, format!("{}/{}", self.nodes[p].path, name)),
            None => (0, name.clone()),
        };
        let index = self.nodes.len();
        let composite = behavior.as_composite();
        self.nodes.push(NodeInfo { name, path, depth, parent, composite: composite.is_some() });
        if let Some(composite) = composite {
            for (child_name, child) in composite.children() {
                self.push(child, child_name.to_owned(), Some(index));
            }
        }
    }

    /// The leaf reached by following the winners down from the root, if the
    /// root had a winner at every level down to a leaf or a silent composite.
    pub fn winning_leaf(&self, record: &TickRecord) -> Option<usize> {
        if !record.nodes.first()?.won {
            return None;
        }
        let mut current = 0;
        loop {
            let next = (current + 1..self.nodes.len())
                .take_while(|&i| self.nodes[i].depth > self.nodes[current].depth)
                .find(|&i| self.nodes[i].parent == Some(current) && record.nodes[i].won);
            match next {
                Some(i) => current = i,
                None => return Some(current),
            }
        }
    }
}

/// What one node did in one tick.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NodeOutcome {
    /// The node's action.
    pub action: Action,
    /// The node's normalised weight within its parent (1 for the root).
    pub weight: f64,
    /// Whether the node won its parent's arbitration (the root "wins" when
    /// it has an opinion).
    pub won: bool,
}

/// A small copy of the state for records.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StateSummary {
    /// The estimated pose.
    pub pose: Pose2,
    /// Measured forward velocity, m/s.
    pub velocity: f64,
    /// Measured rotational velocity, rad/s.
    pub rot_velocity: f64,
    /// The nearest range reading, m.
    pub nearest_range: Option<f64>,
}

/// Everything that happened in one tick.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TickRecord {
    /// Tick number, from 0.
    pub tick: u64,
    /// Seconds since start, from the controller's clock.
    pub time: f64,
    /// What the robot sensed.
    pub state: StateSummary,
    /// Every node's outcome, indexed like [`TreeLayout::nodes`]; node 0 is the
    /// root, whose action went to the robot.
    pub nodes: Vec<NodeOutcome>,
    /// The command sent to the robot.
    pub command: Command,
}

impl TickRecord {
    /// The root behaviour's action.
    pub fn root_action(&self) -> Action {
        self.nodes.first().map_or(Action::none(), |n| n.action)
    }
}

/// Receives every tick's record: a trajectory writer, a log file, a live plot.
pub trait TickSink: Send {
    /// Called once before the first tick with the tree's shape.
    fn start(&mut self, _layout: &TreeLayout) -> std::io::Result<()> {
        Ok(())
    }
    /// Called after every tick.
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()>;
    /// Called once when the controller shuts down: flush here.
    fn finish(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Logs every tick at `trace` level through `tracing`.
#[derive(Clone, Copy, Debug, Default)]
pub struct TracingSink;

impl TickSink for TracingSink {
    fn record(&mut self, r: &TickRecord) -> std::io::Result<()> {
        tracing::trace!(tick = r.tick, time = r.time, x = r.state.pose.x, y = r.state.pose.y, command = ?r.command, "tick");
        Ok(())
    }
}

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
    state: State,
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
            state: State::default(),
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
        self.state.goal = goal;
    }

    /// The tree's shape.
    pub fn layout(&self) -> &TreeLayout {
        &self.layout
    }

    /// The state as of the latest tick.
    pub fn state(&self) -> &State {
        &self.state
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
        self.state.time = self.clock.now();
        self.robot.sense(&mut self.state)?;
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
        let (root, state) = (&mut self.root, &self.state);
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| root.gen_action(state))).map_err(|payload| {
            let panic = BehaviorPanic::caught(root.name(), payload);
            // A leaf root has no composite to silence it.
            self.root_faulted = root.as_composite().is_none();
            panic
        })
    }

    fn fill_record(&mut self, action: Action, command: Command) {
        let r = &mut self.record;
        r.tick = self.ticks;
        r.time = self.state.time;
        r.state = StateSummary {
            pose: self.state.pose,
            velocity: self.state.velocity,
            rot_velocity: self.state.rot_velocity,
            nearest_range: self.state.nearest_range(),
        };
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
