//! A budget on the log lines the live view's clients can cause. The
//! Foxglove server library logs an ERROR line for every malformed message a
//! client sends, and anyone who can reach the view's port is a client: one
//! of them wrote 12 MB of stderr a second, enough to fill a journal or a
//! redirected log, and to bury what the robot said.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::LazyLock;
use std::time::Instant;

/// The most lines a second the live view's library may log.
const MOST_LINES_PER_S: u64 = 10;

/// How often [`admit`] must be asked about events from `target`: line by
/// line for the live view's library, never for the rest.
pub(super) fn interest(target: &str) -> tracing::subscriber::Interest {
    match is_viewers(target) {
        true => tracing::subscriber::Interest::sometimes(),
        false => tracing::subscriber::Interest::always(),
    }
}

fn is_viewers(target: &str) -> bool {
    target.starts_with("foxglove")
}

/// Whether an event from `target` may be logged now: any event not from
/// the live view's library, and that library's first
/// [`MOST_LINES_PER_S`] each second.
pub(super) fn admit(target: &str) -> bool {
    static START: LazyLock<Instant> = LazyLock::new(Instant::now);
    static BUDGET: Budget = Budget::new();
    !is_viewers(target) || BUDGET.admit(START.elapsed().as_secs())
}

/// Lines counted in the second they were asked for; one word holds both,
/// so that the count and its second change together.
struct Budget(AtomicU64);

impl Budget {
    const fn new() -> Self {
        Budget(AtomicU64::new(0))
    }

    /// Whether one more line fits in second `second`.
    fn admit(&self, second: u64) -> bool {
        let mut admitted = false;
        let _ = self.0.fetch_update(Ordering::Relaxed, Ordering::Relaxed, |word| {
            let (at, count) = (word >> 32, word & 0xffff_ffff);
            let count = if at == second & 0xffff_ffff { count } else { 0 };
            admitted = count < MOST_LINES_PER_S;
            Some((second & 0xffff_ffff) << 32 | (count + 1).min(0xffff_ffff))
        });
        admitted
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_second_admits_its_budget_and_no_more() {
        let budget = Budget::new();
        let admitted = |second| (0..100).filter(|_| budget.admit(second)).count() as u64;
        assert_eq!(admitted(5), MOST_LINES_PER_S);
        assert_eq!(admitted(5), 0);
        assert_eq!(admitted(6), MOST_LINES_PER_S);
    }

    #[test]
    fn the_rest_of_the_log_is_never_held_back() {
        for _ in 0..1000 {
            assert!(admit("ubf_session::drive"));
        }
    }
}
