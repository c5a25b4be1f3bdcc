//! `quadcl plot RUN_DIR... --out DIR [--label NAME]... [--smooth N]`: the figures of one or
//! more runs, overlaid (see [`quadcl::plot`]), as PNG and SVG. A sweep folder stands for one
//! run per group: the mean over its finished seeds with their range as a band.

use clap::Args;
use quadcl::plot::{is_sweep, load_run, load_sweep, write_figures, PlotOptions, RunData};
use std::path::PathBuf;

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
    Ok(())
}
