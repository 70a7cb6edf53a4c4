//! Reading configuration: RON with positions in every error, and checked
//! numbers.
//!
//! The checkers plug into serde's `deserialize_with`, so a bad number is
//! reported at its line and column, with the field's name:
//!
//! ```
//! # use serde::Deserialize;
//! #[derive(Debug, Deserialize)]
//! #[serde(deny_unknown_fields)]
//! struct WanderConfig {
//!     #[serde(deserialize_with = "ubf_core::config::positive")]
//!     speed: f64,
//! }
//! let err = ubf_core::config::from_ron::<WanderConfig>("(speed: -1.0)").unwrap_err();
//! assert_eq!((err.line, err.column), (1, 9));
//! assert!(err.message.contains("must be > 0"), "{}", err.message);
//! ```

use serde::de::{DeserializeOwned, Error as _};
use serde::{Deserialize, Deserializer};
use std::fmt;

/// A RON document that could not be read, with the position of the fault.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub struct RonError {
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for RonError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.line, self.column, self.message)
    }
}

impl From<ron::error::SpannedError> for RonError {
    fn from(e: ron::error::SpannedError) -> Self {
        // The parser's limit, in the terms of the file: each level of a tree
        // is several levels of RON. (Inside a behaviour's own config it
        // arrives as text, so the text is what is matched.)
        let message = match e.code.to_string() {
            text if text.starts_with("Exceeded recursion limit") => {
                "nested too deeply: a behaviour tree may be at most 15 composites deep".to_owned()
            }
            text => match misspelt(&text) {
                Some(meant) => format!("{text}; did you mean `{meant}`?"),
                None => text,
            },
        };
        RonError { line: e.span.start.line, column: e.span.start.col, message }
    }
}

/// What the parser's "Unexpected field named `cruise_sped`, expected one of
/// `cruise_speed`, …" (or variant) most likely meant, if one name is close.
fn misspelt(message: &str) -> Option<&str> {
    let found = message.strip_prefix("Unexpected ")?.split_once("named `")?.1.split('`').next()?;
    let expected = message.split_once(", expected ")?.1;
    let known = expected.split('`').skip(1).step_by(2);
    nearest(found, known)
}

/// The name in `known` that `found` most likely misspells, if one is close
/// (as a person would mistype it: a letter dropped, swapped or in the
/// wrong case).
pub fn nearest<'a>(found: &str, known: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    known
        .into_iter()
        .map(|name| (strsim::jaro_winkler(&found.to_lowercase(), &name.to_lowercase()), name))
        .filter(|(likeness, _)| *likeness > 0.85)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, name)| name)
}

/// The most bytes a settings file (a scenario, a robot or model file, a
/// pose file) may hold: thousands of times what any needs.
pub const MOST_SETTINGS_BYTES: u64 = 16 << 20;

/// Reads the file at `path` whole, if it is a regular file of at most
/// `most` bytes: a FIFO would block the reader, a device (`/dev/zero`)
/// never end, and a huge file fill memory, so each is an error that says
/// so instead.
pub fn read_bounded(path: &std::path::Path, most: u64) -> std::io::Result<Vec<u8>> {
    use std::io::{Error, ErrorKind, Read};
    let mut bytes = Vec::new();
    open_regular(path)?.take(most + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > most {
        return Err(Error::new(ErrorKind::InvalidData, format!("larger than {most} bytes")));
    }
    Ok(bytes)
}

/// [`read_bounded`] for a text file: bytes that are not UTF-8 are an
/// error of kind `InvalidData`.
pub fn read_text_bounded(path: &std::path::Path, most: u64) -> std::io::Result<String> {
    String::from_utf8(read_bounded(path, most)?)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "not UTF-8 text"))
}

fn not_regular() -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a regular file")
}

/// Opens `path` for reading if it is a regular file, for a reader that
/// streams it: a FIFO would block the reader, a device never end. Looked
/// at before it is opened, so that a device is not opened at all (opening
/// a serial port can reset what is on its other end).
pub fn open_regular(path: &std::path::Path) -> std::io::Result<std::fs::File> {
    if !std::fs::metadata(path)?.is_file() {
        return Err(not_regular());
    }
    open_unwaiting(path)
}

