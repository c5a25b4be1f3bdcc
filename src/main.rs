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

/// Each minibatch allocates and frees the same large buffers (candle's tensors of
/// activations and gradients, hundreds of KB to MB each). glibc serves a block
/// above its mmap threshold by a fresh mmap, and trims the top of a heap above
/// 128 KB back to the kernel on free, so the next minibatch faults the pages in
/// again, zeroed, and munmap shoots down the other core's TLB: 165,000-470,000
/// page faults and 1.0-4.1 s of system time in 12 iterations of the base config
/// (`perf stat -e page-faults`). With the mmap threshold at glibc's 64-bit
/// ceiling (32 MiB) and trimming only above 512 MiB, freed blocks are reused:
/// 38,000-39,000 faults and 0.5-0.7 s of system time, for a peak memory 2-10 MB
/// higher (60 iterations: 172 -> 174 MB). The numbers trained do not change. Either value set by the user
/// (`MALLOC_MMAP_THRESHOLD_`, `MALLOC_TRIM_THRESHOLD_`) is kept.
fn reuse_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        if std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_none() && std::env::var_os("MALLOC_TRIM_THRESHOLD_").is_none()
        {
            // SAFETY: mallopt only sets allocator parameters; called before any other thread starts.
            unsafe {
                libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
                libc::mallopt(libc::M_TRIM_THRESHOLD, 512 << 20);
            }
        }
    }
}

fn main() -> std::process::ExitCode {
    keep_candle_kernels_on_the_calling_thread();
    reuse_freed_memory();
    // Only fails if a subscriber is already set, which nothing else does.
    let _ = tracing::subscriber::set_global_default(stderr_log::StderrLog::new(std::io::stderr()));
    let cli = cli::Cli::parse();
    match cli::dispatch(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            // Each cause once, no value echoed whole (see quadcl::util::text::error_text).
            eprintln!("error: {}", quadcl::util::text::error_text(&err));
            std::process::ExitCode::FAILURE
        }
    }
}
