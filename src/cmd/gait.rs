//! `quadcl gait --policy DIR [--task TASK] [--vx 0.5] [--wz 0] [--seconds 10] [--json]`:
//! runs the deterministic policy with one command held (no pushes, nominal
//! physics) and prints its contact pattern: duty factors, touchdowns per
//! second, which feet move together and the gait they name (`rl::gait`).

use clap::Args;
use quadcl::config::bounds::{self, Interval};
use quadcl::config::env::check_command;
use quadcl::rl::{record_gait, GaitReport, HeldCommand};
use quadcl::sim::{Perturbation, RobotModel};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct GaitArgs {
    /// Policy directory (or a training run's `checkpoint/`).
    #[arg(long)]
    pub policy: PathBuf,
    /// Task to run on: `none`, `crash:FL`, ...
    #[arg(long, default_value = "none")]
    pub task: String,
    /// Forward velocity command, m/s (in [-10, 10]).
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub vx: f32,
    /// Yaw rate command, rad/s (in [-10, 10]).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub wz: f32,
    /// Seconds recorded, after 2 s to settle into the gait (at most 3600: one contact row a step is kept).
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f32,
    /// Seed of the environment's reset.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: GaitArgs) -> anyhow::Result<()> {
    let seconds = Interval::OpenClosed(0.0, quadcl::record::MAX_SECONDS);
    bounds::check("--seconds", args.seconds, seconds)?;
    check_command("--vx", args.vx)?;
    check_command("--wz", args.wz)?;
    let task: Perturbation = args.task.parse()?;
    let loaded = quadcl::rl::load_for_task(&args.policy, &task.to_string())?;
    let env_cfg = &loaded.info.config.env;
    let robot = RobotModel::for_config(env_cfg)?;
    let report = record_gait(
        &loaded.agent,
        env_cfg,
        &robot,
        &task,
        HeldCommand { command: [args.vx, 0.0, args.wz], warmup_s: 2.0, seconds: args.seconds, seed: args.seed },
    )?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        print_table(&report);
    }
    Ok(())
}

fn print_table(report: &GaitReport) {
    let r = &report.contacts;
    let feet =
        |v: &[f32; 4], unit: &str| format!("FL {:.2}  FR {:.2}  RL {:.2}  RR {:.2}{unit}", v[0], v[1], v[2], v[3]);
    println!("command        vx {:.2} m/s, wz {:.2} rad/s", report.command[0], report.command[2]);
    let fell = if report.fell { " (fell)" } else { "" };
    println!(
        "achieved       vx {:.2} m/s, wz {:.2} rad/s over {:.1} s{fell}",
        report.mean_vx, report.mean_wz, report.seconds
    );
    println!("duty factor    {}", feet(&r.duty_factor, ""));
    println!("touchdowns     {}", feet(&r.touchdowns_per_s, " per s"));
    println!(
        "same state     diagonal {:.2}, lateral {:.2}, fore-aft {:.2}",
        r.diagonal_agreement, r.lateral_agreement, r.fore_aft_agreement
    );
    println!("gait           {}", r.gait);
    println!("last 2 s       (# on the ground, . in the air; one character per 20 ms)");
    for line in &report.contact_strip {
        println!("  {line}");
    }
}
