//! What a tick leaves behind: the tree's shape, laid out once, and each
//! tick's record of what was sensed, decided and commanded.

use crate::{Action, Behavior, Command, GroundTruth, Hold, State};

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

    /// The path of [`TreeLayout::winning_leaf`] (`root/Avoid`), if there is
    /// one.
    pub fn winning_path(&self, record: &TickRecord) -> Option<&str> {
        self.winning_leaf(record).map(|i| self.nodes[i].path.as_str())
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

/// Everything that happened in one tick: what the robot sensed, what the
/// tree made of it, and what the robot was told.
///
/// The controller senses straight into the record's state and hands the
/// behaviours that same state, so a record costs no copy; sinks borrow it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TickRecord {
    /// Tick number, from 0.
    pub tick: u64,
    /// What the robot sensed, as the behaviours saw it: pose, ranges, the
    /// stereo frame, the egomotion estimate, the goal.
    pub state: State,
    /// Where the robot really was when it sensed, for robots that know (a
    /// simulator's); see [`Robot::ground_truth`](crate::Robot::ground_truth).
    pub truth: Option<GroundTruth>,
    /// Why the robot held still instead of obeying `command`, if it did;
    /// see [`Robot::hold`](crate::Robot::hold).
    pub hold: Option<Hold>,
    /// Every node's outcome, indexed like [`TreeLayout::nodes`]; node 0 is the
    /// root, whose action went to the robot.
    pub nodes: Vec<NodeOutcome>,
    /// The command sent to the robot.
    pub command: Command,
}

impl TickRecord {
    /// Copies `other`, reusing this record's buffers: a sink that keeps
    /// records (or hands them to another thread) allocates nothing once warm.
    pub fn copy_from(&mut self, other: &TickRecord) {
        let TickRecord { tick, state, truth, hold, nodes, command } = other;
        self.tick = *tick;
        self.state.copy_from(state);
        self.truth = *truth;
        self.hold = *hold;
        self.nodes.clone_from(nodes);
        self.command = *command;
    }

    /// Seconds since start, from the controller's clock: when the state
    /// was sensed.
    pub fn time(&self) -> f64 {
        self.state.time
    }

    /// The root behaviour's action.
    pub fn root_action(&self) -> Action {
        self.nodes.first().map_or(Action::none(), |n| n.action)
    }
}
