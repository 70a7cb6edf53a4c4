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
use tracing::field::{Field, Visit};
use tracing::{Event, Level, Metadata};
use tracing_subscriber::layer::{Context, Filter};

/// The most warnings and errors a second each of those libraries may log.
const MOST_LINES_PER_S: u64 = 10;

/// The libraries that log what others on the network send them, by the
/// start of their targets: the live view's server and the DDS library.
const FROM_NETWORK: [&str; 2] = ["foxglove", "rustdds"];

/// Where and in what words the DDS library notes every datagram over 1500
/// bytes it sends, to one address or to a multicast group (a scan served
/// on ROS 2, ten times a second: 87 MB of stderr a day, of nothing wrong).
const DATAGRAM_SIZE_NOTICE: (&str, &str) = ("rustdds::network::udp_sender", ": Message size = ");

/// The log filter for those libraries: their warnings and errors held to
/// [`MOST_LINES_PER_S`] a second each (what they say at the levels `-v`
/// asks for is not held back), and, unless asked for, without the DDS
/// library's datagram-size notices.
pub(super) struct NetworkLines {
    /// Whether the datagram-size notices are said (`-vv`).
    pub(super) datagram_sizes: bool,
}

impl<S> Filter<S> for NetworkLines {
    fn enabled(&self, _: &Metadata<'_>, _: &Context<'_, S>) -> bool {
        true
    }

    /// Event by event for those libraries' warnings and errors, never for
    /// the rest. (The `log` crate's lines, the DDS library's among them,
    /// come by call sites never registered, and are asked about each.)
    fn callsite_enabled(&self, metadata: &'static Metadata<'static>) -> tracing::subscriber::Interest {
        match is_budgeted(metadata) && is_from_network(metadata.target()) {
            true => tracing::subscriber::Interest::sometimes(),
            false => tracing::subscriber::Interest::always(),
        }
    }

    fn event_enabled(&self, event: &Event<'_>, _: &Context<'_, S>) -> bool {
        if !is_budgeted(event.metadata()) {
            return true;
        }
        let target = target_of(event);
        let Some(library) = FROM_NETWORK.iter().position(|library| is_from(target, library)) else { return true };
        let (notice_target, notice_words) = DATAGRAM_SIZE_NOTICE;
        if !self.datagram_sizes && target == notice_target && message_of(event).contains(notice_words) {
            return false;
        }
        static START: LazyLock<Instant> = LazyLock::new(Instant::now);
        static BUDGETS: [Budget; FROM_NETWORK.len()] = [Budget::new(), Budget::new()];
        BUDGETS[library].admit(START.elapsed().as_secs())
    }
}

/// Whether `metadata` is of a warning or an error, what the budget holds.
fn is_budgeted(metadata: &Metadata<'_>) -> bool {
    metadata.is_event() && *metadata.level() <= Level::WARN
}

/// An event's target: a `log` crate line's own (its call site's is `log`
/// for them all).
fn target_of<'a>(event: &'a Event<'a>) -> &'a str {
    use tracing_log::NormalizeEvent;
    event.normalized_metadata().map_or(event.metadata().target(), |metadata| metadata.target())
}

fn is_from(target: &str, library: &str) -> bool {
    target.starts_with(library)
}

fn is_from_network(target: &str) -> bool {
    FROM_NETWORK.iter().any(|library| is_from(target, library))
}

/// An event's message, as written.
fn message_of(event: &Event<'_>) -> String {
    struct Message(String);
    impl Visit for Message {
        fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
            if field.name() == "message" {
                self.0 = format!("{value:?}");
            }
        }
    }
    let mut message = Message(String::new());
    event.record(&mut message);
    message.0
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
        if !is_from_network(target_of(event)) {
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
    struct Sink(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

    impl std::io::Write for Sink {
        fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(bytes);
            Ok(bytes.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    /// What `log` writes through a plain line format behind `filter`.
    pub(in crate::cli) fn lines_logged<F>(filter: F, log: impl FnOnce()) -> String
    where
        F: Filter<tracing_subscriber::Registry> + Send + Sync + 'static,
    {
        let said = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let sink = std::sync::Arc::clone(&said);
        use tracing_subscriber::layer::SubscriberExt;
        use tracing_subscriber::Layer;
        let layer = tracing_subscriber::fmt::layer()
            .with_writer(move || Sink(std::sync::Arc::clone(&sink)))
            .with_ansi(false)
            .without_time()
            .with_filter(filter);
        tracing::subscriber::with_default(tracing_subscriber::registry().with(layer), log);
        let text = String::from_utf8(said.lock().unwrap().clone());
        text.unwrap()
    }

    #[test]
    fn each_library_s_warnings_have_a_budget_and_the_rest_of_the_log_none() {
        // The DDS library logs through the `log` crate, whose lines come
        // with a target of `log` and their own in a field.
        let from_log = |target: &str, text: &str| {
            use tracing_log::log::{Level, Record};
            let args = format_args!("{text}");
            let record = Record::builder().target(target).level(Level::Warn).args(args).build();
            tracing_log::format_trace(&record).unwrap();
        };
        let text = lines_logged(NetworkLines { datagram_sizes: false }, || {
            for _ in 0..100 {
                tracing::error!(target: "foxglove::websocket", "a client's garbage");
                from_log("rustdds::structure", "a peer's garbage");
                from_log("rustdds::network::udp_sender", "try_send_to_locator: Message size = 1548");
                from_log("rustdds::network::udp_sender", "send_to_multicast_locator_via: Message size = 1548");
                tracing::warn!(target: "ubf_session::drive", "ours");
                tracing::info!(target: "rustdds::discovery", "asked for with -v");
            }
        });
        let count = |what: &str| text.lines().filter(|l| l.contains(what)).count();
        // Within one second or two of the clock's.
        assert!((10..=20).contains(&count("a client's garbage")), "{text}");
        assert!((10..=20).contains(&count("a peer's garbage")), "{text}");
        assert_eq!(count("Message size"), 0, "{text}");
        assert_eq!((count("ours"), count("asked for with -v")), (100, 100), "{text}");
        assert!(is_from_network("rustdds::network") && !is_from_network("ubf_robots::ros2::node"));
    }
}
