//! What the command-line tests share: `ubf` processes that never outlive
//! a failed assertion, and the Powerbot emulator they drive.
#![allow(dead_code)] // each test file uses its own part

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// A child process killed when dropped, so a failed assertion never leaves
/// an emulator running (holding the test's output open).
pub struct Killed(pub Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

impl std::ops::Deref for Killed {
    type Target = Child;
    fn deref(&self) -> &Child {
        &self.0
    }
}

impl std::ops::DerefMut for Killed {
    fn deref_mut(&mut self) -> &mut Child {
        &mut self.0
    }
}

pub fn emulator() -> (Killed, String, BufReader<std::process::ChildStdout>) {
    emulator_with(&["--listen", "127.0.0.1:0"])
}

/// `ubf emulate-powerbot ARGS`, with the address it serves on.
pub fn emulator_with(args: &[&str]) -> (Killed, String, BufReader<std::process::ChildStdout>) {
    let (child, line, out) = serve("emulate-powerbot", args);
    assert!(line.starts_with("emulating a Powerbot on "), "{line}");
    (child, line.rsplit(' ').next().unwrap().to_owned(), out)
}

/// `ubf emulate-ptu --listen 127.0.0.1:0`, with the address it serves on.
pub fn ptu_emulator() -> (Killed, String, BufReader<std::process::ChildStdout>) {
    let (child, line, out) = serve("emulate-ptu", &["--listen", "127.0.0.1:0"]);
    (child, line.rsplit(' ').next().unwrap().to_owned(), out)
}

/// `ubf COMMAND ARGS`, with the first line it prints (where it serves).
fn serve(command: &str, args: &[&str]) -> (Killed, String, BufReader<std::process::ChildStdout>) {
    let mut child =
        Command::new(env!("CARGO_BIN_EXE_ubf")).arg(command).args(args).stdout(Stdio::piped()).spawn().unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    (Killed(child), line.trim().to_owned(), out)
}

/// The test sweep's arguments (two scenarios, seeds 3..=14) into `out`,
/// with `extra`.
pub fn sweep_args<'a>(out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "sweep",
        "scenarios/corridor-box.ron",
        "scenarios/goto-open-floor.ron",
        "--seeds",
        "3..=14",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    args
}

/// Waits up to `seconds` for `child` to exit.
pub fn wait_for(child: &mut Child, seconds: f64) -> Option<std::process::ExitStatus> {
    let deadline = std::time::Instant::now() + Duration::from_secs_f64(seconds);
    while std::time::Instant::now() < deadline {
        if let Some(status) = child.try_wait().unwrap() {
            return Some(status);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    None
}
