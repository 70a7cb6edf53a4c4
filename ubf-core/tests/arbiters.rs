//! A worked example for every arbiter, ARIA's documented resolver example, and
//! one regression test for each defect of the older implementations.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;
use ubf_core::arbiter::*;
use ubf_core::{from_fn, Action, Behavior, Composite, Condition, State};

fn bid(vote: f64, weight: f64, action: Action) -> Bid {
    Bid::new(Action { vote, ..action }, weight)
}

fn v(velocity: f64) -> Action {
    Action::none().velocity(velocity)
}

fn arbitrate(arbiter: &mut dyn Arbiter, bids: &[Bid]) -> Arbitration {
    arbiter.arbitrate(&State::default(), bids)
}

/// A behaviour that always returns `action`.
fn fixed(name: &str, action: Action) -> impl Behavior {
    from_fn(name.to_owned(), move |_: &State| action)
}

#[test]
fn highest_priority_takes_the_heaviest_voter() {
    // Child 2 is heaviest but silent; child 1 is the heaviest voter.
    let bids = [bid(0.9, 0.1, v(1.0)), bid(0.1, 0.3, v(2.0)), bid(0.0, 0.6, v(3.0))];
    let r = arbitrate(&mut HighestPriority, &bids);
    assert_eq!((r.winner, r.action.motion.velocity), (Some(1), Some(2.0)));
    // Ties go to the earlier child.
    let tied = [bid(0.2, 0.5, v(1.0)), bid(0.9, 0.5, v(2.0))];
    assert_eq!(arbitrate(&mut HighestPriority, &tied).winner, Some(0));
}

#[test]
fn simple_priority_takes_the_first_voter() {
    let bids = [bid(0.0, 0.5, v(1.0)), bid(0.1, 0.1, v(2.0)), bid(0.9, 0.4, v(3.0))];
    assert_eq!(arbitrate(&mut SimplePriority, &bids).winner, Some(1));
    let silent = [bid(0.0, 1.0, v(1.0))];
    assert_eq!(arbitrate(&mut SimplePriority, &silent), Arbitration::no_opinion());
}

#[test]
fn highest_activation_takes_the_largest_utility() {
    // Utilities 0.09, 0.12, 0.10.
    let bids = [bid(0.9, 0.1, v(1.0)), bid(0.4, 0.3, v(2.0)), bid(0.1667, 0.6, v(3.0))];
    let r = arbitrate(&mut HighestActivation, &bids);
    assert_eq!((r.winner, r.action.motion.velocity), (Some(1), Some(2.0)));
}

#[test]
fn activation_fusion_takes_each_channel_from_the_most_activated_child_that_set_it() {
    // Utilities 0.2 (velocity only), 0.1 (velocity and turn), 0.3 (silent).
    let bids =
        [bid(0.4, 0.5, v(1.0)), bid(0.4, 0.25, v(2.0).rot_velocity(0.5)), bid(0.0, 0.25, v(3.0).rot_velocity(-0.5))];
    let r = arbitrate(&mut ActivationFusion, &bids);
    assert_eq!(r.action.motion.velocity, Some(1.0));
    assert_eq!(r.action.motion.rot_velocity, Some(0.5));
    assert_eq!(r.action.vote, 0.4);
    assert_eq!(r.winner, Some(0));
}

#[test]
fn priority_fusion_takes_each_channel_from_the_heaviest_voter_that_set_it() {
    let bids = [
        bid(0.1, 0.6, v(1.0)),
        bid(0.9, 0.3, v(2.0).rot_velocity(0.5)),
        bid(0.9, 0.1, Action::none().rot_velocity(-0.5).heading(1.0)),
    ];
    let r = arbitrate(&mut PriorityFusion, &bids);
    assert_eq!(r.action.motion.velocity, Some(1.0));
    assert_eq!(r.action.motion.rot_velocity, Some(0.5));
    assert_eq!(r.action.motion.heading, Some(1.0));
}

#[test]
fn utility_fusion_takes_each_channel_from_the_largest_raw_vote() {
    let bids = [bid(0.3, 0.9, v(1.0).rot_velocity(0.1)), bid(0.8, 0.1, v(2.0))];
    let r = arbitrate(&mut UtilityFusion, &bids);
    assert_eq!(r.action.motion.velocity, Some(2.0));
    assert_eq!(r.action.motion.rot_velocity, Some(0.1));
    assert_eq!(r.action.vote, 0.8);
}

#[test]
fn command_fusion_is_the_utility_weighted_mean() {
    // Utilities 0.3 and 0.1: velocity (0.3·1 + 0.1·2) / 0.4 = 1.25.
    let bids = [bid(0.6, 0.5, v(1.0)), bid(0.2, 0.5, v(2.0).rot_velocity(-1.0))];
    let r = arbitrate(&mut CommandFusion, &bids);
    assert!((r.action.motion.velocity.unwrap() - 1.25).abs() < 1e-12);
    assert_eq!(r.action.motion.rot_velocity, Some(-1.0));
    assert_eq!(r.action.vote, 0.6);
    assert_eq!(r.winner, Some(0));
}

