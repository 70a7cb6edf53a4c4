//! The docs say what the program does: every fenced block in `README.md`
//! and `docs/*.md` that shows a command, a sample output or a file is
//! checked against the program.
//!
//! How a block is marked (the first word is the language, so the page
//! renders as before):
//!
//! - ```` ```sh run ````: run in this suite, in a scratch copy of the
//!   repository, with `ubf` being the binary under test (`cargo run
//!   --release --` and `./target/release/ubf` stand for it, `cargo build
//!   --release` is already done); `sh run exit=2` expects that status.
//! - ```` ```sh run-slow ````: minutes of work (benchmarks, experiments,
//!   installing OpenCV); run by `cargo test --test docs -- --ignored`.
//! - ```` ```sh no-run: why ````: not run (it needs `sudo`, a serial port,
//!   another program, or it is this suite itself).
//! - ```` ```text output ````: the output (stdout and stderr, in order) of
//!   the `sh` block before it, compared by shape: numbers stand for any
//!   number, runs of spaces for any spacing.
//! - ```` ```ron ```` must load as the scenario or robot file it shows;
//!   ```` ```ron fragment ```` is part of one and is not loaded.
//!
//! Whatever the mark, every `ubf` command line in a shell block must be one
//! that `ubf` accepts.
//!
//! The pages use the ports a user would (`127.0.0.1:8101` for ARCOS); the
//! suite must not, since another program may hold them. In the scratch copy
//! that address stands for a port free when the copy is made, in every
//! block and in the robot files of `robots/config/`.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// A fenced block of a page.
#[derive(Debug)]
struct Block {
    /// `page:line` of its opening fence.
    place: String,
    /// The opening fence's info string: `sh run`, `text output`.
    info: String,
    /// Its lines.
    body: String,
}

impl Block {
    fn language(&self) -> &str {
        self.info.split_whitespace().next().unwrap_or("")
    }

    fn mark(&self) -> &str {
        self.info.split_whitespace().nth(1).unwrap_or("")
    }

    /// The exit status a `sh run` block expects (`exit=N`, 0 by default).
    fn expected_status(&self) -> i32 {
        self.info.split_whitespace().find_map(|w| w.strip_prefix("exit=")?.parse().ok()).unwrap_or(0)
    }
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `README.md` and every page under `docs/`.
fn pages() -> Vec<PathBuf> {
    let mut pages: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    pages.insert(0, root().join("README.md"));
    pages
}

fn blocks(page: &Path) -> Vec<Block> {
    let text = std::fs::read_to_string(page).unwrap();
    let name = page.strip_prefix(root()).unwrap().display().to_string();
    let mut blocks = Vec::new();
    let mut open: Option<Block> = None;
    for (i, line) in text.lines().enumerate() {
        // Fences may be indented, inside a list item.
        match (line.trim_start().strip_prefix("```"), open.take()) {
            (Some(_), Some(block)) => blocks.push(block),
            (Some(info), None) => {
                open = Some(Block {
                    place: format!("{name}:{}", i + 1),
                    info: info.trim().to_owned(),
                    body: String::new(),
                })
            }
            (None, Some(mut block)) => {
                block.body.push_str(line);
                block.body.push('\n');
                open = Some(block);
            }
            (None, None) => {}
        }
    }
    assert!(open.is_none(), "{name}: a fence is never closed");
    blocks
}

fn every_block() -> Vec<Block> {
    pages().iter().flat_map(|p| blocks(p)).collect()
}

/// The block as the suite runs it: the binary under test for `cargo run`.
fn as_run(body: &str) -> String {
    body.replace("cargo run --release -- ", "ubf ")
        .replace("./target/release/ubf ", "ubf ")
        .replace("cargo build --release\n", "")
}

/// The words of each `ubf` command line in a shell block, without
/// redirections, pipes, background `&` and comments.
fn ubf_commands(body: &str) -> Vec<Vec<String>> {
    // Lines continued with a backslash are one command, as in a shell; a
    // shell variable (`"$SLURM_ARRAY_TASK_ID/100"`) stands for 1, its
    // quotes for nothing, so that the rest of the line is still checked.
    let joined = as_run(body).replace("\\\n", " ");
    let mut plain = String::new();
    let mut chars = joined.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' => {}
            '$' => {
                while chars.peek().is_some_and(|c| c.is_ascii_alphanumeric() || *c == '_') {
                    chars.next();
                }
                plain.push('1');
            }
            c => plain.push(c),
        }
    }
    plain
        .lines()
        .filter_map(|line| {
            let line = line.split(" #").next()?.split(['|', '&']).next()?;
            let words: Vec<String> =
                line.split_whitespace().filter(|w| !w.starts_with("2>")).map(str::to_owned).collect();
            (words.first()? == "ubf").then(|| words[1..].to_vec())
        })
        .collect()
}

