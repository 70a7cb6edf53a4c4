//! Properties every arbiter must keep, over random inputs.

use proptest::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;
use ubf_core::arbiter::{ArbiterSpec, CommandFusion};
use ubf_core::{angle_difference, from_fn, wrap_angle, Action, Behavior, Channel, Composite, Condition, State};

#[derive(Clone, Debug)]
struct Child {
    weight: f64,
    vote: f64,
    velocity: Option<f64>,
    heading: Option<f64>,
    max_velocity: Option<f64>,
    stop: bool,
}

fn child() -> impl Strategy<Value = Child> {
    (
        0.0..10.0f64,
        prop_oneof![Just(0.0), 0.01..2.0f64],
        proptest::option::of(-2.0..2.0f64),
        proptest::option::of(-PI..PI),
        proptest::option::of(0.0..3.0f64),
        proptest::bool::weighted(0.1),
    )
        .prop_map(|(weight, vote, velocity, heading, max_velocity, stop)| Child {
            weight,
            vote,
            velocity,
            heading,
            max_velocity,
            stop,
        })
}

fn action_of(c: &Child) -> Action {
    let mut a = Action::with_vote(c.vote);
    a.motion.velocity = c.velocity;
    a.motion.heading = c.heading;
    a.motion.max_velocity = c.max_velocity;
    a.stop = c.stop;
    a
}

fn all_arbiters(n: usize) -> Vec<ArbiterSpec> {
    let mut specs = vec![
        ArbiterSpec::HighestPriority,
        ArbiterSpec::SimplePriority,
        ArbiterSpec::HighestActivation,
        ArbiterSpec::MonteCarlo { hold_ticks: 4 },
        ArbiterSpec::ActivationFusion,
        ArbiterSpec::PriorityFusion,
        ArbiterSpec::UtilityFusion,
        ArbiterSpec::CommandFusion,
        ArbiterSpec::PriorityResolver { priorities: (0..n as i32).map(|i| i % 3).collect() },
    ];
    if n == 2 {
        specs.push(ArbiterSpec::Conditional { when: Condition::Always });
    }
    specs
}

fn tree(spec: &ArbiterSpec, children: &[Child], weight_scale: f64) -> Composite {
    let mut tree = Composite::with_arbiter("root", spec.build(ChaCha8Rng::seed_from_u64(11)));
    for (i, c) in children.iter().enumerate() {
        let action = action_of(c);
        tree = tree.child(from_fn(format!("c{i}"), move |_: &State| action), c.weight * weight_scale);
    }
    tree
}

/// Whether `x` lies on the shorter arc spanned by `values` (all within a
/// half circle of their first element, which the generator does not
/// guarantee, so the caller checks that first).
fn within_arc(x: f64, values: &[f64]) -> bool {
    let offsets: Vec<f64> = values.iter().map(|v| angle_difference(*v, values[0])).collect();
    let lo = offsets.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = offsets.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let dx = angle_difference(x, values[0]);
    dx >= lo - 1e-9 && dx <= hi + 1e-9
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn a_fused_channel_lies_within_its_inputs(children in proptest::collection::vec(child(), 1..7)) {
        for spec in all_arbiters(children.len()) {
            let mut t = tree(&spec, &children, 1.0);
            let action = t.gen_action(&State::default());
            let voters: Vec<&Child> = children.iter().filter(|c| c.vote > 0.0).collect();
            if let Some(v) = action.motion.get(Channel::Velocity) {
                let inputs: Vec<f64> = voters.iter().filter_map(|c| c.velocity).collect();
                let lo = inputs.iter().cloned().fold(f64::INFINITY, f64::min);
                let hi = inputs.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                prop_assert!(v >= lo - 1e-9 && v <= hi + 1e-9, "{spec:?}: {v} outside [{lo}, {hi}]");
            }
            if let Some(h) = action.motion.heading {
                let inputs: Vec<f64> = voters.iter().filter_map(|c| c.heading).collect();
                prop_assert!(!inputs.is_empty());
                let spread_ok = inputs.iter().all(|x| angle_difference(*x, inputs[0]).abs() < PI / 2.0);
                if spread_ok {
                    prop_assert!(within_arc(h, &inputs), "{spec:?}: {h} outside {inputs:?}");
                }
            }
        }
    }

    #[test]
    fn results_do_not_change_when_every_weight_is_scaled(
        children in proptest::collection::vec(child(), 1..7),
        scale in 0.01..100.0f64,
    ) {
        for spec in all_arbiters(children.len()) {
            let a = tree(&spec, &children, 1.0).gen_action(&State::default());
            let b = tree(&spec, &children, scale).gen_action(&State::default());
            for channel in Channel::ALL {
                match (a.motion.get(channel), b.motion.get(channel)) {
                    (Some(x), Some(y)) => prop_assert!((x - y).abs() < 1e-9, "{spec:?} {channel:?}: {x} vs {y}"),
                    (x, y) => prop_assert_eq!(x, y),
                }
            }
            prop_assert!((a.vote - b.vote).abs() < 1e-9);
        }
    }

    #[test]
    fn limits_take_the_minimum_and_stop_wins(children in proptest::collection::vec(child(), 1..7)) {
        for spec in all_arbiters(children.len()) {
            let action = tree(&spec, &children, 1.0).gen_action(&State::default());
            let voters = children.iter().filter(|c| c.vote > 0.0);
            let expected = voters.clone().filter_map(|c| c.max_velocity).fold(None, |m: Option<f64>, l| Some(m.map_or(l, |m| m.min(l))));
            prop_assert_eq!(action.motion.max_velocity, expected, "{:?}", spec);
            if voters.clone().any(|c| c.stop) {
                prop_assert!(action.stop, "{:?}", spec);
                prop_assert!(action.is_voting());
            }
        }
    }

    #[test]
    fn the_circular_mean_is_right_across_plus_minus_pi(center in -PI..PI, spread in 0.0..1.0f64, w in 0.1..10.0f64) {
        // Two headings symmetric about `center` with equal utility average to
        // `center`, wherever `center` lies (including across ±π).
        let a = Action::with_vote(1.0).heading(wrap_angle(center - spread));
        let b = Action::with_vote(1.0).heading(wrap_angle(center + spread));
        let mut t = Composite::new("root", CommandFusion)
            .child(from_fn("a", move |_: &State| a), w)
            .child(from_fn("b", move |_: &State| b), w);
        let h = t.gen_action(&State::default()).motion.heading.unwrap();
        prop_assert!(angle_difference(h, center).abs() < 1e-9, "{h} vs {center}");
    }
}
