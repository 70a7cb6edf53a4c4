//! Arbiters that pick one child's action whole.

use super::{argmax_voter, Arbiter, Arbitration, Bid};
use crate::{Condition, State};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// The voting child with the largest weight; ties go to the earlier child.
#[derive(Clone, Copy, Debug, Default)]
pub struct HighestPriority;

impl Arbiter for HighestPriority {
    fn arbitrate(&mut self, _: &State, bids: &[Bid]) -> Arbitration {
        argmax_voter(bids, |b| b.weight).map_or(Arbitration::no_opinion(), |i| Arbitration::select(bids, i))
    }
}

/// The first voting child in declared order.
#[derive(Clone, Copy, Debug, Default)]
pub struct SimplePriority;

impl Arbiter for SimplePriority {
    fn arbitrate(&mut self, _: &State, bids: &[Bid]) -> Arbitration {
        bids.iter().position(Bid::votes).map_or(Arbitration::no_opinion(), |i| Arbitration::select(bids, i))
    }
}

/// The voting child with the largest utility `vote × weight`.
#[derive(Clone, Copy, Debug, Default)]
pub struct HighestActivation;

impl Arbiter for HighestActivation {
    fn arbitrate(&mut self, _: &State, bids: &[Bid]) -> Arbitration {
        argmax_voter(bids, Bid::utility).map_or(Arbitration::no_opinion(), |i| Arbitration::select(bids, i))
    }
}

/// Draws child `i` with probability `uᵢ / Σu` from a seeded generator and
/// keeps it for `hold_ticks` ticks (this one included), unless it stops
/// voting, in which case it draws again at once.
#[derive(Clone, Debug)]
pub struct MonteCarlo {
    rng: ChaCha8Rng,
    hold_ticks: u32,
    held: Option<usize>,
    remaining: u32,
}

impl MonteCarlo {
    /// The hold period when a scenario gives none.
    pub const DEFAULT_HOLD_TICKS: u32 = 20;

    /// A Monte Carlo arbiter drawing from `rng`, holding each draw for
    /// `hold_ticks` ticks (at least 1).
    pub fn new(rng: ChaCha8Rng, hold_ticks: u32) -> Self {
        MonteCarlo { rng, hold_ticks: hold_ticks.max(1), held: None, remaining: 0 }
    }

    fn draw(&mut self, bids: &[Bid]) -> Option<usize> {
        let total: f64 = bids.iter().map(Bid::utility).sum();
        if total <= 0.0 || !total.is_finite() {
            return None;
        }
        let mut target = self.rng.random::<f64>() * total;
        let mut last_positive = None;
        for (i, bid) in bids.iter().enumerate() {
            let u = bid.utility();
            if u <= 0.0 {
                continue;
            }
            last_positive = Some(i);
            if target < u {
                return Some(i);
            }
            target -= u;
        }
        // Rounding can leave a sliver past the last child: it belongs to it.
        last_positive
    }
}

impl Arbiter for MonteCarlo {
    fn arbitrate(&mut self, _: &State, bids: &[Bid]) -> Arbitration {
        if let Some(i) = self.held {
            if self.remaining > 0 && bids.get(i).is_some_and(|b| b.utility() > 0.0) {
                self.remaining -= 1;
                return Arbitration::select(bids, i);
            }
        }
        self.held = self.draw(bids);
        self.remaining = self.hold_ticks - 1;
        self.held.map_or(Arbitration::no_opinion(), |i| Arbitration::select(bids, i))
    }

    fn reset(&mut self) {
        self.held = None;
        self.remaining = 0;
    }
}

/// Child 0 while a condition on the state holds, child 1 otherwise.
#[derive(Clone, Debug)]
pub struct Conditional {
    when: Condition,
}

impl Conditional {
    /// Acts through child 0 while `when` holds.
    pub fn new(when: Condition) -> Self {
        Conditional { when }
    }
}

impl Arbiter for Conditional {
    fn arbitrate(&mut self, state: &State, bids: &[Bid]) -> Arbitration {
        let chosen = if self.when.holds(state) { 0 } else { 1 };
        match bids.get(chosen) {
            Some(bid) if bid.votes() => Arbitration::select(bids, chosen),
            _ => Arbitration::no_opinion(),
        }
    }
}