/// Opens `path` for reading if what is opened is a regular file. The look
/// before the open can be overtaken: a FIFO swapped in between would block
/// a plain open until a writer came, so the open does not wait, and the
/// handle itself is looked at.
fn open_unwaiting(path: &std::path::Path) -> std::io::Result<std::fs::File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // Reads of a regular file ignore the flag.
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path)?;
    if !file.metadata()?.is_file() {
        return Err(not_regular());
    }
    Ok(file)
}

/// Why the file at `path` could not be read, for a person: a relative
/// path that is not there says where it was looked for, since the working
/// directory is not always the one the reader has in mind (an installed
/// `ubf` run outside the checkout, a service).
pub fn why_unread(path: &std::path::Path, error: &std::io::Error) -> String {
    let cwd = std::env::current_dir();
    match cwd {
        Ok(dir) if error.kind() == std::io::ErrorKind::NotFound && path.is_relative() => {
            format!("not found in the working directory {}", dir.display())
        }
        _ => error.to_string(),
    }
}

/// A file's bytes as text, or where the first byte that is not UTF-8 sits.
pub fn utf8_text(bytes: Vec<u8>) -> Result<String, RonError> {
    String::from_utf8(bytes).map_err(|e| {
        let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
        let line_start = good.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let column = String::from_utf8_lossy(&good[line_start..]).chars().count() + 1;
        RonError { line, column, message: "not UTF-8 text: save the file as UTF-8".into() }
    })
}

/// Where the field at `path` (`["robot", "start"]`: the `start` field of
/// the top-level `robot` field) is named in the RON document `text`, as
/// 1-based line and column; where a field on the path is not written (it
/// took its default), the last one that is; `None` if not even the first
/// is. For errors about a document that parsed, so that they point where
/// its reader should look. (Raw strings are not followed, and a field
/// inside `Some((..))` is found as its parent: both fall back, never
/// mislead.)
pub fn field_position(text: &str, path: &[&str]) -> Option<(usize, usize)> {
    if path.is_empty() {
        return None;
    }
    let mut found: Option<(usize, usize)> = None;
    // The depth the next field on the path is written at: the top-level
    // struct's fields are at depth 1.
    let mut matched = 0;
    let mut depth = 0usize;
    let (mut line, mut column) = (1, 1);
    let mut chars = text.chars().peekable();
    // The identifier being read, and where it began.
    let mut word = String::new();
    let mut word_at = (1, 1);
    // An identifier just read, waiting to see whether a `:` follows.
    let mut pending: Option<(String, (usize, usize))> = None;
    while let Some(c) = chars.next() {
        let at = (line, column);
        if c == '\n' {
            (line, column) = (line + 1, 1);
        } else {
            column += 1;
        }
        if c.is_alphanumeric() || c == '_' {
            if word.is_empty() {
                word_at = at;
            }
            word.push(c);
            continue;
        }
        if !word.is_empty() {
            pending = Some((std::mem::take(&mut word), word_at));
        }
        match c {
            _ if c.is_whitespace() => continue,
            '/' if chars.peek() == Some(&'/') => {
                for c in chars.by_ref() {
                    if c == '\n' {
                        (line, column) = (line + 1, 1);
                        break;
                    }
                }
                continue;
            }
            '/' if chars.peek() == Some(&'*') => {
                let mut last = ' ';
                for c in chars.by_ref() {
                    if c == '\n' {
                        (line, column) = (line + 1, 1);
                    } else {
                        column += 1;
                    }
                    if last == '*' && c == '/' {
                        break;
                    }
                    last = c;
                }
                continue;
            }
            '"' => {
                let mut escaped = false;
                for c in chars.by_ref() {
                    if c == '\n' {
                        (line, column) = (line + 1, 1);
                    } else {
                        column += 1;
                    }
                    match c {
                        '"' if !escaped => break,
                        '\\' => escaped = !escaped,
                        _ => escaped = false,
                    }
                }
            }
            ':' if chars.peek() != Some(&':') => {
                if let Some((name, name_at)) = pending.take() {
                    if depth == matched + 1 && name == path[matched] {
                        found = Some(name_at);
                        matched += 1;
                        if matched == path.len() {
                            return found;
                        }
                    }
                }
                continue;
            }
            '(' | '[' | '{' => depth += 1,
            ')' | ']' | '}' => {
                depth = depth.saturating_sub(1);
                if depth < matched {
                    // Out of the last field found's value: its child is
                    // not written.
                    return found;
                }
            }
            ',' if depth == matched && matched > 0 => return found,
            _ => {}
        }
        pending = None;
    }
    found
}

