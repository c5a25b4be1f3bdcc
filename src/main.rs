//! The `quadcl` binary: parse the command line and dispatch.

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = quadcl::cli::Cli::parse();
    match quadcl::cli::dispatch(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
