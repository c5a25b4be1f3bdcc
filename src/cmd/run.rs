//! `quadcl run --config FILE --out DIR [--method NAME] [--resume]`: trains a task sequence
//! headless (see `headless`), draws its figures into `DIR/plots/` (see `quadcl::plot`), then
//! prints the summary measures.

use clap::Args;
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct RunArgs {
    /// Run file (TOML): experiment config, [method], [eval], [run] and the [[task]] sequence.
    #[arg(long)]
    pub config: PathBuf,
    /// Output folder: metrics.json, checkpoints/, log.txt, run.toml, tb/ (TensorBoard and CSV), plots/.
    #[arg(long)]
    pub out: PathBuf,
    /// Continue an interrupted run in --out from its last completed task (a folder that holds no run yet starts it).
    #[arg(long)]
    pub resume: bool,
    /// Stop after this many completed tasks (continue later with --resume).
    #[arg(long)]
    pub stop_after: Option<usize>,
    /// After each task, record one evaluation episode of every learned task into DIR/episodes/ (`mcap`: Foxglove, `rrd`: Rerun, `mp4`: a video).
    #[arg(long, value_name = "mcap|rrd")]
    pub record: Option<quadcl::record::RecordFormat>,
    /// Train with this method instead of the run file's [method] name: ours, wsn, packnet, piggyback, finetune, ewc, si, rwalk, er, agem
    /// (its settings still come from the file's [method.NAME] table). Give it again with --resume.
    #[arg(long)]
    pub method: Option<String>,
    /// Write no TensorBoard events or CSV (DIR/tb/).
    #[arg(long)]
    pub no_tb: bool,
}

pub fn run(args: RunArgs) -> anyhow::Result<()> {
    if let Some(n) = args.stop_after {
        // Stopping after no task would train nothing and report an empty run.
        anyhow::ensure!(n >= 1, "--stop-after = {n}: expected at least 1 task");
    }
    // The results are written: a figure that fails to draw is a warning, not the run's failure.
    // They are drawn while the run still holds its folder.
    let plots = args.out.join(quadcl::plot::PLOTS_DIR);
    let draw = |_: &quadcl::engine::MetricsFile| {
        if let Err(e) = quadcl::plot::write_run_plots(&args.out) {
            eprintln!(
                "warning: {}: the figures were not drawn: {}",
                plots.display(),
                quadcl::util::text::error_text(&e)
            );
        }
    };
    let m = quadcl::headless::run_then(
        &args.config,
        &args.out,
        quadcl::headless::RunOptions {
            resume: args.resume,
            progress: std::io::stderr().is_terminal(),
            stop_after: args.stop_after,
            record: args.record,
            method: args.method.clone(),
            no_tensorboard: args.no_tb,
        },
        draw,
    )?;
    let show = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
    println!(
        "{} steps of {} ({}): average performance {}, forgetting {}, plasticity {}, forward transfer {}; results in {}",
        m.completed_steps,
        m.total_steps,
        m.method,
        show(m.summary.average_performance),
        show(m.summary.forgetting),
        show(m.summary.plasticity),
        show(m.summary.forward_transfer_mean),
        args.out.display()
    );
    Ok(())
}
