//! A budget on the log lines that others on the network can cause, each
//! kept to one line. The Foxglove server library logs an ERROR line for
//! every malformed message a live view's client sends, and the DDS library
//! one for many a malformed or outsized message a peer on the domain
//! sends; anyone who can reach the port or the domain can send them. One
//! live-view client wrote 12 MB of stderr a second, enough to fill a
//! journal or a redirected log and to bury what the robot said; a DDS
//! peer's 64 MB messages, 10 kB a second.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::LazyLock;
use std::time::Instant;

/// The most lines a second those libraries may log, together.
const MOST_LINES_PER_S: u64 = 10;

/// How often [`admit`] must be asked about events from `target`: line by
/// line for those libraries, never for the rest.
pub(super) fn interest(target: &str) -> tracing::subscriber::Interest {
    match is_from_network(target) {
        true => tracing::subscriber::Interest::sometimes(),
        false => tracing::subscriber::Interest::always(),
    }
}

/// Whether `target` is a library that logs what others on the network
/// send it: the live view's server or the DDS library.
fn is_from_network(target: &str) -> bool {
    target.starts_with("foxglove") || target.starts_with("rustdds")
}

/// Whether an event from `target` may be logged now: any event not from
/// those libraries, and their first [`MOST_LINES_PER_S`] each second.
pub(super) fn admit(target: &str) -> bool {
    static START: LazyLock<Instant> = LazyLock::new(Instant::now);
    static BUDGET: Budget = Budget::new();
    !is_from_network(target) || BUDGET.admit(START.elapsed().as_secs())
}

/// A line format that keeps each of those libraries' lines one line:
/// their messages quote what a client or peer sent, and a newline in that
/// would start a line of its own making (`… ERROR ubf: the robot has
/// reached its goal`). Every other line is formatted by `F` as it is.
pub(super) struct OneLineFromNetwork<F>(pub(super) F);

impl<S, N, F> tracing_subscriber::fmt::FormatEvent<S, N> for OneLineFromNetwork<F>
where
    S: tracing::Subscriber + for<'a> tracing_subscriber::registry::LookupSpan<'a>,
    N: for<'a> tracing_subscriber::fmt::FormatFields<'a> + 'static,
    F: tracing_subscriber::fmt::FormatEvent<S, N>,
{
    fn format_event(
        &self,
        context: &tracing_subscriber::fmt::FmtContext<'_, S, N>,
        mut writer: tracing_subscriber::fmt::format::Writer<'_>,
        event: &tracing::Event<'_>,
    ) -> std::fmt::Result {
        if !is_from_network(event.metadata().target()) {
            return self.0.format_event(context, writer, event);
        }
        let mut line = String::new();
        self.0.format_event(context, tracing_subscriber::fmt::format::Writer::new(&mut line), event)?;
        writeln!(writer, "{}", line.trim_end_matches('\n').replace('\n', "\\n"))
    }
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
pub(super) mod tests {
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
    fn a_newline_a_client_sent_does_not_start_a_line() {
        let written = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let sink = std::sync::Arc::clone(&written);
        let subscriber = tracing_subscriber::fmt()
            .with_writer(move || Sink(std::sync::Arc::clone(&sink)))
            .with_ansi(false)
            .event_format(OneLineFromNetwork(tracing_subscriber::fmt::format()))
            .finish();
        tracing::subscriber::with_default(subscriber, || {
            tracing::error!(target: "foxglove::websocket", "Invalid message: `x\nERROR ubf: forged`");
            tracing::warn!(target: "ubf", "ours\nspans two lines");
        });
        let text = String::from_utf8(written.lock().unwrap().clone()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3, "{text}");
        assert!(lines[0].ends_with("Invalid message: `x\\nERROR ubf: forged`"), "{text}");
        assert_eq!(lines[2], "spans two lines");
    }

    /// A writer into a shared buffer.
    pub(in crate::cli) struct Sink(pub(in crate::cli) std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

    impl std::io::Write for Sink {
        fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(bytes);
            Ok(bytes.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn the_live_view_s_and_the_dds_library_s_lines_are_budgeted() {
        assert!(is_from_network("foxglove::websocket::server"));
        assert!(is_from_network("rustdds::structure::sequence_number"));
        assert!(!is_from_network("ubf_robots::ros2::node"));
    }

    #[test]
    fn the_rest_of_the_log_is_never_held_back() {
        for _ in 0..1000 {
            assert!(admit("ubf_session::drive"));
        }
    }
}
