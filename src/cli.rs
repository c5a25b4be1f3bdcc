//! The command line: one clap subcommand per job; each is implemented in its
//! own file under `cmd/`.

use clap::{Parser, Subcommand};

/// quadcl: continual reinforcement learning on a simulated quadruped.
///
/// Train one policy on a sequence of locomotion tasks (broken, inverted or
/// noisy legs) with per-task binary masks, so that no task is forgotten.
#[derive(Debug, Parser)]
#[command(name = "quadcl", version, about, long_about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Throughput figures: environment steps per second, masked network train steps.
    Bench(crate::cmd::bench::BenchArgs),
    /// Per network, layer and task: selected, vacant, occupied and private parameter counts.
    Masks(crate::cmd::masks::MasksArgs),
    /// Train one task with PPO + CENet; writes metrics and a policy directory.
    Train(crate::cmd::train::TrainArgs),
    /// Evaluate a policy on a task: return, tracking errors, falls (JSON with --json).
    Eval(crate::cmd::eval::EvalArgs),
    /// A learned task as plain dense networks for deployment (ONNX or safetensors), its contract as metadata.
    Export(crate::cmd::export::ExportArgs),
    /// The contact pattern of a policy under one held command: duty factors, foot pairings, gait.
    Gait(crate::cmd::gait::GaitArgs),
    /// Train a task sequence headless: metrics.json, checkpoints/, log (resumable).
    Run(crate::cmd::run::RunArgs),
    /// Figures of runs, overlaid: training curves per task, the whole sequence, the evaluation matrix, plasticity (PNG and SVG).
    Plot(crate::cmd::plot::PlotArgs),
    /// Record a policy's episodes on a task into an .mcap file (Foxglove) or an .rrd file (Rerun).
    Record(crate::cmd::record::RecordArgs),
    /// Watch a policy walk on a task in the Rerun 3D viewer, live (and optionally save it as .rrd).
    View(crate::cmd::view::ViewArgs),
    /// The workbench (also what `quadcl` alone opens): step through a sequence, watch training, masks, the robot.
    Tui(crate::cmd::tui::TuiArgs),
    /// What quadcl understood of a robot's URDF (legs, joints, masses, feet, warnings) and whether it stands.
    Robot(crate::cmd::robot::RobotArgs),
    /// Sim-to-real fine-tuning of one learned task on a shifted environment (its private parameters only).
    Finetune(crate::cmd::finetune::FinetuneArgs),
    /// Grids of runs (methods x seeds x settings): plan, run here or on Slurm, status, collect with intervals.
    Sweep(crate::cmd::sweep::SweepArgs),
}

/// Runs the chosen subcommand. Without one, opens the workbench (or, without a terminal, says what to run).
pub fn dispatch(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Some(Command::Bench(args)) => crate::cmd::bench::run(args),
        Some(Command::Masks(args)) => crate::cmd::masks::run(args),
        Some(Command::Train(args)) => crate::cmd::train::run(args),
        Some(Command::Eval(args)) => crate::cmd::eval::run(args),
        Some(Command::Export(args)) => crate::cmd::export::run(args),
        Some(Command::Gait(args)) => crate::cmd::gait::run(args),
        Some(Command::Run(args)) => crate::cmd::run::run(args),
        Some(Command::Plot(args)) => crate::cmd::plot::run(args),
        Some(Command::Finetune(args)) => crate::cmd::finetune::run(args),
        Some(Command::Tui(args)) => crate::cmd::tui::run(args),
        Some(Command::Record(args)) => crate::cmd::record::run(args),
        Some(Command::View(args)) => crate::cmd::view::run(args),
        Some(Command::Robot(args)) => crate::cmd::robot::run(args),
        Some(Command::Sweep(args)) => crate::cmd::sweep::run(args),
        None => crate::cmd::tui::run(crate::cmd::tui::TuiArgs::default()),
    }
}