#[test]
fn command_fusion_averages_headings_on_the_circle() {
    // 170° and −170° average to 180°, not to 0°.
    let a = Action::none().heading(170f64.to_radians());
    let b = Action::none().heading(-170f64.to_radians());
    let r = arbitrate(&mut CommandFusion, &[bid(1.0, 0.5, a), bid(1.0, 0.5, b)]);
    assert!((r.action.motion.heading.unwrap().abs() - PI).abs() < 1e-9);
}

#[test]
fn monte_carlo_draws_in_proportion_to_utility() {
    // Utilities 0.1, 0.3, 0.6 (the raw votes are equal).
    let bids = [bid(1.0, 0.1, v(0.0)), bid(1.0, 0.3, v(1.0)), bid(1.0, 0.6, v(2.0))];
    let mut mc = MonteCarlo::new(ChaCha8Rng::seed_from_u64(1), 1);
    let mut counts = [0usize; 3];
    let draws = 30_000;
    for _ in 0..draws {
        counts[arbitrate(&mut mc, &bids).winner.unwrap()] += 1;
    }
    for (count, expected) in counts.iter().zip([0.1, 0.3, 0.6]) {
        let share = *count as f64 / draws as f64;
        // Four standard deviations of a binomial share at n = 30 000.
        let tolerance = 4.0 * (expected * (1.0 - expected) / draws as f64).sqrt();
        assert!((share - expected).abs() < tolerance, "{counts:?}");
    }
}

#[test]
fn conditional_switches_on_the_state() {
    let bids = [bid(1.0, 0.5, v(0.0)), bid(1.0, 0.5, v(1.0))];
    let mut arbiter = Conditional::new(Condition::Bumped);
    let mut state = State::default();
    assert_eq!(arbiter.arbitrate(&state, &bids).winner, Some(1));
    state.bumpers.front = true;
    assert_eq!(arbiter.arbitrate(&state, &bids).winner, Some(0));
}

#[test]
fn aria_resolver_documented_example() {
    // A at priority 4 wants −400 at strength 0.25; B and C at priority 3
    // average to 0 at strength 1; D at priority 1 is ignored.
    let bids =
        [bid(0.25, 0.25, v(-400.0)), bid(0.5, 0.25, v(100.0)), bid(0.5, 0.25, v(-100.0)), bid(1.0, 0.25, v(5000.0))];
    let mut resolver = PriorityResolver::new(vec![4, 3, 3, 1]);
    let r = arbitrate(&mut resolver, &bids);
    assert!((r.action.motion.velocity.unwrap() + 100.0).abs() < 1e-9, "{:?}", r.action);
    assert!((r.action.vote - 1.0).abs() < 1e-12);
    assert_eq!(r.winner, Some(0));
}

#[test]
fn aria_resolver_leaves_channels_to_lower_levels_until_saturated() {
    // Priority 2 sets only velocity; the turn comes from priority 1.
    let bids = [bid(1.0, 0.5, v(1.0)), bid(1.0, 0.5, v(9.0).rot_velocity(0.3))];
    let r = arbitrate(&mut PriorityResolver::new(vec![2, 1]), &bids);
    assert_eq!(r.action.motion.velocity, Some(1.0));
    assert_eq!(r.action.motion.rot_velocity, Some(0.3));
}

// --- Regression tests for the defects of the older implementations. ---

#[test]
fn regression_monte_carlo_first_call_chooses_rather_than_doing_nothing() {
    let bids = [bid(1.0, 1.0, v(1.0))];
    let mut mc = MonteCarlo::new(ChaCha8Rng::seed_from_u64(0), 20);
    assert_eq!(arbitrate(&mut mc, &bids).winner, Some(0));
}

#[test]
fn regression_monte_carlo_counts_its_hold_period_down() {
    let bids = [bid(1.0, 0.5, v(0.0)), bid(1.0, 0.5, v(1.0))];
    let hold = 5;
    let mut mc = MonteCarlo::new(ChaCha8Rng::seed_from_u64(3), hold);
    let winners: Vec<usize> = (0..400).map(|_| arbitrate(&mut mc, &bids).winner.unwrap()).collect();
    // Within each hold window the choice never changes…
    for window in winners.chunks(hold as usize) {
        assert!(window.iter().all(|&w| w == window[0]), "{winners:?}");
    }
    // …and across windows it does change (an arbiter that never counted down
    // would hold its first choice for ever).
    let firsts: Vec<usize> = winners.chunks(hold as usize).map(|w| w[0]).collect();
    assert!(firsts.contains(&0) && firsts.contains(&1), "{firsts:?}");
}

