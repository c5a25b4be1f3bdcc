//! `quadcl train --config FILE --out DIR`: trains one task (default `none`,
//! the unperturbed robot) with PPO + CENet and writes `config.toml`,
//! `metrics.jsonl`, `summary.json`, `policy/` and `tb/` (TensorBoard events and a CSV of
//! the same scalars; `--no-tb` leaves it out) into DIR.

use clap::Args;
use quadcl::config::Config;
use quadcl::rl::SimTrainEnv;
use quadcl::sim::Perturbation;
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Experiment config (TOML); keys it leaves out keep their defaults.
    #[arg(long)]
    pub config: PathBuf,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
    /// Task to train: `none`, `crash:FL`, `invert:RR+noise:FR`, ...
    #[arg(long, default_value = "none")]
    pub task: String,
    /// Override the number of iterations of the config.
    #[arg(long)]
    pub iterations: Option<usize>,
    /// Override the master seed of the config.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Go on from DIR/checkpoint/ (written every `ppo.checkpoint_every`
    /// iterations) with the same config; `--iterations` may raise the total.
    /// The run goes on bit for bit as if it had not stopped (timing fields aside).
    #[arg(long, conflicts_with = "force")]
    pub resume: bool,
    /// Train anew into an --out that already holds a training run, replacing its results.
    #[arg(long)]
    pub force: bool,
    /// Write no TensorBoard events or CSV (DIR/tb/).
    #[arg(long)]
    pub no_tb: bool,
}

/// What in `out` says it holds a training run already.
fn existing_run(out: &std::path::Path) -> Option<&'static str> {
    ["metrics.jsonl", "policy", "checkpoint", "summary.json"].into_iter().find(|name| out.join(name).exists())
}

pub fn run(args: TrainArgs) -> anyhow::Result<()> {
    let mut config = Config::load(&args.config)?;
    if let Some(iterations) = args.iterations {
        quadcl::config::bounds::check_count("--iterations", iterations, 1, quadcl::config::ppo::MAX_ITERATIONS)?;
        config.ppo.iterations = iterations;
    }
    if let Some(seed) = args.seed {
        config.seed = seed;
    }
    let task: Perturbation = args.task.parse()?;
    let task_name = task.to_string();
    // One training at a time in --out, held until this command returns.
    let _lock = quadcl::engine::lock_folder(&args.out)?;
    if let Some(found) = existing_run(&args.out).filter(|_| !args.resume && !args.force) {
        anyhow::bail!(
            "{} already holds a training run ({found}): --resume continues it, --force replaces it, or choose another --out",
            args.out.display()
        );
    }
    let resume = if args.resume { Some(quadcl::rl::load_resume_point(&config, &task_name, &args.out)?) } else { None };
    // An exact checkpoint restores every env's state over fresh ones; an older one reseeds them.
    let env_seed = match &resume {
        Some(point) if !point.is_exact() => {
            quadcl::util::derive_seed(config.seed, quadcl::util::Stream::Trainer(point.state.iteration))
        }
        _ => config.seed,
    };
    let mut env = SimTrainEnv::new(&config.env, &task, config.ppo.num_envs, env_seed)?;
    let progress = std::io::stderr().is_terminal();
    let summary = quadcl::rl::train_from(&config, &task_name, &mut env, &args.out, progress, !args.no_tb, resume)?;
    let report = serde_json::json!({
        "task": task.to_string(),
        "iterations": summary.iterations,
        "env_steps": summary.env_steps,
        "wall_s": summary.wall_s,
        "env_steps_per_s": summary.env_steps as f64 / summary.wall_s.max(1e-9),
        "time_env_s": summary.env_s,
        "time_policy_s": summary.policy_s,
        "time_update_s": summary.update_s,
        "threads": rayon::current_num_threads(),
        "last": summary.last,
    });
    quadcl::util::write_atomic(&args.out.join("summary.json"), serde_json::to_string_pretty(&report)?.as_bytes())?;
    eprintln!(
        "trained {} iterations ({} env steps) in {:.0} s: physics {:.0} s, policy forward {:.0} s, updates {:.0} s; policy in {}",
        summary.iterations,
        summary.env_steps,
        summary.wall_s,
        summary.env_s,
        summary.policy_s,
        summary.update_s,
        args.out.join("policy").display()
    );
    Ok(())
}
