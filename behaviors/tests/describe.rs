//! Each stock behaviour's description says what its config really is:
//! every field it reads, no other, and the defaults it really has.

use serde::de::DeserializeOwned;
use std::fmt::Debug;
use ubf_behaviors::{ActionAidingConfig, AvoidCollisionConfig, GoToConfig, InjectFaultConfig, StopConfig};
use ubf_core::config::{from_ron, Checked};
use ubf_core::Describe;

/// Checks `C`'s description against `C` itself; `required` holds a value
/// for each required field (RON, without the parentheses).
fn check<C: DeserializeOwned + Describe + PartialEq + Debug>(required: &str) {
    let fields = C::fields();
    let with = |extra: &str| {
        let body = [required, extra].iter().filter(|s| !s.is_empty()).copied().collect::<Vec<_>>().join(", ");
        from_ron::<C>(&format!("({body})"))
    };
    let base = with("").unwrap_or_else(|e| panic!("{required}: {e}"));
    for f in fields.iter().filter(|f| !f.required()) {
        // Written out, the described default reads back as the default.
        let written = with(&format!("{}: {}", f.name, f.default))
            .unwrap_or_else(|e| panic!("{}: default `{}` does not read: {e}", f.name, f.default));
        assert_eq!(written, base, "{}: the described default `{}` is not the default", f.name, f.default);
    }
    // The fields the config accepts are the fields described: serde names
    // them when it meets one it does not know.
    let refused = with("no_such_field: 1").unwrap_err().message;
    // "… in `Config`, expected one of `a`, `b`, or `c` instead" (or
    // "expected either `a` or `b`", or "expected `a`").
    let expected = refused.split_once(", expected").map_or("", |(_, list)| list);
    let listed: Vec<&str> = expected.split('`').skip(1).step_by(2).collect();
    let described: Vec<&str> = fields.iter().map(|f| f.name).collect();
    let (mut a, mut b) = (listed.clone(), described.clone());
    a.sort_unstable();
    b.sort_unstable();
    assert_eq!(a, b, "fields read ({refused}) against fields described");
}

#[test]
fn descriptions_match_the_configs() {
    check::<GoToConfig>("");
    check::<StopConfig>("");
    check::<Checked<AvoidCollisionConfig>>("");
    check::<InjectFaultConfig>("after_s: 1.0");
    check::<ActionAidingConfig>("technique: None");
}