/// The RON dialect of scenario and robot files: `Name(field: ..)` for
/// behaviours with a config, and `field: value` for optional fields.
pub fn ron_options() -> ron::Options {
    use ron::extensions::Extensions;
    ron::Options::default().with_default_extension(Extensions::UNWRAP_VARIANT_NEWTYPES | Extensions::IMPLICIT_SOME)
}

/// Reads a value from RON text. Documents that contain behaviour trees are
/// read with [`crate::Registry::from_ron`] instead.
pub fn from_ron<T: DeserializeOwned>(text: &str) -> Result<T, RonError> {
    ron_options().from_str(text).map_err(|e| with_hint(RonError::from(e), text))
}

/// The error, with a hint where the dialect differs from plain RON: with
/// newtype variants unwrapped, `Some((field: ..))` is read as a struct named
/// `Some`, and the parser's complaint names neither.
fn with_hint(mut error: RonError, text: &str) -> RonError {
    // The line up to and including the character the parser stopped at.
    let before: String =
        text.lines().nth(error.line.saturating_sub(1)).unwrap_or_default().chars().take(error.column).collect();
    let compact: String = before.chars().filter(|c| !c.is_whitespace()).collect();
    if compact.ends_with("Some((") {
        error.message += "; write an optional setting as `Some(field: ..)` or just `(field: ..)`, without the inner \
                          parentheses";
    }
    // A value out of range or of the wrong kind: the message names
    // neither its field nor what the line means, so the field is named.
    let value_at = before.chars().count().min(error.column.saturating_sub(1));
    let of_value = ["is out of range", "out of bounds", "Expected ", "variant named"];
    if of_value.iter().any(|fault| error.message.contains(fault)) {
        if let Some(field) = field_of_value(&before.chars().take(value_at).collect::<String>()) {
            error.message = format!("{field}: {}", error.message);
        }
    }
    error
}

/// The field whose value starts where `line_before` ends (`    width: `
/// gives `width`; the parser may stop past a number's sign, or inside an
/// optional value's `Some(`), if it does.
fn field_of_value(line_before: &str) -> Option<&str> {
    let value_start = line_before.trim_end_matches(['-', '+']).trim_end();
    let value_start = value_start.strip_suffix("Some(").unwrap_or(value_start).trim_end();
    let name = value_start.strip_suffix(':')?.trim_end();
    let field = name.rsplit(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).next()?;
    field.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_').then_some(field)
}

fn number_where<'de, D: Deserializer<'de>>(d: D, ok: impl Fn(f64) -> bool, rule: &str) -> Result<f64, D::Error> {
    let v = f64::deserialize(d)?;
    if ok(v) {
        Ok(v)
    } else {
        Err(D::Error::custom(format!("{} is out of range: must be {rule}", shown(v))))
    }
}

/// A number as a person would write it: `1e-300`, not three hundred zeros
/// (as `{}` would print it), for messages that quote what a file says.
pub fn shown(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e7).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// A finite number > 0.
pub fn positive<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_where(d, |v| v.is_finite() && v > 0.0, "> 0")
}

/// A control period, s: 1 ms to 10 s.
pub fn period_s<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_where(d, |v| (1e-3..=10.0).contains(&v), "from 0.001 to 10 s")
}

/// A duration, s: > 0 and at most 10⁷ s (about four months).
pub fn duration_s<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_where(d, |v| v > 0.0 && v <= 1e7, "> 0 and at most 1e7 s")
}

/// A length in the world, m: 1 cm to 10 km.
pub fn extent_m<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_where(d, |v| (0.01..=1e4).contains(&v), "from 0.01 to 10000 m")
}

/// A number within `range`, else an error that gives the rule (`rule`,
/// e.g. "from 0.01 to 1 s"): for a crate's own bounded fields,
/// `fn period<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
/// number_in(d, 0.01..=1.0, "from 0.01 to 1 s") }`.
pub fn number_in<'de, D: Deserializer<'de>>(
    d: D,
    range: std::ops::RangeInclusive<f64>,
    rule: &str,
) -> Result<f64, D::Error> {
    number_where(d, |v| range.contains(&v), rule)
}

