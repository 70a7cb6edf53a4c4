//! Behaviour trees from RON: building, naming, seeding and every kind of bad
//! input with its position.

use rand::Rng;
use serde::Deserialize;
use ubf_core::config::positive;
use ubf_core::{Action, Behavior, BehaviorSpec, BuildContext, Describe, Field, Registry, State};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CruiseConfig {
    #[serde(deserialize_with = "positive")]
    speed: f64,
}

impl Describe for CruiseConfig {
    fn fields() -> Vec<Field> {
        vec![Field::new("speed", "number", "m/s", "required", "> 0", "forward speed")]
    }
}

struct Cruise(f64);

impl Behavior for Cruise {
    fn gen_action(&mut self, _: &State) -> Action {
        Action::with_vote(1.0).velocity(self.0)
    }
}

fn registry() -> Registry {
    let mut r = Registry::new();
    r.register("Cruise", |c: &CruiseConfig, _: &BuildContext| Cruise(c.speed));
    r
}

fn error_of(text: &str) -> (usize, usize, String) {
    let e = registry().from_ron::<BehaviorSpec>(text).unwrap_err();
    (e.line, e.column, e.message)
}

#[test]
fn builds_a_nested_tree_with_unique_names() {
    let spec: BehaviorSpec = registry()
        .from_ron(
            "Composite(name: \"top\", arbiter: CommandFusion, children: [
                (behavior: Cruise(speed: 1.0)),
                (behavior: Cruise(speed: 3.0), weight: 3.0),
                (behavior: Composite(arbiter: MonteCarlo(), vote: 0.5, children: [(behavior: Cruise(speed: 2.0))]), name: \"inner\"),
            ])",
        )
        .unwrap();
    assert_eq!(spec.kind(), "Composite");
    let mut tree = spec.build(&BuildContext::new(1));
    let names: Vec<&str> = tree.as_composite().unwrap().children().map(|(n, _)| n).collect();
    assert_eq!(names, ["Cruise", "Cruise_2", "inner"]);
    // (1·1 + 3·3 + 1·2) / 5 with all votes 1 and weights 1, 3, 1 (the inner
    // composite's vote override 0.5 halves its utility): (1 + 9 + 0.5·2) / 4.5.
    let v = tree.gen_action(&State::default()).motion.velocity.unwrap();
    assert!((v - 11.0 / 4.5).abs() < 1e-12, "{v}");
}

#[test]
fn each_node_gets_its_own_repeatable_random_stream() {
    let ctx = BuildContext::new(42);
    let a: u64 = ctx.child("a").rng().random();
    let b: u64 = ctx.child("b").rng().random();
    assert_ne!(a, b);
    assert_eq!(a, BuildContext::new(42).child("a").rng().random::<u64>());
    assert_ne!(a, BuildContext::new(43).child("a").rng().random::<u64>());
}

#[test]
fn a_later_registration_replaces_an_earlier_one() {
    let mut r = registry();
    r.register("Cruise", |_: &CruiseConfig, _: &BuildContext| Cruise(9.0));
    let spec: BehaviorSpec = r.from_ron("Cruise(speed: 1.0)").unwrap();
    assert_eq!(spec.build(&BuildContext::new(0)).gen_action(&State::default()).motion.velocity, Some(9.0));
}

#[test]
fn unknown_behaviour_names_the_known_ones() {
    let (line, col, msg) =
        error_of("Composite(arbiter: CommandFusion, children: [\n  (behavior: Crusie(speed: 1.0))])");
    assert_eq!(line, 2);
    assert!(col > 1);
    assert!(msg.contains("unknown behaviour `Crusie`") && msg.contains("Composite, Cruise"), "{msg}");
}

#[test]
fn unknown_field_is_reported_where_it_stands() {
    let (line, col, msg) = error_of("Composite(arbiter: CommandFusion, children: [\n  (behavior: Cruise(sped: 1.0))])");
    assert_eq!((line, col), (2, 21));
    assert!(msg.contains("sped") && msg.contains("speed"), "{msg}");
}

