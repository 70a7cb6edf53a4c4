//! The front door under careless input: every shipped scenario and robot
//! file, mutated (numbers to NaN, ±inf, 0, −1, 1e308, u32::MAX; lines
//! deleted or repeated; brackets nested thousands deep), must be refused
//! with a position or load into a run that finishes (within 5 simulated
//! seconds, a minute of wall time, and without aborting on memory). The
//! same for a recorded image directory's `camera.ron` and `frames.csv`,
//! replayed through the stereo pipeline. 2 000 cases in the suite
//! (`UBF_FUZZ_CASES` sets another number; `UBF_FUZZ_TRACE=FILE` keeps the
//! case being tried, for a crash); the ignored test runs 10⁵.

use proptest::prelude::*;
use std::path::Path;
use ubf::scenario::Scenario;

/// Every shipped scenario and robot file, with its text.
fn shipped() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in ["scenarios", "lab/scenarios/thesis", "robots/config"] {
        for entry in std::fs::read_dir(root.join(dir)).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "ron") {
                files.push((path.display().to_string(), std::fs::read_to_string(&path).unwrap()));
            }
        }
    }
    files.sort();
    files
}

const REPLACEMENTS: [&str; 8] = ["NaN", "inf", "-inf", "0", "-1", "1e308", "4294967295", "0.0"];

/// One mutation of `text`: a number replaced, a line deleted, a line
/// repeated, or brackets opened 5 000 deep, chosen by `pick`.
fn mutate(text: &str, kind: u8, pick: usize, replacement: &str) -> String {
    let lines: Vec<&str> = text.lines().collect();
    match kind % 4 {
        3 => {
            let mut at = pick % (text.len() + 1);
            while !text.is_char_boundary(at) {
                at -= 1;
            }
            let bracket = ["(", "[", "Composite(arbiter: Priority, children: [(behavior: "][pick % 3];
            format!("{}{}{}", &text[..at], bracket.repeat(5000), &text[at..])
        }
        0 => {
            // The pick-th number in the file.
            let numbers: Vec<(usize, usize)> = number_spans(text);
            if numbers.is_empty() {
                return text.to_owned();
            }
            let (start, end) = numbers[pick % numbers.len()];
            format!("{}{replacement}{}", &text[..start], &text[end..])
        }
        1 => {
            let i = pick % lines.len().max(1);
            lines.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, l)| *l).collect::<Vec<_>>().join("\n")
        }
        _ => {
            let i = pick % lines.len().max(1);
            let mut out: Vec<&str> = lines.clone();
            if let Some(line) = lines.get(i) {
                out.insert(i, line);
            }
            out.join("\n")
        }
    }
}

/// Byte spans of the numeric literals in `text`.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let bytes = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let starts =
            bytes[i].is_ascii_digit() && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'));
        if starts {
            let start = if i > 0 && bytes[i - 1] == b'-' { i - 1 } else { i };
            let mut end = i;
            while end < bytes.len() && (bytes[end].is_ascii_digit() || matches!(bytes[end], b'.' | b'e' | b'E')) {
                end += 1;
            }
            spans.push((start, end));
            i = end;
        } else {
            i += 1;
        }
    }
    spans
}

/// Loads `text` as the file it came from: refused with a position, or
/// accepted and (for a scenario) run for at most 5 simulated seconds.
fn front_door(path: &str, text: &str) -> Result<(), TestCaseError> {
    let registry = ubf::registry();
    if path.contains("robots/config") {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("robot.ron");
        std::fs::write(&file, text).unwrap();
        if let Err(e) = ubf::drive::DriveConfig::load(&registry, &file) {
            prop_assert!(e.to_string().contains("robot.ron"), "no file named: {e}");
        }
        return Ok(());
    }
    match Scenario::from_ron(&registry, text) {
        Err(e) => prop_assert!(e.line >= 1 && e.column >= 1, "{e}"),
        Ok(mut scenario) => {
            if scenario.check_start().is_err() || scenario.check_work().is_err() {
                return Ok(());
            }
            scenario.max_time_s = scenario.max_time_s.min(5.0);
            let started = std::time::Instant::now();
            let report = ubf::run::run(&scenario, 0, None);
            prop_assert!(report.is_ok(), "{:?}", report.err());
            prop_assert!(started.elapsed().as_secs() < 60, "a 5 s run took {:?}", started.elapsed());
        }
    }
    Ok(())
}