/// A ground robot's speed, m/s: > 0 and at most 10 (faster than any robot
/// this drives, so a slip of the keyboard is caught; the robot's own limits
/// then bound it further).
pub fn speed_m_s<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_where(d, |v| v > 0.0 && v <= 10.0, "> 0 and at most 10 m/s")
}

/// A turn rate, °/s: > 0 and at most 3600 (ten turns a second).
pub fn rate_deg_s<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_where(d, |v| v > 0.0 && v <= 3600.0, "> 0 and at most 3600 °/s")
}

/// An angle, °: from −360 to 360.
pub fn angle_deg<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_where(d, |v| (-360.0..=360.0).contains(&v), "from -360 to 360°")
}

/// A coordinate in the world, m: within 10 km of the origin.
pub fn coordinate_m<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_where(d, |v| (-1e4..=1e4).contains(&v), "from -10000 to 10000 m")
}

/// A name shown to people (on a terminal, in a plot): text without control
/// characters, which a terminal would obey (an escape retitles it, or clears
/// the screen).
pub fn shown_name<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    let name = String::deserialize(d)?;
    match name.chars().find(|c| c.is_control()) {
        Some(c) => Err(D::Error::custom(format!("the name holds a control character ({c:?}): write it without"))),
        None => Ok(name),
    }
}

/// A finite number ≥ 0.
pub fn non_negative<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_where(d, |v| v.is_finite() && v >= 0.0, "≥ 0")
}

/// Any finite number.
pub fn finite<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_where(d, f64::is_finite, "a finite number")
}

/// A number in [0, 1].
pub fn unit_interval<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_where(d, |v| (0.0..=1.0).contains(&v), "within [0, 1]")
}

/// A config that can check itself beyond what its field types say: numbers
/// that must agree with each other, lists that must not be empty.
pub trait Check {
    /// Why the config is wrong, if it is.
    fn check(&self) -> Result<(), String>;
}

/// Reads a [`Check`] config and checks it, so the error carries a position
/// (the end of the config): `#[serde(deserialize_with = "ubf_core::config::checked")]`.
pub fn checked<'de, D: Deserializer<'de>, T: Deserialize<'de> + Check>(d: D) -> Result<T, D::Error> {
    let value = T::deserialize(d)?;
    value.check().map_err(D::Error::custom)?;
    Ok(value)
}

/// A [`Check`] config checked as it is read, for registering a behaviour
/// whose config needs more than per-field checks:
/// `registry.register("Avoid", |c: &Checked<AvoidConfig>, _| Avoid::new(&c.0))`.
#[derive(Clone, Debug, PartialEq)]
pub struct Checked<T>(pub T);

impl<'de, T: Deserialize<'de> + Check> Deserialize<'de> for Checked<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        checked(d).map(Checked)
    }
}

/// An optional finite number > 0.
pub fn optional_positive<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    match Option::<f64>::deserialize(d)? {
        Some(v) if !(v.is_finite() && v > 0.0) => Err(D::Error::custom(format!("{v} is out of range: must be > 0"))),
        v => Ok(v),
    }
}

/// An optional number within `range` (see [`number_in`]).
pub fn optional_number_in<'de, D: Deserializer<'de>>(
    d: D,
    range: std::ops::RangeInclusive<f64>,
    rule: &str,
) -> Result<Option<f64>, D::Error> {
    match Option::<f64>::deserialize(d)? {
        Some(v) if !range.contains(&v) => {
            Err(D::Error::custom(format!("{} is out of range: must be {rule}", shown(v))))
        }
        v => Ok(v),
    }
}

/// An optional duration, s: > 0 and at most 10⁷ s.
pub fn optional_duration_s<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    optional_number_in(d, f64::MIN_POSITIVE..=1e7, "> 0 and at most 1e7 s")
}

/// An optional angle, °: from −360 to 360.
pub fn optional_angle_deg<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    optional_number_in(d, -360.0..=360.0, "from -360 to 360°")
}

