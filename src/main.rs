//! The `fieldhouse` binary: parses the command line and hands off to the library.
//! Everything it does lives in [`cli`]; the simulation itself is in the library.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
