//! Arbiters that build the result channel by channel.

use super::{argmax_voter, max_vote, Arbiter, Arbitration, Bid};
use crate::{Action, Channel, State};

/// Per channel: the value from the voting child with the largest key among
/// those that set the channel. The result's vote is the largest vote.
fn fuse_by_largest(bids: &[Bid], key: impl Fn(&Bid) -> f64) -> Arbitration {
    if !bids.iter().any(Bid::votes) {
        return Arbitration::no_opinion();
    }
    let mut action = Action::with_vote(max_vote(bids));
    for channel in Channel::ALL {
        let mut best: Option<(f64, f64)> = None;
        for bid in bids {
            if let Some(value) = bid.channel(channel) {
                let k = key(bid);
                if best.is_none_or(|(best_key, _)| k > best_key) {
                    best = Some((k, value));
                }
            }
        }
        action.motion.set(channel, best.map(|(_, value)| value));
    }
    Arbitration { action, winner: argmax_voter(bids, Bid::utility) }
}

/// Per channel: the value from the child with the largest utility
/// `vote × weight` among those that set the channel.
#[derive(Clone, Copy, Debug, Default)]
pub struct ActivationFusion;

impl Arbiter for ActivationFusion {
    fn arbitrate(&mut self, _: &State, bids: &[Bid]) -> Arbitration {
        fuse_by_largest(bids, Bid::utility)
    }
}

/// Per channel: the value from the voting child with the largest weight
/// among those that set the channel.
#[derive(Clone, Copy, Debug, Default)]
pub struct PriorityFusion;

impl Arbiter for PriorityFusion {
    fn arbitrate(&mut self, _: &State, bids: &[Bid]) -> Arbitration {
        fuse_by_largest(bids, |b| b.weight)
    }
}

/// Per channel: the value from the child with the largest raw vote among
/// those that set the channel.
#[derive(Clone, Copy, Debug, Default)]
pub struct UtilityFusion;

impl Arbiter for UtilityFusion {
    fn arbitrate(&mut self, _: &State, bids: &[Bid]) -> Arbitration {
        fuse_by_largest(bids, |b| b.action.effective_vote())
    }
}

/// Per channel: the utility-weighted mean `Σ uᵢ xᵢ / Σ uᵢ` over the children
/// that set the channel; headings are fused as a weighted circular mean. The
/// result's vote is the largest vote.
#[derive(Clone, Copy, Debug, Default)]
pub struct CommandFusion;

impl Arbiter for CommandFusion {
    fn arbitrate(&mut self, _: &State, bids: &[Bid]) -> Arbitration {
        if !bids.iter().any(Bid::votes) {
            return Arbitration::no_opinion();
        }
        let mut action = Action::with_vote(max_vote(bids));
        for channel in Channel::ALL {
            let mut mean = WeightedMean::new(channel.is_direction());
            for bid in bids {
                if let Some(value) = bid.channel(channel) {
                    mean.add(value, bid.utility());
                }
            }
            action.motion.set(channel, mean.value());
        }
        Arbitration { action, winner: argmax_voter(bids, Bid::utility) }
    }
}

/// A running weighted mean of plain numbers or of directions.
///
/// Directions are averaged as unit vectors. Where they cancel exactly (two
/// opposite headings of equal weight) there is no mean direction; the value
/// of the heaviest single contribution is used instead of an arbitrary 0.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WeightedMean {
    direction: bool,
    total_weight: f64,
    sum: f64,
    sum_sin: f64,
    sum_cos: f64,
    heaviest: Option<(f64, f64)>,
}

impl WeightedMean {
    pub(crate) fn new(direction: bool) -> Self {
        WeightedMean { direction, total_weight: 0.0, sum: 0.0, sum_sin: 0.0, sum_cos: 0.0, heaviest: None }
    }

    /// Adds `value` with `weight`; non-positive weights contribute nothing.
    pub(crate) fn add(&mut self, value: f64, weight: f64) {
        if weight <= 0.0 || !weight.is_finite() {
            return;
        }
        self.total_weight += weight;
        if self.direction {
            let (s, c) = value.sin_cos();
            self.sum_sin += weight * s;
            self.sum_cos += weight * c;
        } else {
            self.sum += weight * value;
        }
        if self.heaviest.is_none_or(|(w, _)| weight > w) {
            self.heaviest = Some((weight, value));
        }
    }

    /// Sum of the weights added.
    pub(crate) fn total_weight(&self) -> f64 {
        self.total_weight
    }

    pub(crate) fn value(&self) -> Option<f64> {
        if self.total_weight <= 0.0 {
            return None;
        }
        if !self.direction {
            return Some(self.sum / self.total_weight);
        }
        let resultant = self.sum_sin.hypot(self.sum_cos);
        if resultant <= 1e-12 * self.total_weight {
            self.heaviest.map(|(_, v)| v)
        } else {
            Some(self.sum_sin.atan2(self.sum_cos))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn directional_mean_crosses_pi() {
        let mut m = WeightedMean::new(true);
        m.add(PI - 0.1, 1.0);
        m.add(-PI + 0.1, 1.0);
        let v = m.value().unwrap();
        assert!((v.abs() - PI).abs() < 1e-9, "{v}");
    }

    #[test]
    fn cancelling_directions_fall_back_to_heaviest() {
        let mut m = WeightedMean::new(true);
        m.add(0.0, 1.0);
        m.add(PI, 1.0);
        assert_eq!(m.value(), Some(0.0));
    }
}
