//! The `loops` binary: the command of the `loops_cli` library, with the process's arguments.

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(loops_cli::main(std::env::args_os()))
}
