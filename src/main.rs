//! The `quadcl` binary: parse the command line, show the library's warnings
//! on stderr, and dispatch. The command line (`cli`), one file per subcommand
//! (`cmd`) and the benchmarks (`bench`) live here, outside the library.

mod bench;
mod cli;
mod cmd;
mod stderr_log;

use clap::Parser;

/// candle runs its large element-wise kernels on a pool of its own (one worker per
/// further core) whose threads spin between kernels. quadcl already keeps both
/// cores busy from rayon (the networks' branches of the update, the envs), so
/// that pool only competes with it: with it off (`CANDLE_NUM_THREADS=1`, which
/// sizes nothing else) the kernels run on the calling thread and the PPO
/// update of the base config took about 20 % less time while other work shared
/// the machine (`quadcl bench --only ppo`). A value set by the user is kept.
fn keep_candle_kernels_on_the_calling_thread() {
    if std::env::var_os("CANDLE_NUM_THREADS").is_none() {
        // Before any thread is started, so no other thread reads the environment.
        std::env::set_var("CANDLE_NUM_THREADS", "1");
    }
}

fn main() -> std::process::ExitCode {
    keep_candle_kernels_on_the_calling_thread();
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
