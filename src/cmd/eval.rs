//! `quadcl eval --policy DIR --task TASK [--episodes N] [--seed S] [--video DIR] --json`:
//! one episode per environment with the deterministic policy, random
//! commands from the env config (vx in [-1, 1] m/s, wz in [-pi/2, pi/2] rad/s
//! by default) and the training config's randomisation and pushes (`--no-pushes`
//! turns the pushes off; `--push-interval-s` and `--push-max-vel` set another
//! push regime, e.g. to score policies trained under different pushes on the
//! same test); prints mean return, normalised performance (over the best return a task
//! allows, as metrics.json has it), tracking errors, fall rate, survival, and which learned
//! task's network acted (`recalls`: a task the policy never learned is run zero-shot with its
//! last learned task's). `--video DIR` adds `DIR/TASK.mp4` of the policy on the task.
//! `--policy-cmd CMD` takes the actions from another program instead (an exported
//! model in ONNX Runtime: `rl::ExternalPolicy` says the protocol), in the
//! environments the policy directory's config describes.

use clap::Args;
use quadcl::config::bounds::{self, NON_NEGATIVE};
use quadcl::record::{record_video, RecordOptions, VideoSize};
use quadcl::rl::SimTrainEnv;
use quadcl::sim::Perturbation;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Policy directory written by `quadcl train` (or its `checkpoint/`, evaluated as if the
    /// task ended at that iteration).
    #[arg(long)]
    pub policy: PathBuf,
    /// Task to evaluate on: `none`, `crash:FL`, ...
    #[arg(long, default_value = "none")]
    pub task: String,
    /// Episodes (one per parallel environment).
    #[arg(long, default_value_t = 32)]
    pub episodes: usize,
    /// Seed of the evaluation environments (commands, randomisation).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Evaluate without the training pushes (by default the env config's pushes stay on,
    /// so a fall rate includes push recovery; this separates tracking from it).
    #[arg(long, conflicts_with_all = ["push_interval_s", "push_max_vel"])]
    pub no_pushes: bool,
    /// Seconds between pushes instead of the training config's `env.push_interval_s`
    /// (0 turns them off).
    #[arg(long, value_name = "S")]
    pub push_interval_s: Option<f32>,
    /// Largest push (a change of the trunk's horizontal velocity, m/s, uniform per axis)
    /// instead of the training config's `env.push_max_vel`.
    #[arg(long, value_name = "M_PER_S")]
    pub push_max_vel: Option<f32>,
    /// Take the actions from this program instead of the policy's networks (run with `sh -c`;
    /// it reads observation histories and writes actions as little-endian f32 on its standard
    /// input and output, e.g. `python3 scripts/policy_server.py task.onnx`). The policy directory
    /// still gives the environment.
    #[arg(long, value_name = "CMD")]
    pub policy_cmd: Option<String>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Also write a video of the policy on the task into this folder (`TASK.mp4`, 10 s at
    /// 480 x 360, the evaluation's seed and random commands, no pushes; through ffmpeg).
    #[arg(long, value_name = "DIR")]
    pub video: Option<PathBuf>,
}

pub fn run(args: EvalArgs) -> anyhow::Result<()> {
    quadcl::config::ppo::check_env_count("--episodes", args.episodes)?;
    let task: Perturbation = args.task.parse()?;
    // A policy trained on several tasks recalls the one asked for; a single-task
    // policy (the base policy) is evaluated on any perturbation.
    let loaded = quadcl::rl::load_for_task(&args.policy, &task.to_string())?;
    let agent = &loaded.agent;
    let mut env_cfg = loaded.info.config.env.clone();
    if args.no_pushes {
        env_cfg.push_interval_s = 0.0;
    }
    if let Some(s) = args.push_interval_s {
        bounds::check("--push-interval-s", s, NON_NEGATIVE)?;
        env_cfg.push_interval_s = s;
    }
    if let Some(v) = args.push_max_vel {
        bounds::check("--push-max-vel", v, NON_NEGATIVE)?;
        env_cfg.push_max_vel = v;
    }
    let env_cfg = &env_cfg;
    let mut env = SimTrainEnv::new(env_cfg, &task, args.episodes, args.seed)?;
    let max_steps = env_cfg.evaluation_step_bound();
    let report = match &args.policy_cmd {
        None => quadcl::rl::evaluate(agent, &mut env, &task.to_string(), args.seed, max_steps)?,
        Some(command) => {
            let mut program = quadcl::rl::ExternalPolicy::spawn(command, agent.dims(), args.episodes)?;
            let mut policy = |_: &[f32], histories: &[f32]| program.act(histories);
            let report = quadcl::rl::evaluate_with(&mut policy, &mut env, &task.to_string(), args.seed, max_steps)?;
            program.finish()?;
            report
        }
    };
    // Normalised performance as metrics.json's evaluations have it (METHOD.md 4).
    let mut value = serde_json::to_value(&report)?;
    let fields = value.as_object_mut().expect("a struct serialises to an object");
    fields.insert("performance".into(), (report.mean_return / quadcl::engine::max_episode_return(env_cfg)).into());
    // Which learned task's network acted: the task asked for, or (a task the policy never
    // learned: zero-shot) its last learned one.
    fields.insert("recalls".into(), loaded.recalled_task().into());
    if let Some(dir) = &args.video {
        let out = dir.join(format!("{}.mp4", quadcl::engine::task_file_name(&task.to_string())));
        let options = RecordOptions { seconds: 10.0, episodes: None, command: None, seed: args.seed, force: true };
        record_video(&args.policy, &[task.to_string()], &out, VideoSize::default(), &options)?;
        fields.insert("video".into(), out.display().to_string().into());
    }
    if args.json {
        println!("{value}");
    } else {
        for (key, v) in fields.iter() {
            println!("{key:<14} {v}");
        }
    }
    Ok(())
}
