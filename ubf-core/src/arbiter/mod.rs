//! Arbiters: how a composite turns its children's actions into one.
//!
//! Each child's action arrives as a [`Bid`] with the child's weight,
//! normalised so that the weights of a composite sum to 1. A child's
//! *utility* is `vote × weight`. Children that do not vote (vote 0, negative
//! or not a number) are ignored by every arbiter.
//!
//! Arbiters decide the command channels only. The safety channels are
//! combined by the [`crate::Composite`] around every arbiter, so that no
//! arbiter can lose them: limits combine "most restrictive wins" and a stop
//! request from any voting child wins.

mod fusion;
mod resolver;
mod selection;

pub use fusion::{ActivationFusion, CommandFusion, PriorityFusion, UtilityFusion};
pub use resolver::PriorityResolver;
pub use selection::{Conditional, HighestActivation, HighestPriority, MonteCarlo, SimplePriority};

use crate::{Action, Channel, Condition, State};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// One child's action and its normalised weight.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bid {
    /// What the child wants.
    pub action: Action,
    /// The child's weight, normalised over its composite (Σ = 1).
    pub weight: f64,
}

impl Bid {
    /// A bid of `action` at `weight`.
    pub const fn new(action: Action, weight: f64) -> Self {
        Bid { action, weight }
    }

    /// Whether the child votes at all.
    pub fn votes(&self) -> bool {
        self.action.is_voting()
    }

    /// `vote × weight`, or 0 for a child that does not vote.
    pub fn utility(&self) -> f64 {
        self.action.effective_vote() * self.weight
    }

    /// The child's value on one channel, if it votes and set the channel to a
    /// finite number. A non-finite value counts as unset rather than
    /// poisoning a fused result.
    pub fn channel(&self, channel: Channel) -> Option<f64> {
        if !self.votes() {
            return None;
        }
        self.action.motion.get(channel).filter(|v| v.is_finite())
    }
}

/// The outcome of one arbitration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Arbitration {
    /// The combined action.
    pub action: Action,
    /// The child that won: the one selected, or for fusing arbiters the one
    /// that contributed most. `None` when nobody voted.
    pub winner: Option<usize>,
}

impl Arbitration {
    /// Nobody voted: no opinion, no winner.
    pub const fn no_opinion() -> Self {
        Arbitration { action: Action::none(), winner: None }
    }

    /// Child `index`'s action taken whole.
    pub fn select(bids: &[Bid], index: usize) -> Self {
        Arbitration { action: bids[index].action, winner: Some(index) }
    }
}

/// Combines the actions of a composite's children into one.
pub trait Arbiter: Send {
    /// Combines `bids` (one per child, in declared order) given the state.
    fn arbitrate(&mut self, state: &State, bids: &[Bid]) -> Arbitration;

    /// Forgets any memory (a held choice, a generator's position is kept).
    fn reset(&mut self) {}

    /// A name for pictures of the tree: by default the type's own name.
    fn name(&self) -> &str {
        let full = std::any::type_name::<Self>();
        full.rsplit("::").next().unwrap_or(full)
    }
}

/// The first voting child with the largest key (ties go to the earlier child).
fn argmax_voter(bids: &[Bid], key: impl Fn(&Bid) -> f64) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, bid) in bids.iter().enumerate().filter(|(_, b)| b.votes()) {
        let k = key(bid);
        if best.is_none_or(|(_, bk)| k > bk) {
            best = Some((i, k));
        }
    }
    best.map(|(i, _)| i)
}

/// The largest vote among voting children, or 0.
fn max_vote(bids: &[Bid]) -> f64 {
    bids.iter().map(|b| b.action.effective_vote()).fold(0.0, f64::max)
}

/// An arbiter as written in a scenario file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ArbiterSpec {
    /// See [`HighestPriority`].
    HighestPriority,
    /// See [`SimplePriority`].
    SimplePriority,
    /// See [`HighestActivation`].
    HighestActivation,
    /// See [`MonteCarlo`].
    MonteCarlo {
        /// Ticks a drawn child keeps control while it still votes.
        #[serde(default = "default_hold_ticks")]
        hold_ticks: u32,
    },
    /// See [`ActivationFusion`].
    ActivationFusion,
    /// See [`PriorityFusion`].
    PriorityFusion,
    /// See [`UtilityFusion`].
    UtilityFusion,
    /// See [`CommandFusion`].
    CommandFusion,
    /// See [`Conditional`]; needs exactly two children.
    Conditional {
        /// Child 0 acts while this holds, child 1 otherwise.
        #[serde(deserialize_with = "crate::config::checked")]
        when: Condition,
    },
    /// See [`PriorityResolver`]; one priority per child.
    PriorityResolver {
        /// One integer priority per child, in declared order; higher first.
        priorities: Vec<i32>,
    },
}

fn default_hold_ticks() -> u32 {
    MonteCarlo::DEFAULT_HOLD_TICKS
}

impl ArbiterSpec {
    /// Checks that the arbiter fits a composite of `children` children.
    pub fn check(&self, children: usize) -> Result<(), String> {
        match self {
            ArbiterSpec::Conditional { .. } if children != 2 => {
                Err(format!("Conditional needs exactly 2 children (act-when-true, act-otherwise), found {children}"))
            }
            ArbiterSpec::PriorityResolver { priorities } if priorities.len() != children => {
                Err(format!("PriorityResolver has {} priorities for {children} children", priorities.len()))
            }
            ArbiterSpec::MonteCarlo { hold_ticks: 0 } => Err("MonteCarlo hold_ticks must be at least 1".into()),
            _ => Ok(()),
        }
    }

    /// Builds the arbiter. `rng` is used by the arbiters that draw.
    pub fn build(&self, rng: ChaCha8Rng) -> Box<dyn Arbiter> {
        match self {
            ArbiterSpec::HighestPriority => Box::new(HighestPriority),
            ArbiterSpec::SimplePriority => Box::new(SimplePriority),
            ArbiterSpec::HighestActivation => Box::new(HighestActivation),
            ArbiterSpec::MonteCarlo { hold_ticks } => Box::new(MonteCarlo::new(rng, *hold_ticks)),
            ArbiterSpec::ActivationFusion => Box::new(ActivationFusion),
            ArbiterSpec::PriorityFusion => Box::new(PriorityFusion),
            ArbiterSpec::UtilityFusion => Box::new(UtilityFusion),
            ArbiterSpec::CommandFusion => Box::new(CommandFusion),
            ArbiterSpec::Conditional { when } => Box::new(Conditional::new(when.clone())),
            ArbiterSpec::PriorityResolver { priorities } => Box::new(PriorityResolver::new(priorities.clone())),
        }
    }
}