#[test]
fn nan_and_negative_numbers_are_refused() {
    let (_, _, msg) = error_of("Cruise(speed: NaN)");
    assert!(msg.contains("NaN is out of range: must be > 0"), "{msg}");
    let (_, _, msg) =
        error_of("Composite(arbiter: CommandFusion, children: [(behavior: Cruise(speed: 1.0), weight: -2.0)])");
    assert!(msg.contains("-2 is out of range"), "{msg}");
    let (_, _, msg) = error_of("Composite(arbiter: CommandFusion, vote: -1.0, children: [])");
    assert!(msg.contains("-1 is out of range"), "{msg}");
    let (_, _, msg) = error_of("Composite(arbiter: Conditional(when: ObstacleWithin(range: -0.5)), children: [])");
    assert!(msg.contains("finite and ≥ 0"), "{msg}");
}

#[test]
fn arbiters_that_need_a_shape_check_it() {
    let (_, _, msg) =
        error_of("Composite(arbiter: Conditional(when: Bumped), children: [(behavior: Cruise(speed: 1.0))])");
    assert!(msg.contains("exactly 2 children"), "{msg}");
    let (_, _, msg) = error_of(
        "Composite(arbiter: PriorityResolver(priorities: [1, 2]), children: [(behavior: Cruise(speed: 1.0))])",
    );
    assert!(msg.contains("2 priorities for 1 children"), "{msg}");
    let (_, _, msg) = error_of("Composite(arbiter: MonteCarlo(hold_ticks: 0), children: [])");
    assert!(msg.contains("at least 1"), "{msg}");
}

#[test]
fn malformed_text_is_reported_not_panicked_on() {
    for text in [
        "",
        "Composite(",
        "Cruise(speed: 1.0",
        "[[[[",
        "Cruise(speed: 1.0) trailing",
        "Composite(arbiter: Nope, children: [])",
    ] {
        assert!(registry().from_ron::<BehaviorSpec>(text).is_err(), "{text:?}");
    }
}

#[test]
fn specs_outside_a_registry_are_an_error_not_a_panic() {
    let e = ubf_core::config::from_ron::<BehaviorSpec>("Cruise(speed: 1.0)").unwrap_err();
    assert!(e.message.contains("Registry::from_ron"), "{}", e.message);
}

#[test]
fn ten_thousand_children_load_with_unique_names_including_taken_suffixes() {
    // Naming was cubic in the children once: 3 000 took 23 s to load.
    let mut children = vec!["(behavior: Cruise(speed: 1.0))".to_owned(); 10_000];
    children[1] = "(behavior: Cruise(speed: 1.0), name: \"Cruise_3\")".to_owned();
    let text = format!("Composite(arbiter: CommandFusion, children: [{}])", children.join(", "));
    let spec: BehaviorSpec = registry().from_ron(&text).unwrap();
    let tree = spec.build(&BuildContext::new(0));
    let names: Vec<&str> = tree.as_composite().unwrap().children().map(|(n, _)| n).collect();
    assert_eq!(&names[..4], ["Cruise", "Cruise_3", "Cruise_2", "Cruise_4"]);
    let unique: std::collections::HashSet<&&str> = names.iter().collect();
    assert_eq!(unique.len(), 10_000);
}

#[test]
fn an_optional_setting_in_double_parentheses_gets_a_hint() {
    // The dialect unwraps newtype variants, so `Some((..))` is not read;
    // the error says how to write it instead.
    #[derive(Debug, Deserialize)]
    #[allow(dead_code)]
    struct Inner {
        a: f64,
    }
    #[derive(Debug, Deserialize)]
    #[allow(dead_code)]
    struct Outer {
        inner: Option<Inner>,
    }
    let error = ubf_core::config::from_ron::<Outer>("(inner: Some((a: 1.0)))").unwrap_err();
    assert!(error.message.contains("`Some(field: ..)`"), "{error}");
    assert_eq!((error.line, error.column), (1, 14));
    let read = ubf_core::config::from_ron::<Outer>("(inner: Some(a: 1.0))").unwrap();
    assert!(read.inner.is_some());
    // Errors elsewhere carry no hint.
    let other = ubf_core::config::from_ron::<Outer>("(inner: (b: 1.0))").unwrap_err();
    assert!(!other.message.contains("Some(field"), "{other}");
}