/// A directory of three small rendered pairs, recorded once.
fn recording() -> &'static Path {
    static DIR: std::sync::OnceLock<tempfile::TempDir> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut scenario = Scenario::load(&ubf::registry(), &root.join("scenarios/rendered-corridor.ron")).unwrap();
        let camera = &mut scenario.robot.camera.as_mut().unwrap().stereo;
        (camera.width_px, camera.height_px, camera.focal_px) = (160, 120, 138.6);
        let dir = tempfile::tempdir().unwrap();
        ubf::frames::record(&scenario, 1, dir.path(), 3).unwrap();
        dir
    })
    .path()
}

/// Replays a copy of the recording with `file` (`camera.ron` or
/// `frames.csv`) replaced by `text`: it runs, or it is refused naming the
/// file and where in it (or the image it lists that cannot be read).
fn replayed(file: &str, text: &str) -> Result<(), TestCaseError> {
    let dir = tempfile::tempdir().unwrap();
    for name in ["camera.ron", "frames.csv", "left", "right"] {
        std::os::unix::fs::symlink(recording().join(name), dir.path().join(name)).unwrap();
    }
    std::fs::remove_file(dir.path().join(file)).unwrap();
    std::fs::write(dir.path().join(file), text).unwrap();
    let started = std::time::Instant::now();
    match ubf::frames::replay(dir.path(), &ubf::frames::ReplayOptions::default()).map_err(|e| e.to_string()) {
        Ok(replay) => prop_assert!(replay.report.frames <= 6, "{:?}", replay.report),
        Err(e) if file == "camera.ron" && e.contains("camera.ron:") => {}
        Err(e) if e.contains("frames.csv:") || e.contains("no pairs listed") => {}
        Err(e) => prop_assert!(false, "refused without saying where: {e}"),
    }
    prop_assert!(started.elapsed().as_secs() < 60, "three pairs took {:?}", started.elapsed());
    Ok(())
}

fn check_cases(cases: u32) {
    let files = shipped();
    let config = ProptestConfig { cases, failure_persistence: None, ..ProptestConfig::default() };
    proptest!(config, |(file in 0..files.len(), kind in any::<u8>(), pick in any::<usize>(), r in 0..REPLACEMENTS.len())| {
        let (path, text) = &files[file];
        let mutated = mutate(text, kind, pick, REPLACEMENTS[r]);
        if let Ok(trace) = std::env::var("UBF_FUZZ_TRACE") {
            std::fs::write(trace, format!("{path}\n{mutated}")).unwrap();
        }
        front_door(path, &mutated)?;
    });
    let recorded: Vec<(&str, String)> = ["camera.ron", "frames.csv"]
        .into_iter()
        .map(|name| (name, std::fs::read_to_string(recording().join(name)).unwrap()))
        .collect();
    let config = ProptestConfig { cases: cases / 4, failure_persistence: None, ..ProptestConfig::default() };
    proptest!(config, |(file in 0..2usize, kind in any::<u8>(), pick in any::<usize>(), r in 0..REPLACEMENTS.len())| {
        let (name, text) = &recorded[file];
        replayed(name, &mutate(text, kind, pick, REPLACEMENTS[r]))?;
    });
}

#[test]
fn mutated_shipped_files_are_refused_with_a_position_or_run() {
    check_cases(std::env::var("UBF_FUZZ_CASES").ok().and_then(|n| n.parse().ok()).unwrap_or(2000));
}

#[test]
#[ignore = "10⁵ cases: run it on purpose, in release"]
fn a_hundred_thousand_mutated_files() {
    check_cases(100_000);
}