/// Numbers stand for any number, spacing for any spacing.
fn shape(text: &str) -> Vec<String> {
    text.lines()
        .map(|line| {
            let mut out = String::new();
            let mut chars = line.chars().peekable();
            while let Some(c) = chars.next() {
                if c.is_ascii_digit() {
                    while chars.peek().is_some_and(|c| c.is_ascii_digit() || *c == '.' || *c == 'e') {
                        chars.next();
                    }
                    out.push('#');
                } else {
                    out.push(c);
                }
            }
            out.split_whitespace().collect::<Vec<_>>().join(" ")
        })
        .filter(|line| !line.is_empty())
        .collect()
}

#[test]
fn every_shell_block_is_marked_and_every_output_follows_a_run() {
    let mut last_shell: Option<String> = None;
    for block in every_block() {
        match (block.language(), block.mark()) {
            ("sh", "run" | "run-slow") => last_shell = Some(block.mark().to_owned()),
            ("sh", mark) => {
                assert!(
                    mark.starts_with("no-run:"),
                    "{}: mark it `sh run`, `sh run-slow` or `sh no-run: why`",
                    block.place
                );
                last_shell = None;
            }
            ("text", "output") => {
                assert!(last_shell.is_some(), "{}: an output block must follow a `sh run` block", block.place)
            }
            _ => {}
        }
    }
}

#[test]
fn every_ubf_command_the_docs_show_is_accepted() {
    let mut checked = 0;
    for block in every_block().iter().filter(|b| b.language() == "sh") {
        for words in ubf_commands(&block.body) {
            if let Err(e) = ubf::cli::parses(&words) {
                panic!("{}: `ubf {}` is refused:\n{e}", block.place, words.join(" "));
            }
            checked += 1;
        }
    }
    assert!(checked > 20, "only {checked} commands found: is the extraction broken?");
}

#[test]
fn every_ron_block_loads() {
    let registry = ubf::registry();
    let dir = tempfile::tempdir().unwrap();
    let mut loaded = 0;
    for block in every_block().iter().filter(|b| b.language() == "ron" && b.mark() != "fragment") {
        let text = block.body.trim_start();
        if text.starts_with("Scenario(") {
            if let Err(e) = ubf::scenario::Scenario::from_ron(&registry, text) {
                panic!("{}: {e}", block.place);
            }
        } else if text.starts_with("RobotConfig(") {
            // In a robots/ of its own beside links to the repository's
            // models, where its model is found: written into the
            // repository's robots/config/, it was there for the scratch
            // copy of another test to list and then miss.
            let robots = dir.path().join("robots");
            std::fs::create_dir_all(robots.join("config")).unwrap();
            if !robots.join("models").exists() {
                link_entries(&root().join("robots"), &robots, &["config"]);
            }
            let file = robots.join("config/docs.ron");
            std::fs::write(&file, text).unwrap();
            let result = ubf::drive::DriveConfig::load(&registry, &file);
            if let Err(e) = result {
                panic!("{}: {e}", block.place);
            }
        } else {
            panic!("{}: a `ron` block is a Scenario or a RobotConfig, or is marked `ron fragment`", block.place);
        }
        loaded += 1;
    }
    drop(dir);
    assert!(loaded >= 2, "only {loaded} files found");
}

/// The address the pages serve ARCOS on, replaced in the scratch copy.
const DOCS_ARCOS_ADDRESS: &str = "127.0.0.1:8101";

/// A scratch copy of the repository: its top-level entries linked, `docs/`
/// copied (a command may redraw a figure there), `robots/config/` copied
/// with [`DOCS_ARCOS_ADDRESS`] replaced by a free port's, nothing else
/// written.
struct Scratch {
    dir: tempfile::TempDir,
    /// What stands for [`DOCS_ARCOS_ADDRESS`].
    arcos_address: String,
}

impl Scratch {
    fn path(&self) -> &Path {
        self.dir.path()
    }

    /// `body` with the pages' ports replaced by the scratch copy's.
    fn localize(&self, body: &str) -> String {
        body.replace(DOCS_ARCOS_ADDRESS, &self.arcos_address)
    }
}

/// A loopback address with a port nobody held a moment ago.
fn free_address() -> String {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    listener.local_addr().unwrap().to_string()
}

/// Links every entry of `from` into `to` except `skip`.
fn link_entries(from: &Path, to: &Path, skip: &[&str]) {
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap();
        if skip.iter().any(|skip| name == *skip) {
            continue;
        }
        std::os::unix::fs::symlink(&path, to.join(name)).unwrap();
    }
}

