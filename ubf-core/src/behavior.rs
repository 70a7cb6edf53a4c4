//! The behaviour trait: state in, action out.

use crate::{Action, Composite, State};

/// A robot behaviour: looks at the state, says what it wants and how much.
///
/// Only [`Behavior::gen_action`] is required. It must not block (it runs
/// inside the control tick) and returns [`Action::none`] when it has nothing
/// to say.
pub trait Behavior: Send {
    /// The action this behaviour wants for this tick.
    fn gen_action(&mut self, state: &State) -> Action;

    /// A short name for logs and records; defaults to the type's name.
    fn name(&self) -> &str {
        short_type_name(std::any::type_name::<Self>())
    }

    /// Forgets everything learnt so far, as if newly built.
    fn reset(&mut self) {}

    /// The composite behind this behaviour, if it is one. The controller uses
    /// it to record every node of the tree; leaf behaviours keep the default.
    fn as_composite(&self) -> Option<&Composite> {
        None
    }
}

impl<B: Behavior + ?Sized> Behavior for Box<B> {
    fn gen_action(&mut self, state: &State) -> Action {
        (**self).gen_action(state)
    }
    fn name(&self) -> &str {
        (**self).name()
    }
    fn reset(&mut self) {
        (**self).reset()
    }
    fn as_composite(&self) -> Option<&Composite> {
        (**self).as_composite()
    }
}

/// A behaviour panicked: where in the tree, and what it said. Composites
/// catch a child's panic, silence that child for the rest of the run and
/// pass this up with the child's name prefixed, so the controller learns the
/// full path (`root/avoid/sonar`) and can stop the robot.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("behaviour {path} panicked: {message}")]
pub struct BehaviorPanic {
    /// Slash-separated names from the root, as in a tree layout.
    pub path: String,
    /// The panic's message.
    pub message: String,
}

impl BehaviorPanic {
    /// The panic that unwound out of the behaviour named `name`, with its
    /// path extended by that name.
    pub fn caught(name: &str, payload: Box<dyn std::any::Any + Send>) -> BehaviorPanic {
        match payload.downcast::<BehaviorPanic>() {
            Ok(inner) => BehaviorPanic { path: format!("{name}/{}", inner.path), message: inner.message },
            Err(payload) => BehaviorPanic { path: name.to_owned(), message: panic_message(payload.as_ref()) },
        }
    }
}

thread_local! {
    /// How many [`catch_reported`] calls this thread is inside.
    static CATCHING: std::cell::Cell<u32> = const { std::cell::Cell::new(0) };
}

/// Runs `f`, catching a panic that the caller reports in its own words (a
/// behaviour's, named by its path; a session's, with the robot stopped).
/// While `f` runs, [`panic_is_reported`] says so, so that a panic hook can
/// leave the telling to the caller.
pub fn catch_reported<T>(f: impl FnOnce() -> T) -> std::thread::Result<T> {
    CATCHING.with(|c| c.set(c.get() + 1));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    CATCHING.with(|c| c.set(c.get() - 1));
    result
}

/// Whether a panic on this thread now would be caught and reported by a
/// [`catch_reported`] around it.
pub fn panic_is_reported() -> bool {
    CATCHING.with(|c| c.get() > 0)
}

/// What a panic said: its `&str` or `String` payload.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(no message)".into())
}

/// `a::b::Wander<c::D>` → `Wander<c::D>`: the path adds noise to records.
fn short_type_name(full: &str) -> &str {
    let generic_start = full.find('<').unwrap_or(full.len());
    let start = full[..generic_start].rfind("::").map_or(0, |i| i + 2);
    &full[start..]
}

/// A behaviour made from a closure, for tests, benchmarks and one-liners.
///
/// ```
/// use ubf_core::{from_fn, Action, Behavior, State};
/// let mut creep = from_fn("creep", |_state: &State| Action::with_vote(1.0).velocity(0.1));
/// assert_eq!(creep.gen_action(&State::default()).motion.velocity, Some(0.1));
/// assert_eq!(creep.name(), "creep");
/// ```
pub fn from_fn<F>(name: impl Into<String>, f: F) -> FnBehavior<F>
where
    F: FnMut(&State) -> Action + Send,
{
    FnBehavior { name: name.into(), f }
}

/// See [`from_fn`].
pub struct FnBehavior<F> {
    name: String,
    f: F,
}

impl<F> Behavior for FnBehavior<F>
where
    F: FnMut(&State) -> Action + Send,
{
    fn gen_action(&mut self, state: &State) -> Action {
        (self.f)(state)
    }
    fn name(&self) -> &str {
        &self.name
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Plain;
    impl Behavior for Plain {
        fn gen_action(&mut self, _: &State) -> Action {
            Action::none()
        }
    }

    #[test]
    fn default_name_is_the_short_type_name() {
        assert_eq!(Plain.name(), "Plain");
        assert_eq!(short_type_name("a::b::W<c::D>"), "W<c::D>");
        assert_eq!(short_type_name("W"), "W");
    }
}
