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
        // One pass over the bids, every channel at once: each channel still
        // sums its bids in order, so the result is the same as channel by
        // channel, for a third of the work.
        let mut means = Channel::ALL.map(|channel| WeightedMean::new(channel.is_direction()));
        for bid in bids.iter().filter(|b| b.votes()) {
            // What `Bid::utility` and `Bid::channel` give a voting bid,
            // without asking again whether it votes.
            let utility = bid.action.vote * bid.weight;
            for (mean, channel) in means.iter_mut().zip(Channel::ALL) {
                if let Some(value) = bid.action.motion.get(channel).filter(|v| v.is_finite()) {
                    mean.add(value, utility);
                }
            }
        }
        let mut action = Action::with_vote(max_vote(bids));
        for (mean, channel) in means.iter().zip(Channel::ALL) {
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
/// A single direction is its own mean: its sine and cosine are taken only
/// once a second one arrives (the common case, one behaviour steering by
/// heading, then costs no trigonometry).
#[derive(Clone, Copy, Debug)]
pub(crate) struct WeightedMean {
    direction: bool,
    contributions: u32,
    total_weight: f64,
    sum: f64,
    sum_sin: f64,
    sum_cos: f64,
    /// The first contribution, `(weight, value)`.
    first: (f64, f64),
    /// The heaviest contribution, `(weight, value)`.
    heaviest: (f64, f64),
}

impl WeightedMean {
    pub(crate) fn new(direction: bool) -> Self {
        WeightedMean {
            direction,
            contributions: 0,
            total_weight: 0.0,
            sum: 0.0,
            sum_sin: 0.0,
            sum_cos: 0.0,
            first: (0.0, 0.0),
            heaviest: (0.0, 0.0),
        }
    }

    /// Adds `value` with `weight`; non-positive weights contribute nothing.
    pub(crate) fn add(&mut self, value: f64, weight: f64) {
        if weight <= 0.0 || !weight.is_finite() {
            return;
        }
        self.contributions += 1;
        self.total_weight += weight;
        if weight > self.heaviest.0 {
            self.heaviest = (weight, value);
        }
        if !self.direction {
            self.sum += weight * value;
            return;
        }
        match self.contributions {
            1 => self.first = (weight, value),
            2 => {
                self.add_direction(self.first);
                self.add_direction((weight, value));
            }
            _ => self.add_direction((weight, value)),
        }
    }

    fn add_direction(&mut self, (weight, value): (f64, f64)) {
        let (s, c) = value.sin_cos();
        self.sum_sin += weight * s;
        self.sum_cos += weight * c;
    }

    /// Sum of the weights added.
    pub(crate) fn total_weight(&self) -> f64 {
        self.total_weight
    }

    pub(crate) fn value(&self) -> Option<f64> {
        if self.contributions == 0 {
            return None;
        }
        if !self.direction {
            return Some(self.sum / self.total_weight);
        }
        if self.contributions == 1 {
            let value = self.first.1;
            let within = value > -std::f64::consts::PI && value <= std::f64::consts::PI;
            return Some(if within { value } else { crate::wrap_angle(value) });
        }
        // The resultant's length, squared: `hypot` cost a tenth of a tick.
        let resultant_squared = self.sum_sin * self.sum_sin + self.sum_cos * self.sum_cos;
        if resultant_squared <= (1e-12 * self.total_weight).powi(2) {
            Some(self.heaviest.1)
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
    fn one_direction_is_its_own_mean_within_the_half_open_circle() {
        for (value, mean) in [(0.2, 0.2), (PI, PI), (-PI, PI), (4.0, 4.0 - 2.0 * PI)] {
            let mut m = WeightedMean::new(true);
            m.add(value, 0.7);
            assert!((m.value().unwrap() - mean).abs() < 1e-12, "{value}: {:?}", m.value());
        }
        let mut m = WeightedMean::new(true);
        m.add(0.2, 0.7);
        assert_eq!(m.value(), Some(0.2), "exactly, not through sine, cosine and arctangent");
        m.add(0.4, 0.7);
        assert!((m.value().unwrap() - 0.3).abs() < 1e-12, "a second direction is averaged: {:?}", m.value());
    }

    #[test]
    fn cancelling_directions_fall_back_to_heaviest() {
        let mut m = WeightedMean::new(true);
        m.add(0.0, 1.0);
        m.add(PI, 1.0);
        assert_eq!(m.value(), Some(0.0));
    }
}
