//! The `ubf` command: run `ubf --help`.

fn main() -> std::process::ExitCode {
    ubf::cli::main_with(ubf::registry())
}
