//! The `quadcl` binary: parse the command line, show the library's warnings
//! on stderr, and dispatch. The command line (`cli`), one file per subcommand
//! (`cmd`) and the benchmarks (`bench`) live here, outside the library.

mod bench;
mod cli;
mod cmd;
mod stderr_log;

use clap::Parser;

fn main() -> std::process::ExitCode {
    // Only fails if a subscriber is already set, which nothing else does.
    let _ = tracing::subscriber::set_global_default(stderr_log::StderrLog::new(std::io::stderr()));
    let cli = cli::Cli::parse();
    match cli::dispatch(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
