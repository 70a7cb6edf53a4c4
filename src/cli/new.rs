//! `ubf new`: a crate of one's own behaviours that starts right — a
//! behaviour, a scenario that uses it, a test that runs it, and a profile
//! that builds the simulator optimised — written from
//! `examples/my-behaviours`, which the suite builds and tests.

use super::{CliError, Exit, Outcome};
use std::path::{Path, PathBuf};

/// Where the new crate takes ubf from.
pub(super) enum UbfSource {
    /// A checkout of ubf on this machine.
    Path(PathBuf),
    /// A git repository holding ubf.
    Git(String),
}

/// The name the example crate's sources use, which a new crate's replaces.
const EXAMPLE_NAME: &str = "my-behaviours";

/// The files of a new crate: where each goes and what it holds. All but
/// the manifest are `examples/my-behaviours`' own, which the suite builds
/// and tests; its manifest is a workspace member's, so the new crate's is
/// a template beside this file.
const FILES: [(&str, &str); 5] = [
    ("Cargo.toml", include_str!("template/Cargo.toml.in")),
    ("src/main.rs", include_str!("../../examples/my-behaviours/src/main.rs")),
    ("tests/scenario.rs", include_str!("../../examples/my-behaviours/tests/scenario.rs")),
    ("my-behaviours.ron", include_str!("../../examples/my-behaviours/my-behaviours.ron")),
    (".gitignore", include_str!("../../examples/my-behaviours/.gitignore")),
];

/// Writes a new crate into `dir` (absent or empty), named after it.
pub(super) fn command(dir: &Path, source: Option<UbfSource>) -> Outcome {
    let name = crate_name(dir).map_err(CliError::bad_input)?;
    let source = match source {
        Some(source) => source,
        None => UbfSource::Path(this_checkout().ok_or_else(|| {
            CliError::bad_input(
                "this ubf was built from sources no longer on this machine: say where ubf is with \
                 --ubf-path DIR (a checkout) or --ubf-git URL",
            )
        })?),
    };
    let dependencies = match &source {
        UbfSource::Path(path) => {
            let path = std::path::absolute(path)
                .map_err(|e| CliError::bad_input(format!("--ubf-path {}: {e}", path.display())))?;
            if !path.join("ubf-core/Cargo.toml").is_file() {
                return Err(CliError::bad_input(format!(
                    "{} holds no ubf-core/Cargo.toml, so it is not a checkout of ubf",
                    path.display()
                )));
            }
            let text = |p: &Path| toml_string(&p.display().to_string());
            format!("ubf = {{ path = {} }}\nubf-core = {{ path = {} }}", text(&path), text(&path.join("ubf-core")))
        }
        UbfSource::Git(url) => {
            format!("ubf = {{ git = {0} }}\nubf-core = {{ git = {0} }}", toml_string(url))
        }
    };
    if std::fs::read_dir(dir).is_ok_and(|mut entries| entries.next().is_some()) {
        return Err(CliError::bad_input(format!(
            "{} is not empty: a new crate goes into a new (or empty) directory, and nothing there is overwritten",
            dir.display()
        )));
    }
    for (file, template) in FILES {
        let path = dir.join(file.replace(EXAMPLE_NAME, &name));
        let body = template.replace(EXAMPLE_NAME, &name).replace("{ubf_dependencies}", &dependencies);
        write(&path, &body)?;
    }
    // The versions of every crate ubf was tested with, so the new crate
    // builds as ubf's own suite did.
    if let UbfSource::Path(path) = &source {
        if let Ok(lock) = std::fs::read(path.join("Cargo.lock")) {
            write(&dir.join("Cargo.lock"), &String::from_utf8_lossy(&lock))?;
        }
    }
    println!("wrote the crate `{name}` in {}: a behaviour (Cruise), {name}.ron using it, and a test", dir.display());
    println!("next: cd {} && cargo run --release -- run {name}.ron && cargo test", dir.display());
    Ok(Exit::Success)
}

/// The crate's name: the directory's, which Cargo must accept.
fn crate_name(dir: &Path) -> Result<String, String> {
    let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    let mut chars = name.chars();
    let starts_right = chars.next().is_some_and(|c| c.is_ascii_lowercase());
    if !starts_right || !chars.all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '_') {
        return Err(format!(
            "`{}`: the crate is named after its directory, which must start with a lower-case letter and hold \
             only lower-case letters, digits, `-` and `_`",
            dir.display()
        ));
    }
    let as_crate = name.replace('-', "_");
    if RESERVED.contains(&as_crate.as_str()) {
        return Err(format!(
            "`{}`: the crate is named after its directory, and `{name}` is {}: choose another name",
            dir.display(),
            if as_crate.starts_with("ubf") { "a crate it depends on" } else { "a Rust keyword or a standard crate" }
        ));
    }
    Ok(name.to_owned())
}

/// Names Cargo or Rust refuse for a package, or that would clash with
/// what the crate depends on.
const RESERVED: &[&str] = &[
    "abstract",
    "alloc",
    "as",
    "async",
    "await",
    "become",
    "box",
    "break",
    "const",
    "continue",
    "core",
    "crate",
    "do",
    "dyn",
    "else",
    "enum",
    "extern",
    "false",
    "final",
    "fn",
    "for",
    "gen",
    "if",
    "impl",
    "in",
    "let",
    "loop",
    "macro",
    "match",
    "mod",
    "move",
    "mut",
    "override",
    "priv",
    "proc_macro",
    "pub",
    "ref",
    "return",
    "self",
    "serde",
    "serde_json",
    "static",
    "std",
    "struct",
    "super",
    "test",
    "trait",
    "true",
    "try",
    "type",
    "typeof",
    "ubf",
    "ubf_behaviors",
    "ubf_core",
    "ubf_lab",
    "ubf_perception",
    "ubf_robots",
    "ubf_session",
    "unsafe",
    "unsized",
    "use",
    "virtual",
    "where",
    "while",
    "yield",
];

/// The checkout this binary was built from, if it is still there.
fn this_checkout() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    dir.join("ubf-core/Cargo.toml").is_file().then_some(dir)
}

/// `text` as a TOML basic string.
fn toml_string(text: &str) -> String {
    let mut quoted = String::from('"');
    for c in text.chars() {
        match c {
            '"' => quoted.push_str("\\\""),
            '\\' => quoted.push_str("\\\\"),
            c if c.is_control() => quoted.push_str(&format!("\\u{:04X}", c as u32)),
            c => quoted.push(c),
        }
    }
    quoted.push('"');
    quoted
}

fn write(path: &Path, body: &str) -> Result<(), CliError> {
    let fail = |e: std::io::Error| CliError::failed(format!("cannot write {}: {e}", path.display()));
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(fail)?;
    }
    std::fs::write(path, body).map_err(fail)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_crate_is_named_after_its_directory_as_cargo_allows() {
        assert_eq!(crate_name(Path::new("work/my-behaviours")).unwrap(), "my-behaviours");
        for bad in ["My", "1st", "with space", "", "ünï", "a.b", "fn", "self", "test", "std", "ubf", "ubf-core"] {
            assert!(crate_name(Path::new(bad)).is_err(), "{bad}");
        }
    }

    #[test]
    fn paths_are_quoted_for_toml() {
        assert_eq!(toml_string(r#"C:\a "b""#), r#""C:\\a \"b\"""#);
    }
}
