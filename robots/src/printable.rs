//! Text a device sent, made fit to show.

/// A string from a device (a robot's name, a pan-tilt unit's message), as
/// it is shown on a terminal and in logs: lossy UTF-8, with control
/// characters escaped (`\u{1b}`), which a terminal would obey and a log
/// would take for a line of its own.
pub(crate) fn text(bytes: &[u8]) -> String {
    let mut text = String::new();
    for c in String::from_utf8_lossy(bytes).chars() {
        match c.is_control() {
            true => text.extend(c.escape_default()),
            false => text.push(c),
        }
    }
    text
}

/// [`text`], cut after `most` characters (marked `…`): what a device or a
/// stranger sent may be of any length, and a log line is read.
pub(crate) fn text_cut(bytes: &[u8], most: usize) -> String {
    let text = text(bytes);
    match text.char_indices().nth(most) {
        Some((cut, _)) => format!("{}…", &text[..cut]),
        None => text,
    }
}
