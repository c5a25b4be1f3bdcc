//! `quadcl finetune --policy DIR --task TASK --shift FILE --out DIR`:
//! sim-to-real fine-tuning of one learned task (METHOD.md 2.7, see
//! `engine::sim2real`). Prints the task's evaluation before and after, and
//! checks that no other task changed.

use clap::Args;
use quadcl::config::bounds;
use quadcl::config::ppo::{check_env_count, MAX_ITERATIONS};
use quadcl::engine::Shift;
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct FinetuneArgs {
    /// Policy directory (e.g. a run's last checkpoint).
    #[arg(long)]
    pub policy: PathBuf,
    /// The learned task to fine-tune (`crash:FL`, ...).
    #[arg(long)]
    pub task: String,
    /// Shift file (TOML): friction, added_mass, motor_strength, latency_s, iterations.
    #[arg(long)]
    pub shift: PathBuf,
    /// New policy directory to write (created).
    #[arg(long)]
    pub out: PathBuf,
    /// Override the shift file's iterations.
    #[arg(long)]
    pub iterations: Option<usize>,
    /// Seed of the fine-tuning and evaluation streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Evaluation episodes per task.
    #[arg(long, default_value_t = 16)]
    pub episodes: usize,
}

pub fn run(args: FinetuneArgs) -> anyhow::Result<()> {
    let mut shift = Shift::load(&args.shift)?;
    if let Some(n) = args.iterations {
        bounds::check_count("--iterations", n, 1, MAX_ITERATIONS)?;
        shift.iterations = n;
    }
    check_env_count("--episodes", args.episodes)?;
    let r = quadcl::engine::sim2real(
        &args.policy,
        &args.task,
        &shift,
        &args.out,
        args.seed,
        args.episodes,
        std::io::stderr().is_terminal(),
    )?;
    let find = |v: &[quadcl::engine::Evaluation]| v.iter().find(|e| e.report.task == r.task).cloned();
    if let (Some(b), Some(a)) = (find(&r.before), find(&r.after)) {
        println!(
            "{}: performance {:.4} -> {:.4}, lin_vel_err {:.3} -> {:.3}, fall_rate {:.3} -> {:.3}",
            r.task,
            b.performance,
            a.performance,
            b.report.lin_vel_err,
            a.report.lin_vel_err,
            b.report.fall_rate,
            a.report.fall_rate
        );
    }
    anyhow::ensure!(
        r.changed_other_tasks.is_empty(),
        "other tasks changed: {:?} (a bug: fine-tuning must not touch them)",
        r.changed_other_tasks
    );
    println!(
        "{} other tasks unchanged (bit-identical evaluations); new policy in {}",
        r.before.len() - 1,
        args.out.display()
    );
    Ok(())
}
