//! The ARIA-style priority resolver.

use super::fusion::WeightedMean;
use super::{Arbiter, Arbitration, Bid};
use crate::{Action, Channel, State};

/// Resolves children by integer priority, reading each vote as a strength
/// in [0, 1] (larger votes are clamped to 1).
///
/// Children of equal priority are averaged channel by channel,
/// `d = Σ dᵢ sᵢ / Σ sᵢ` with strength `min(Σ sᵢ, 1)`. Levels are then merged
/// from the highest priority down: with accumulated strength `s_acc`, the next
/// level contributes `s_eff = min(s_new, 1 − s_acc)` and
/// `d = (s_acc d_acc + s_eff d_new) / (s_acc + s_eff)`. Once a channel is at
/// strength 1 nothing below changes it. The result's vote is the largest
/// channel strength.
#[derive(Clone, Debug)]
pub struct PriorityResolver {
    priorities: Vec<i32>,
    /// Child indices, highest priority first; stable, so declared order
    /// breaks ties.
    order: Vec<usize>,
}

impl PriorityResolver {
    /// A resolver for children with these priorities, in declared order.
    /// Children beyond the list take no part (a scenario file is checked so
    /// that the counts match).
    pub fn new(priorities: Vec<i32>) -> Self {
        let mut order: Vec<usize> = (0..priorities.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(priorities[i]));
        PriorityResolver { priorities, order }
    }

    fn strength(bid: &Bid) -> f64 {
        bid.action.effective_vote().min(1.0)
    }

    /// The value and accumulated strength of one channel.
    fn resolve_channel(&self, bids: &[Bid], channel: Channel) -> Option<(f64, f64)> {
        let mut accumulated = WeightedMean::new(channel.is_direction());
        let mut level_start = 0;
        while level_start < self.order.len() && accumulated.total_weight() < 1.0 {
            let priority = self.priorities[self.order[level_start]];
            let level_end = self.order[level_start..]
                .iter()
                .position(|&i| self.priorities[i] != priority)
                .map_or(self.order.len(), |n| level_start + n);
            let mut level = WeightedMean::new(channel.is_direction());
            for &i in &self.order[level_start..level_end] {
                if let Some(value) = bids.get(i).and_then(|b| b.channel(channel)) {
                    level.add(value, Self::strength(&bids[i]));
                }
            }
            if let Some(value) = level.value() {
                let s_new = level.total_weight().min(1.0);
                accumulated.add(value, s_new.min(1.0 - accumulated.total_weight()));
            }
            level_start = level_end;
        }
        accumulated.value().map(|v| (v, accumulated.total_weight().min(1.0)))
    }
}

impl Arbiter for PriorityResolver {
    fn arbitrate(&mut self, _: &State, bids: &[Bid]) -> Arbitration {
        let rank = |i: usize| (self.priorities[i], Self::strength(&bids[i]));
        let mut winner: Option<usize> = None;
        for (i, _) in bids.iter().enumerate().take(self.priorities.len()).filter(|(_, b)| b.votes()) {
            let better = winner.is_none_or(|w| rank(i) > rank(w));
            if better {
                winner = Some(i);
            }
        }
        let Some(winner) = winner else {
            return Arbitration::no_opinion();
        };
        let mut action = Action::none();
        let mut strength: f64 = 0.0;
        for channel in Channel::ALL {
            let resolved = self.resolve_channel(bids, channel);
            action.motion.set(channel, resolved.map(|(v, _)| v));
            strength = strength.max(resolved.map_or(0.0, |(_, s)| s));
        }
        // An action with limits or a stop but no command channel still bids.
        action.vote = if strength > 0.0 { strength } else { Self::strength(&bids[winner]) };
        Arbitration { action, winner: Some(winner) }
    }
}
