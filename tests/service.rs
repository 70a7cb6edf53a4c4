//! The systemd unit in `deploy/` is one systemd accepts: `systemd-analyze
//! verify` (systemd's own checker, which `scripts/install-test-deps.sh`
//! installs) passes on it, with `ExecStart` pointed at the binary under
//! test, and its sandboxing keeps `systemd-analyze security`'s exposure
//! score at the level docs/deploy.md gives.

use std::process::Command;

/// The unit, with its `ExecStart` at the binary under test, in a scratch
/// folder; the folder and the unit's path.
fn unit() -> (tempfile::TempDir, std::path::PathBuf) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("deploy/ubf-drive.service")).unwrap();
    assert!(text.contains("ExecStart=/usr/local/bin/ubf drive"), "the unit names the installed binary");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ubf-drive.service");
    std::fs::write(&path, text.replace("/usr/local/bin/ubf", env!("CARGO_BIN_EXE_ubf"))).unwrap();
    (dir, path)
}

fn analyze(args: &[&str], unit: &std::path::Path) -> std::process::Output {
    Command::new("systemd-analyze").args(args).arg(unit).output().unwrap_or_else(|e| {
        panic!("systemd-analyze: {e}; scripts/install-test-deps.sh installs it (Debian package systemd)")
    })
}

#[test]
fn systemd_accepts_the_service_unit() {
    let (_dir, path) = unit();
    let out = analyze(&["verify"], &path);
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && said.trim().is_empty(), "{said}");
}

#[test]
fn the_service_unit_is_sandboxed() {
    let (_dir, path) = unit();
    let out = analyze(&["security", "--offline=yes"], &path);
    let said = String::from_utf8_lossy(&out.stdout);
    let score: f64 = said
        .lines()
        .find_map(|l| l.split("Overall exposure level for ubf-drive.service: ").nth(1))
        .and_then(|rest| rest.split_whitespace().next()?.parse().ok())
        .unwrap_or_else(|| panic!("no score in: {said}{}", String::from_utf8_lossy(&out.stderr)));
    // docs/deploy.md gives 1.5; 10 is a unit with no sandboxing at all.
    assert!(score <= 2.0, "exposure {score}: {said}");
}
