//! The `pendula` command; everything it does is in the library target (`src/lib.rs`).

fn main() -> std::process::ExitCode {
    pendula_cli::run()
}
