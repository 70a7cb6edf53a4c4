//! A sweep's warnings, each said once. The runs of a sweep share their
//! scenario, so a warning one run gives (an aid with no camera to aid
//! with, a writer that fell behind) the others give too: two thousand
//! seeds wrote it two thousand times, burying whatever else was said.
//! While a sweep runs, a warning already said (the same words from the
//! same place in the code) is held back and counted, and the sweep says
//! how many at its end.

use std::collections::HashSet;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};
use tracing::callsite::Identifier;
use tracing::field::{Field, Visit};
use tracing::{Event, Level, Metadata};
use tracing_subscriber::layer::{Context, Filter};

/// Whether warnings are being said once (a sweep is running).
static ONCE: AtomicBool = AtomicBool::new(false);

/// The warnings said while [`ONCE`] held: where from, and their words.
static SAID: Mutex<Option<HashSet<(Identifier, String)>>> = Mutex::new(None);

/// Warnings held back.
static HELD_BACK: AtomicU64 = AtomicU64::new(0);

/// The most different warnings remembered; beyond them a new one is held
/// back too, so that a warning whose words change every run (a time in
/// it) cannot fill the memory.
const MOST_REMEMBERED: usize = 10_000;

/// The log filter that holds repeated warnings back while [`say_once`]
/// is in force; it lets everything through otherwise.
pub(super) struct RepeatedWarnings;

impl<S> Filter<S> for RepeatedWarnings {
    fn enabled(&self, _: &Metadata<'_>, _: &Context<'_, S>) -> bool {
        true
    }

    /// Event by event for warnings, never for the rest.
    fn callsite_enabled(&self, metadata: &'static Metadata<'static>) -> tracing::subscriber::Interest {
        match is_warning(metadata) {
            true => tracing::subscriber::Interest::sometimes(),
            false => tracing::subscriber::Interest::always(),
        }
    }

    fn event_enabled(&self, event: &Event<'_>, _: &Context<'_, S>) -> bool {
        admit(event)
    }
}

fn is_warning(metadata: &Metadata<'_>) -> bool {
    metadata.is_event() && *metadata.level() == Level::WARN
}

/// Holds repeated warnings back until dropped, then says how many were.
pub(super) struct SayingOnce(());

impl Drop for SayingOnce {
    fn drop(&mut self) {
        ONCE.store(false, Ordering::SeqCst);
        *SAID.lock().unwrap_or_else(PoisonError::into_inner) = None;
        let held_back = HELD_BACK.swap(0, Ordering::SeqCst);
        if held_back > 0 {
            let plural = if held_back == 1 { "" } else { "s" };
            eprintln!("held back {held_back} warning{plural} said already: many runs say each warning once");
        }
    }
}

/// From now until the guard is dropped, a warning already said is held
/// back and counted (if the log has [`RepeatedWarnings`]).
pub(super) fn say_once() -> SayingOnce {
    ONCE.store(true, Ordering::SeqCst);
    SayingOnce(())
}

/// Whether `event` may be logged now: anything but a warning, any warning
/// outside a sweep, and a sweep's warnings the first time they are said.
fn admit(event: &Event<'_>) -> bool {
    let metadata = event.metadata();
    if !is_warning(metadata) || !ONCE.load(Ordering::SeqCst) {
        return true;
    }
    // Lines from the `log` crate share one call site: their words and
    // target tell them apart.
    let mut words = Words(String::new());
    event.record(&mut words);
    let key = (metadata.callsite(), words.0);
    let mut said = SAID.lock().unwrap_or_else(PoisonError::into_inner);
    let said = said.get_or_insert_with(HashSet::new);
    let new = said.len() < MOST_REMEMBERED && said.insert(key);
    if !new {
        HELD_BACK.fetch_add(1, Ordering::SeqCst);
    }
    new
}

/// An event's fields, written out: its words, and for a line from the
/// `log` crate (whose call site is one for all of them) its target, file
/// and line too.
struct Words(String);

impl Visit for Words {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        use std::fmt::Write;
        let _ = write!(self.0, "{}={value:?} ", field.name());
    }
}

#[cfg(test)]
mod tests {
    use super::super::network_log::tests::lines_logged;
    use super::*;

    #[test]
    fn in_a_sweep_each_warning_is_said_once_and_its_repeats_are_counted() {
        let warn_in_runs = |runs: u64| {
            for run in 0..runs {
                tracing::warn!("the aid has no camera");
                tracing::warn!("the writer fell behind in run {}", run % 2);
                tracing::error!("an error is always said");
            }
        };
        let text = lines_logged(RepeatedWarnings, || {
            // Before a sweep, every warning.
            warn_in_runs(2);
            let sweep = say_once();
            warn_in_runs(5);
            assert_eq!(HELD_BACK.load(Ordering::SeqCst), 4 + 3);
            drop(sweep);
            // After it, every warning again.
            warn_in_runs(1);
        });
        let count = |what: &str| text.lines().filter(|l| l.contains(what)).count();
        assert_eq!(count("the aid has no camera"), 2 + 1 + 1, "{text}");
        // Words that differ are said, each once.
        assert_eq!(count("the writer fell behind in run 0"), 1 + 1 + 1, "{text}");
        assert_eq!(count("the writer fell behind in run 1"), 1 + 1, "{text}");
        assert_eq!(count("an error is always said"), 2 + 5 + 1, "{text}");
        assert_eq!(HELD_BACK.load(Ordering::SeqCst), 0, "the guard said the count and cleared it");
    }
}
