//! The `raycost` binary: parse arguments, run, and turn the error's variant into the exit code
//! (`raycost::error::Error::exit_code`: 0 success, 2 bad input or usage, 1 failure, 130 Ctrl-C).

use std::process::ExitCode;

use clap::Parser;
use raycost::app;
use raycost::cli::Cli;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match app::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let code = e.exit_code();
            if code != 0 {
                eprintln!("error: {e:#}");
            }
            ExitCode::from(code)
        }
    }
}