fn scratch() -> Scratch {
    let scratch = Scratch { dir: tempfile::tempdir().unwrap(), arcos_address: free_address() };
    let dir = scratch.path();
    link_entries(root(), dir, &[".git", "out", "docs", "robots"]);
    std::fs::create_dir(dir.join("docs")).unwrap();
    for entry in std::fs::read_dir(root().join("docs")).unwrap() {
        let path = entry.unwrap().path();
        let to = dir.join("docs").join(path.file_name().unwrap());
        match path.is_dir() {
            true => std::os::unix::fs::symlink(&path, to).unwrap(),
            false => drop(std::fs::copy(&path, to).unwrap()),
        }
    }
    std::fs::create_dir(dir.join("robots")).unwrap();
    link_entries(&root().join("robots"), &dir.join("robots"), &["config"]);
    std::fs::create_dir(dir.join("robots/config")).unwrap();
    for entry in std::fs::read_dir(root().join("robots/config")).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(dir.join("robots/config").join(path.file_name().unwrap()), scratch.localize(&text)).unwrap();
    }
    let bin = dir.join(".bin");
    std::fs::create_dir(&bin).unwrap();
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_ubf"), bin.join("ubf")).unwrap();
    scratch
}

/// Runs a block's commands with `sh -e` in `dir`, stderr into stdout, and
/// stops everything it started (a server sent to the background) when it
/// ends or after `limit`. Returns the status and the output.
fn run_block(dir: &Path, body: &str, limit: Duration) -> (i32, String) {
    use std::os::unix::process::CommandExt;
    let path = format!("{}:{}", dir.join(".bin").display(), std::env::var("PATH").unwrap_or_default());
    let target = root().join("target");
    let mut child = Command::new("sh")
        .arg("-ec")
        .arg(format!("exec 2>&1\n{}", as_run(body)))
        .current_dir(dir)
        .env("PATH", path)
        .env("CARGO_TARGET_DIR", target)
        .env("RUST_BACKTRACE", "0")
        .env_remove("RUST_LOG")
        .stdout(std::process::Stdio::piped())
        .stdin(std::process::Stdio::null())
        .process_group(0)
        .spawn()
        .unwrap();
    let group = child.id() as i32;
    let reader = {
        let mut stdout = child.stdout.take().unwrap();
        std::thread::spawn(move || {
            let mut out = String::new();
            let _ = std::io::Read::read_to_string(&mut stdout, &mut out);
            out
        })
    };
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code().unwrap_or(-1);
        }
        if started.elapsed() > limit {
            break -1;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    // The block's background servers, and the block itself if it overran.
    let _ = Command::new("kill").arg("--").arg(format!("-{group}")).stderr(std::process::Stdio::null()).status();
    let _ = child.wait();
    (status, reader.join().unwrap())
}

/// Runs every block marked `mark`, each with the output block after it.
fn run_marked(mark: &str, limit: Duration) {
    let dir = scratch();
    let blocks = every_block();
    let mut ran = 0;
    for (i, block) in blocks.iter().enumerate() {
        if block.language() != "sh" || block.mark() != mark {
            continue;
        }
        let (status, output) = run_block(dir.path(), &dir.localize(&block.body), limit);
        assert_eq!(status, block.expected_status(), "{}: exit status {status}; output:\n{output}", block.place);
        if let Some(expected) = blocks.get(i + 1).filter(|b| b.info == "text output") {
            assert_eq!(
                shape(&output),
                shape(&expected.body),
                "{}: the output differs from {} in shape:\n{output}",
                block.place,
                expected.place
            );
        }
        ran += 1;
    }
    assert!(ran > 0, "no `sh {mark}` block found");
}

#[test]
fn every_runnable_block_runs_and_prints_what_the_docs_show() {
    // A guard against a block that hangs, not a bound on its time: the
    // whole test took 187 s beside an experiment, and one block overran
    // 300 s beside two experiments and the suite's own builds.
    run_marked("run", Duration::from_secs(900));
}

#[test]
#[ignore = "minutes: benchmarks, long experiments, installing OpenCV"]
fn every_slow_block_runs() {
    run_marked("run-slow", Duration::from_secs(3600));
}

#[test]
fn the_shape_of_an_output_ignores_numbers_and_spacing_only() {
    assert_eq!(shape("distance   8.36 m\n\nwall time 0.000 s"), shape("distance 12 m\nwall time 1.5 s"));
    assert_ne!(shape("goal reached    yes"), shape("goal reached    no"));
    assert_eq!(
        ubf_commands("cargo run --release -- run a.ron -vvv 2>&1 | head -3  # note\n"),
        vec![vec!["run".to_owned(), "a.ron".into(), "-vvv".into()]]
    );
}

#[test]
fn the_behaviour_tables_are_the_behaviours_own_descriptions() {
    let page = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scenario-format.md")).unwrap();
    let registry = ubf::registry();
    for name in registry.names() {
        let heading = format!("### `{name}`\n");
        let at = page.find(&heading).unwrap_or_else(|| panic!("docs/scenario-format.md has no section {heading}"));
        let table_start = at + page[at..].find("\n| field").expect("a table under the heading") + 1;
        let table: String =
            page[table_start..].lines().take_while(|l| l.starts_with('|')).map(|l| format!("{l}\n")).collect();
        let expected = ubf_core::markdown_table(registry.fields(name).unwrap());
        assert!(
            table == expected,
            "docs/scenario-format.md, `{name}`: the table differs from the behaviour's description \
             (`ubf behaviors --describe {name}`); it should read:\n{expected}"
        );
    }
}
