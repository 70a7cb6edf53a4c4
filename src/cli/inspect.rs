//! `ubf check`, `ubf tree` and `ubf behaviors`: looking at files and at
//! the registry without running anything.

use super::{CliError, Exit, Outcome};
use crate::scenario::Scenario;
use std::path::{Path, PathBuf};
use ubf_core::{BehaviorSpec, Registry};

/// Checks every file, reporting each bad one; exit code 2 if any was.
pub(super) fn check(registry: &Registry, files: &[PathBuf]) -> Outcome {
    let mut outcome = Exit::Success;
    for file in files {
        let checked = if is_robot_file(file) {
            crate::drive::DriveConfig::load(registry, file)
                .map_err(|e| e.to_string())
                .and_then(|(config, model)| {
                    config.check_camera().map_err(|e| format!("{}: camera: {e}", file.display()))?;
                    Ok((config, model))
                })
                .map(|(config, model)| {
                    let nodes = ubf_core::TreeLayout::of(config.root.build(&ubf_core::BuildContext::new(0)).as_ref());
                    format!(
                        "robot file \"{}\": a {} at {}, {} behaviour nodes",
                        config.name,
                        model.name,
                        config.connection,
                        nodes.nodes.len()
                    )
                })
        } else {
            Scenario::load(registry, file).map(|s| format!("scenario \"{}\"", s.name)).map_err(|e| e.to_string())
        };
        match checked {
            Ok(what) => println!("{}: ok, {what}", file.display()),
            Err(e) => {
                eprintln!("error: {e}");
                outcome = Exit::BadInput;
            }
        }
    }
    Ok(outcome)
}

/// Whether `file` is a robot file for `ubf drive` rather than a scenario:
/// it names itself `RobotConfig(…)`, or has a `connection`.
fn is_robot_file(file: &Path) -> bool {
    let bytes = ubf_core::config::read_bounded(file, ubf_core::config::MOST_SETTINGS_BYTES);
    let Some(text) = bytes.ok().and_then(|bytes| String::from_utf8(bytes).ok()) else { return false };
    let body: String = text.lines().map(|l| l.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n");
    let body = body.trim_start();
    body.starts_with("RobotConfig") || (body.starts_with('(') && body.contains("connection:"))
}

/// Prints a scenario's or robot file's tree as DOT or Mermaid.
pub(super) fn tree(registry: &Registry, file: &Path, mermaid: bool) -> Outcome {
    let spec: BehaviorSpec = if is_robot_file(file) {
        crate::drive::DriveConfig::load(registry, file).map(|(config, _)| config.root).map_err(CliError::bad_input)?
    } else {
        Scenario::load(registry, file).map(|s| s.root).map_err(CliError::bad_input)?
    };
    let root = spec.build(&ubf_core::BuildContext::new(0));
    print!("{}", if mermaid { crate::tree::mermaid(root.as_ref()) } else { crate::tree::dot(root.as_ref()) });
    Ok(Exit::Success)
}

/// Lists the registered behaviours, or describes their fields.
pub(super) fn behaviors(registry: &Registry, describe: bool, names: &[String]) -> Outcome {
    if let Some(unknown) = names.iter().find(|n| !registry.contains(n)) {
        let known: Vec<&str> = registry.names().collect();
        return Err(CliError::bad_input(format!(
            "unknown behaviour `{unknown}`; known behaviours: {}",
            known.join(", ")
        )));
    }
    let chosen: Vec<&str> =
        if names.is_empty() { registry.names().collect() } else { names.iter().map(String::as_str).collect() };
    for (i, name) in chosen.iter().enumerate() {
        if !describe {
            println!("{name}");
            continue;
        }
        let fields = registry.fields(name).unwrap_or_default();
        if i > 0 {
            println!();
        }
        println!("### `{name}`\n");
        if fields.is_empty() {
            println!("No settings: `{name}()`.");
        } else {
            print!("{}", ubf_core::markdown_table(fields));
        }
    }
    Ok(Exit::Success)
}
