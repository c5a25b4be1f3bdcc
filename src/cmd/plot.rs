//! `quadcl plot RUN_DIR... --out DIR [--label NAME]... [--smooth N]`: the figures of one or
//! more runs, overlaid (see [`quadcl::plot`]), as PNG and SVG. A sweep folder stands for one
//! run per group: the mean over its finished seeds with their range as a band. `--filmstrip`
//! adds a picture of each run's gait on every task it learned (`record::filmstrip`).

use anyhow::Context;
use clap::Args;
use quadcl::plot::{is_sweep, load_run, load_sweep, write_figures, PlotOptions, RunData};
use quadcl::record::{filmstrip, Filmstrip};
use std::path::{Path, PathBuf};

/// The longest moving mean `--smooth` takes.
const MAX_SMOOTH: usize = 1000;

#[derive(Debug, Args)]
pub struct PlotArgs {
    /// Run folders (`quadcl run`: metrics.json; `quadcl train`: metrics.jsonl), those files, or
    /// sweep folders (each group drawn as the mean of its finished seeds, their range shaded).
    #[arg(required = true, value_name = "RUN_DIR")]
    pub runs: Vec<PathBuf>,
    /// Folder for the figures (created): task_curves, sequence, eval_matrix and plasticity, each .png and .svg.
    #[arg(long)]
    pub out: PathBuf,
    /// A run's name in the legends, once per RUN_DIR in order (default: each folder's name; for a
    /// sweep, put before each group's name).
    #[arg(long, value_name = "NAME")]
    pub label: Vec<String>,
    /// Draw each curve as its moving mean over N iterations (1: as recorded).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub smooth: usize,
    /// Also draw each run folder's gait: `filmstrip.png` (`filmstrip-LABEL.png` for several runs),
    /// six pictures of every task its last checkpoint learned, 0.06 s apart after 2 s at 0.5 m/s.
    #[arg(long)]
    pub filmstrip: bool,
}

/// Reads the runs, writes the figures and prints the files written.
pub fn run(args: PlotArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.label.is_empty() || args.label.len() == args.runs.len(),
        "{} --label for {} runs: give one per RUN_DIR, in order, or none",
        args.label.len(),
        args.runs.len()
    );
    quadcl::config::bounds::check_count("--smooth", args.smooth, 1, MAX_SMOOTH)?;
    let mut runs: Vec<RunData> = Vec::new();
    for (i, path) in args.runs.iter().enumerate() {
        let label = args.label.get(i).map(String::as_str);
        if is_sweep(path) {
            for mut group in load_sweep(path)? {
                if let Some(prefix) = label {
                    group.label = format!("{prefix} {}", group.label);
                }
                runs.push(group);
            }
        } else {
            runs.push(load_run(path, label)?);
        }
    }
    for file in write_figures(&runs, &args.out, &PlotOptions { smooth: args.smooth })? {
        println!("{}", file.display());
    }
    if args.filmstrip {
        for (i, path) in args.runs.iter().enumerate() {
            let name = match (args.runs.len(), args.label.get(i)) {
                (1, _) => "filmstrip.png".to_string(),
                (_, Some(label)) => format!("filmstrip-{}.png", quadcl::engine::task_file_name(label)),
                (_, None) => format!("filmstrip-{i}.png"),
            };
            let out = args.out.join(name);
            write_filmstrip(path, &out)?;
            println!("{}", out.display());
        }
    }
    Ok(())
}

/// The filmstrip of the run folder `run` (its last checkpoint, every task it learned) into `out`.
fn write_filmstrip(run: &Path, out: &Path) -> anyhow::Result<()> {
    let checkpoints = run.join(quadcl::engine::CHECKPOINTS);
    let mut steps: Vec<PathBuf> = std::fs::read_dir(&checkpoints)
        .with_context(|| format!("--filmstrip: {} has no checkpoints/ (a run folder of `quadcl run`)", run.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    steps.sort();
    let last =
        steps.pop().with_context(|| format!("--filmstrip: {} holds no checkpoint yet", checkpoints.display()))?;
    let tasks = quadcl::rl::load_policy_or_checkpoint(&last)?.policy.tasks;
    let picture = filmstrip(&last, &tasks, &Filmstrip::default())?;
    quadcl::util::write_atomic(out, &picture.png()?)
}