#[test]
fn regression_monte_carlo_redraws_when_the_held_child_falls_silent() {
    let mut mc = MonteCarlo::new(ChaCha8Rng::seed_from_u64(0), 100);
    assert_eq!(arbitrate(&mut mc, &[bid(1.0, 0.5, v(0.0)), bid(0.0, 0.5, v(1.0))]).winner, Some(0));
    assert_eq!(arbitrate(&mut mc, &[bid(0.0, 0.5, v(0.0)), bid(1.0, 0.5, v(1.0))]).winner, Some(1));
}

#[test]
fn regression_monte_carlo_samples_utilities_not_raw_votes() {
    // Equal votes, weights 0.01 and 0.99: drawing on raw votes would split
    // evenly.
    let bids = [bid(1.0, 0.01, v(0.0)), bid(1.0, 0.99, v(1.0))];
    let mut mc = MonteCarlo::new(ChaCha8Rng::seed_from_u64(9), 1);
    let zeros = (0..2000).filter(|_| arbitrate(&mut mc, &bids).winner == Some(0)).count();
    assert!(zeros < 60, "child 0 drawn {zeros} times of 2000");
}

#[test]
fn regression_priority_fusion_keeps_weights_on_their_own_children() {
    // The silent first child must not shift the weights onto the others: the
    // heaviest voter is child 2, whatever child 0 does.
    let bids = [bid(0.0, 0.5, v(0.0)), bid(1.0, 0.1, v(1.0)), bid(1.0, 0.4, v(2.0))];
    assert_eq!(arbitrate(&mut PriorityFusion, &bids).action.motion.velocity, Some(2.0));
}

#[test]
fn regression_activation_fusion_takes_the_best_not_the_last_voter() {
    let bids = [bid(0.9, 0.5, v(1.0)), bid(0.2, 0.5, v(2.0))];
    assert_eq!(arbitrate(&mut ActivationFusion, &bids).action.motion.velocity, Some(1.0));
}

#[test]
fn regression_weights_work_for_any_number_of_children() {
    let mut tree = Composite::new("root", CommandFusion);
    for i in 0..7 {
        tree = tree.child(fixed(&format!("c{i}"), Action::with_vote(1.0).velocity(i as f64)), 1.0);
    }
    let action = tree.gen_action(&State::default());
    assert!((action.motion.velocity.unwrap() - 3.0).abs() < 1e-12);
    let weights: Vec<f64> = tree.last_bids().iter().map(|b| b.weight).collect();
    assert!(weights.iter().all(|w| (w - 1.0 / 7.0).abs() < 1e-12), "{weights:?}");
}

#[test]
fn regression_command_fusion_treats_zero_as_a_command() {
    // One child commands a stop of the wheels with 0.0; it must pull the
    // mean down, not be skipped as unset.
    let bids = [bid(1.0, 0.5, v(0.0)), bid(1.0, 0.5, v(1.0))];
    assert_eq!(arbitrate(&mut CommandFusion, &bids).action.motion.velocity, Some(0.5));
    let only_zero = [bid(1.0, 1.0, v(0.0))];
    assert_eq!(arbitrate(&mut CommandFusion, &only_zero).action.motion.velocity, Some(0.0));
}

// --- The safety rules, applied by the composite around every arbiter. ---

#[test]
fn a_stop_from_any_voter_wins_every_arbiter() {
    let specs = [
        ArbiterSpec::HighestPriority,
        ArbiterSpec::SimplePriority,
        ArbiterSpec::HighestActivation,
        ArbiterSpec::MonteCarlo { hold_ticks: 3 },
        ArbiterSpec::ActivationFusion,
        ArbiterSpec::PriorityFusion,
        ArbiterSpec::UtilityFusion,
        ArbiterSpec::CommandFusion,
        ArbiterSpec::Conditional { when: Condition::Always },
        ArbiterSpec::PriorityResolver { priorities: vec![5, 1] },
    ];
    for spec in specs {
        let mut tree = Composite::with_arbiter("root", spec.build(ChaCha8Rng::seed_from_u64(0)))
            .child(fixed("go", Action::with_vote(1.0).velocity(1.0).max_velocity(0.8)), 10.0)
            .child(fixed("halt", Action::stop(0.1).max_velocity(0.3)), 1.0);
        let action = tree.gen_action(&State::default());
        assert!(action.stop, "{spec:?}");
        assert_eq!(action.motion.max_velocity, Some(0.3), "{spec:?}");
        assert_eq!(tree.last_winner(), Some(1), "{spec:?}");
    }
}

#[test]
fn the_vote_override_bids_only_when_there_is_an_opinion() {
    let mut loud =
        Composite::new("loud", HighestPriority).child(fixed("a", Action::with_vote(0.1).velocity(1.0)), 1.0).vote(0.9);
    assert_eq!(loud.gen_action(&State::default()).vote, 0.9);
    let mut silent = Composite::new("silent", HighestPriority).child(fixed("a", Action::none()), 1.0).vote(0.9);
    assert!(!silent.gen_action(&State::default()).is_voting());
    let mut empty = Composite::new("empty", CommandFusion).vote(0.9);
    assert!(!empty.gen_action(&State::default()).is_voting());
}
