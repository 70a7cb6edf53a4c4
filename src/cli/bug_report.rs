//! What a user sees when ubf itself fails: one paragraph saying what
//! failed, where, that the robot was stopped and the logs kept, and how to
//! report it, instead of Rust's panic message and backtrace (which
//! `RUST_BACKTRACE=1` still gives, for the report).
//!
//! A panic that ubf catches and reports in its own words (a behaviour's,
//! named by its path in the tree; a camera thread's, as a camera fault) is
//! left to that report.

/// Installs the panic hook that prints the paragraph.
pub(super) fn install() {
    let rust_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if std::env::var_os("RUST_BACKTRACE").is_some_and(|v| v != "0") {
            return rust_hook(info);
        }
        if ubf_core::panic_is_reported() {
            return;
        }
        let place =
            info.location().map_or_else(String::new, |l| format!(" at {}:{}:{}", l.file(), l.line(), l.column()));
        let message = ubf_core::panic_message(info.payload());
        let thread = std::thread::current().name().map_or_else(String::new, |n| format!(" (thread {n})"));
        eprintln!(
            "error: ubf failed inside itself{place}{thread}: {message}. This is a bug in ubf, not in your files. A \
             robot being driven is sent STOP and the logs written so far are kept. Please report it with the command \
             you ran and what it printed with RUST_BACKTRACE=1 set."
        );
    }));
}