/// An optional finite number ≥ 0.
pub fn optional_non_negative<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    match Option::<f64>::deserialize(d)? {
        Some(v) if !(v.is_finite() && v >= 0.0) => Err(D::Error::custom(format!("{v} is out of range: must be ≥ 0"))),
        v => Ok(v),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn a_fifo_that_overtakes_the_look_is_refused_without_waiting() {
        // The open step on its own, as if the FIFO had been swapped in after
        // the look: a plain open would wait for a writer that never comes.
        let path = std::env::temp_dir().join(format!("ubf-open-regular-{}", std::process::id()));
        let _ = std::fs::remove_file(&path);
        assert!(std::process::Command::new("mkfifo").arg(&path).status().unwrap().success());
        let (sent, opened) = crossbeam_channel::bounded(1);
        let fifo = path.clone();
        std::thread::spawn(move || sent.send(open_unwaiting(&fifo).map(drop)));
        let outcome = opened.recv_timeout(std::time::Duration::from_secs(10));
        std::fs::remove_file(&path).unwrap();
        let error = outcome.expect("the open waited for a writer").unwrap_err();
        assert_eq!(error.to_string(), "not a regular file");
    }

    #[test]
    fn a_field_is_found_by_its_path_and_not_in_strings_comments_or_other_fields() {
        let text = "Scenario(\n  name: \"goal: x\", // goal: no\n  robot: (speed: 1, start: (x: 1)),\n  world: (start: 2),\n  goal: (x: 3),\n)";
        assert_eq!(field_position(text, &["goal"]), Some((5, 3)));
        assert_eq!(field_position(text, &["robot", "start"]), Some((3, 21)));
        // Not written: the nearest that is.
        assert_eq!(field_position(text, &["world", "goal"]), Some((4, 3)));
        assert_eq!(field_position("Scenario(robot: (start: 1), world: (x: 1))", &["robot", "x"]), Some((1, 10)));
        assert_eq!(field_position(text, &["seed"]), None);
        assert_eq!(field_position(text, &["start"]), None);
    }

    #[test]
    fn a_value_the_parser_stops_at_is_said_with_its_field() {
        #[derive(Debug, Deserialize)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct Corridor {
            #[serde(deserialize_with = "extent_m")]
            width: f64,
            count: u32,
        }
        let said = |text: &str| from_ron::<Corridor>(text).unwrap_err().to_string();
        assert_eq!(
            said("(\n  width: -3.0,\n  count: 1)"),
            "2:10: width: -3 is out of range: must be from 0.01 to 10000 m"
        );
        assert_eq!(said("(width: 6.0, count:-40)"), "1:21: count: Integer is out of bounds");
        // Not at a value: nothing added.
        assert!(said("(width: 6.0, cont: 4)").starts_with("1:14: Unexpected field named `cont`"));
        assert_eq!(field_of_value("  goal: "), Some("goal"));
        assert_eq!(field_of_value("(noise: Some("), Some("noise"));
        // RON takes marks such as U+200E as white space: several bytes.
        assert_eq!(field_of_value("(\u{200E}width: "), Some("width"));
        assert_eq!(
            said("(\u{200E}width: -3.0, count: 1)"),
            "1:10: width: -3 is out of range: must be from 0.01 to 10000 m"
        );
        assert_eq!(field_of_value("(x: 1, \"a:\" "), None);
        assert_eq!(field_of_value("  9lives: "), None);
    }

    #[test]
    fn a_misspelt_name_is_matched_and_a_strange_one_is_not() {
        let field = "Unexpected field named `cruise_sped`, expected one of `cruise_speed`, `turn_gain` instead";
        assert_eq!(misspelt(field), Some("cruise_speed"));
        let variant = "Unexpected enum variant named `HighestPrority`, expected one of `HighestPriority`, `MonteCarlo`";
        assert_eq!(misspelt(variant), Some("HighestPriority"));
        assert_eq!(misspelt("Unexpected field named `zzz`, expected one of `cruise_speed`, `vote` instead"), None);
        assert_eq!(nearest("GoTO", ["Stop", "GoTo", "SweepCamera"]), Some("GoTo"));
        assert_eq!(nearest("Wander", ["Stop", "GoTo", "SweepCamera"]), None);
    }

    #[test]
    fn a_regular_file_within_the_bound_is_read_and_one_beyond_it_refused() {
        let path = std::env::temp_dir().join(format!("ubf-read-bounded-{}", std::process::id()));
        std::fs::write(&path, b"12345").unwrap();
        let within = read_bounded(&path, 5).unwrap();
        let beyond = read_bounded(&path, 4).unwrap_err();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(within, b"12345");
        assert_eq!(beyond.to_string(), "larger than 4 bytes");
    }
}
