//! `quadcl record --policy DIR --task T --seconds S --out FILE.mcap [--episodes N]
//! [--vx V --vy V --wz W] [--force]`: a policy's episodes on a task into a file
//! (see `record::record_episodes`), then a line saying what was written.

use clap::Args;
use quadcl::record::{record_episodes, RecordOptions};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct RecordArgs {
    /// Policy directory (any form `quadcl eval` takes: a policy, a training checkpoint, a sequence's checkpoint).
    #[arg(long)]
    pub policy: PathBuf,
    /// Task to run on: `none`, `crash:FL`, ...
    #[arg(long, default_value = "none")]
    pub task: String,
    /// Simulated seconds at most.
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Stop after this many finished episodes (falls or time-outs).
    #[arg(long)]
    pub episodes: Option<u64>,
    /// Output file: `.mcap` (Foxglove).
    #[arg(long)]
    pub out: PathBuf,
    /// Hold this forward velocity command, m/s (with --vy and --wz; without any, the env's random commands).
    #[arg(long, allow_hyphen_values = true)]
    pub vx: Option<f32>,
    /// Held lateral velocity command, m/s.
    #[arg(long, allow_hyphen_values = true)]
    pub vy: Option<f32>,
    /// Held yaw rate command, rad/s.
    #[arg(long, allow_hyphen_values = true)]
    pub wz: Option<f32>,
    /// Seed of the environment's reset.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Replace an existing --out file.
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: RecordArgs) -> anyhow::Result<()> {
    let held = args.vx.is_some() || args.vy.is_some() || args.wz.is_some();
    let command = held.then(|| [args.vx.unwrap_or(0.0), args.vy.unwrap_or(0.0), args.wz.unwrap_or(0.0)]);
    let options =
        RecordOptions { seconds: args.seconds, episodes: args.episodes, command, seed: args.seed, force: args.force };
    let s = record_episodes(&args.policy, &args.task, &args.out, &options)?;
    println!(
        "recorded {} control steps ({:.1} s simulated, {} episodes ended) of {} into {} ({:.1} MB) in {:.1} s",
        s.control_steps,
        s.sim_seconds,
        s.episodes,
        args.task,
        args.out.display(),
        s.bytes as f64 / 1e6,
        s.wall_seconds
    );
    Ok(())
}
