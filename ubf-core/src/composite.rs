//! Composite behaviours: children plus an arbiter, itself a behaviour.

use crate::{Action, Arbiter, Behavior, BehaviorPanic, Bid, State};

struct Child {
    name: String,
    behavior: Box<dyn Behavior>,
    raw_weight: f64,
    /// The child panicked once; it stays silent from then on.
    faulted: bool,
}

/// Children and an arbiter, behaving as one behaviour, so trees nest to any
/// depth.
///
/// Weights are normalised to sum to 1 whatever the number of children; a
/// negative or non-finite weight counts as 0, and if every weight is 0 the
/// children share equally. Around the arbiter the composite applies the
/// safety rules: limits from every voting child combine "most restrictive
/// wins", and a stop from any voting child wins.
///
/// With [`Composite::vote`] set, the composite bids that vote to its parent
/// whenever it has an opinion at all (a composite whose children are silent
/// stays silent, so it cannot win its parent's arbitration with nothing).
///
/// A child that panics is caught here: it is silenced for good and the
/// panic goes on up as a [`BehaviorPanic`] naming its path, for the
/// controller to stop the robot.
///
/// ```
/// use ubf_core::{arbiter::CommandFusion, from_fn, Action, Behavior, Composite, State};
/// let mut tree = Composite::new("root", CommandFusion)
///     .child(from_fn("fast", |_: &State| Action::with_vote(1.0).velocity(1.0)), 1.0)
///     .child(from_fn("slow", |_: &State| Action::with_vote(1.0).velocity(0.0)), 3.0);
/// let action = tree.gen_action(&State::default());
/// assert!((action.motion.velocity.unwrap() - 0.25).abs() < 1e-12);
/// ```
pub struct Composite {
    name: String,
    children: Vec<Child>,
    arbiter: Box<dyn Arbiter>,
    vote: Option<f64>,
    /// One bid per child, reused every tick so that a tick allocates nothing.
    bids: Vec<Bid>,
    winner: Option<usize>,
}

impl Composite {
    /// An empty composite with this arbiter.
    pub fn new(name: impl Into<String>, arbiter: impl Arbiter + 'static) -> Self {
        Self::with_arbiter(name, Box::new(arbiter))
    }

    /// An empty composite with an already boxed arbiter.
    pub fn with_arbiter(name: impl Into<String>, arbiter: Box<dyn Arbiter>) -> Self {
        Composite { name: name.into(), children: Vec::new(), arbiter, vote: None, bids: Vec::new(), winner: None }
    }

    /// Adds a child named after the behaviour.
    pub fn child(mut self, behavior: impl Behavior + 'static, weight: f64) -> Self {
        let name = behavior.name().to_owned();
        self.push_child(name, Box::new(behavior), weight);
        self
    }

    /// Adds a child under a name of your choosing.
    pub fn named_child(mut self, name: impl Into<String>, behavior: impl Behavior + 'static, weight: f64) -> Self {
        self.push_child(name.into(), Box::new(behavior), weight);
        self
    }

    /// Sets the vote this composite bids to its parent.
    pub fn vote(mut self, vote: f64) -> Self {
        self.vote = Some(vote);
        self
    }

    /// Adds a child; the weights of all children are normalised again.
    pub fn push_child(&mut self, name: String, behavior: Box<dyn Behavior>, weight: f64) {
        let raw_weight = if weight.is_finite() && weight > 0.0 { weight } else { 0.0 };
        self.children.push(Child { name, behavior, raw_weight, faulted: false });
        self.bids.push(Bid::default());
        let total: f64 = self.children.iter().map(|c| c.raw_weight).sum();
        let n = self.children.len() as f64;
        for (child, bid) in self.children.iter().zip(&mut self.bids) {
            bid.weight = if total > 0.0 { child.raw_weight / total } else { 1.0 / n };
        }
    }

    /// Sets or clears the vote override.
    pub fn set_vote(&mut self, vote: Option<f64>) {
        self.vote = vote;
    }

    /// The children's names and behaviours, in declared order.
    pub fn children(&self) -> impl ExactSizeIterator<Item = (&str, &dyn Behavior)> {
        self.children.iter().map(|c| (c.name.as_str(), c.behavior.as_ref()))
    }

    /// The arbiter's name.
    pub fn arbiter_name(&self) -> &str {
        self.arbiter.name()
    }

    /// The vote this composite bids to its parent instead of its winner's,
    /// if one is set.
    pub fn vote_override(&self) -> Option<f64> {
        self.vote
    }

    /// Each child's action and normalised weight from the latest tick.
    pub fn last_bids(&self) -> &[Bid] {
        &self.bids
    }

    /// The child that won the latest tick, if any voted.
    pub fn last_winner(&self) -> Option<usize> {
        self.winner
    }
}

/// Limits combine "most restrictive wins"; a stop from any voting child wins,
/// and the strongest stopping child is then the winner.
fn apply_safety(action: &mut Action, winner: &mut Option<usize>, bids: &[Bid]) {
    let mut strongest_stop: Option<usize> = None;
    for (i, bid) in bids.iter().enumerate().filter(|(_, b)| b.votes()) {
        action.motion.restrict_to(&bid.action.motion);
        if bid.action.stop && strongest_stop.is_none_or(|s| bid.utility() > bids[s].utility()) {
            strongest_stop = Some(i);
        }
    }
    if let Some(s) = strongest_stop {
        if !action.stop {
            *winner = Some(s);
        }
        action.stop = true;
        action.vote = action.effective_vote().max(bids[s].action.vote);
    }
}

impl Behavior for Composite {
    fn gen_action(&mut self, state: &State) -> Action {
        for (child, bid) in self.children.iter_mut().zip(&mut self.bids) {
            if child.faulted {
                bid.action = Action::none();
                continue;
            }
            let behavior = &mut child.behavior;
            // The action is written straight into the bid, not passed back
            // through the `Result`: one copy of it fewer every child, every tick.
            let asked = crate::catch_reported(|| bid.action = behavior.gen_action(state));
            match asked {
                Ok(()) => {}
                Err(payload) => {
                    child.faulted = true;
                    bid.action = Action::none();
                    std::panic::resume_unwind(Box::new(BehaviorPanic::caught(&child.name, payload)));
                }
            }
        }
        let decision = self.arbiter.arbitrate(state, &self.bids);
        let (mut action, mut winner) = (decision.action, decision.winner);
        apply_safety(&mut action, &mut winner, &self.bids);
        if let Some(vote) = self.vote {
            if action.is_voting() {
                action.vote = vote;
            }
        }
        self.winner = winner.filter(|_| action.is_voting());
        action
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn reset(&mut self) {
        self.arbiter.reset();
        self.winner = None;
        for child in &mut self.children {
            child.behavior.reset();
        }
    }

    fn as_composite(&self) -> Option<&Composite> {
        Some(self)
    }
}
