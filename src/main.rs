//! The `raycost` binary: parse arguments, run, and turn errors into exit codes
//! (0 success, 2 bad input or usage, 1 internal failure).

use std::process::ExitCode;

use clap::Parser;
use raycost::app;
use raycost::cli::Cli;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match app::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // A closed pipe (`raycost theory … | head`) is not a failure.
            if e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>()
                    .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            }) {
                return ExitCode::SUCCESS;
            }
            eprintln!("error: {e:#}");
            ExitCode::from(app::exit_code(&e))
        }
    }
}
