//! A sweep's warnings, each said once. The runs of a sweep share their
//! scenario, so a warning one run gives (an aid with no camera to aid
//! with, a writer that fell behind) the others give too: two thousand
//! seeds wrote it two thousand times, burying whatever else was said.
//! While a sweep runs, a warning from a place in the code already heard
//! from is held back and counted, and the sweep says how many at its end.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, PoisonError};
use tracing::callsite::Identifier;
use tracing::{Level, Metadata};

/// Whether warnings are being said once (a sweep is running).
static ONCE: AtomicBool = AtomicBool::new(false);

/// How often each place has warned while [`ONCE`] held.
static HEARD: Mutex<Option<HashMap<Identifier, u64>>> = Mutex::new(None);

/// From now on, each place's first warning only is let through.
pub(super) fn say_once() {
    ONCE.store(true, Ordering::SeqCst);
}

/// How often [`admit`] must be asked about events from `metadata`'s call
/// site: event by event for warnings, never for the rest.
pub(super) fn interest(metadata: &Metadata<'_>) -> tracing::subscriber::Interest {
    match is_warning(metadata) {
        true => tracing::subscriber::Interest::sometimes(),
        false => tracing::subscriber::Interest::always(),
    }
}

fn is_warning(metadata: &Metadata<'_>) -> bool {
    metadata.is_event() && *metadata.level() == Level::WARN
}

/// Whether an event may be logged now: anything but a warning, any
/// warning outside a sweep, and a sweep's first warning from each place.
pub(super) fn admit(metadata: &Metadata<'_>) -> bool {
    if !is_warning(metadata) || !ONCE.load(Ordering::SeqCst) {
        return true;
    }
    let mut heard = HEARD.lock().unwrap_or_else(PoisonError::into_inner);
    let count = heard.get_or_insert_with(HashMap::new).entry(metadata.callsite()).or_insert(0);
    *count += 1;
    *count == 1
}

/// Says how many warnings were held back as repeats, if any were.
pub(super) fn say_held_back() {
    let (repeats, places) = held_back();
    let plural = |n: u64, noun: &str| format!("{n} {noun}{}", if n == 1 { "" } else { "s" });
    if repeats > 0 {
        eprintln!(
            "held back {} of {} above: many runs say each warning once",
            plural(repeats, "repeat"),
            plural(places as u64, "warning")
        );
    }
}

/// How many warnings were held back as repeats, and from how many places.
fn held_back() -> (u64, usize) {
    let heard = HEARD.lock().unwrap_or_else(PoisonError::into_inner);
    let repeated = heard.iter().flat_map(HashMap::values).filter(|&&n| n > 1);
    repeated.fold((0, 0), |(repeats, places), n| (repeats + n - 1, places + 1))
}

#[cfg(test)]
mod tests {
    use super::super::viewer_log::tests::Sink;
    use super::*;

    #[test]
    fn in_a_sweep_each_place_warns_once_and_its_repeats_are_counted() {
        let said = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let sink = std::sync::Arc::clone(&said);
        use tracing_subscriber::layer::SubscriberExt;
        use tracing_subscriber::Layer;
        let once =
            tracing_subscriber::filter::DynFilterFn::new(|metadata, _| admit(metadata)).with_callsite_filter(interest);
        let layer = tracing_subscriber::fmt::layer()
            .with_writer(move || Sink(std::sync::Arc::clone(&sink)))
            .with_ansi(false)
            .without_time()
            .with_filter(once);
        let warn_in_runs = |runs: u64| {
            for run in 0..runs {
                tracing::warn!("the aid has no camera (run {run})");
                tracing::warn!("another place");
                tracing::error!("an error is always said");
            }
        };
        tracing::subscriber::with_default(tracing_subscriber::registry().with(layer), || {
            // Before a sweep, every warning.
            warn_in_runs(2);
            say_once();
            warn_in_runs(5);
        });
        let text = String::from_utf8(said.lock().unwrap().clone()).unwrap();
        let count = |what: &str| text.lines().filter(|l| l.contains(what)).count();
        assert_eq!(count("the aid has no camera"), 3, "{text}");
        assert_eq!(count("another place"), 3, "{text}");
        assert_eq!(count("an error is always said"), 7, "{text}");
        assert!(text.contains("the aid has no camera (run 0)"), "the first run's is the one said: {text}");
        assert_eq!(held_back(), (8, 2));
    }
}
