//! `quadcl export --policy DIR [--task T | --all-tasks] --format onnx|safetensors --out FILE`:
//! a learned task as plain dense networks for deployment, the contract as metadata
//! (library: `export`). Prints what it wrote and the self-check's figure.

use clap::Args;
use quadcl::export::{self, ExportFormat};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// Policy directory, as `quadcl eval` takes it (a `quadcl train` output or its
    /// `checkpoint/`, a sequence run's checkpoint).
    #[arg(long)]
    pub policy: PathBuf,
    /// The learned task to export (`none`, `crash:FL`, ...); default: the last learned.
    #[arg(long, conflicts_with = "all_tasks")]
    pub task: Option<String>,
    /// Export every learned task: --out is then a folder, one file per task (`crash_FL.onnx`, ...).
    #[arg(long)]
    pub all_tasks: bool,
    /// File format.
    #[arg(long, value_enum, default_value = "onnx")]
    pub format: ExportFormat,
    /// Output file (a folder with --all-tasks).
    #[arg(long)]
    pub out: PathBuf,
    /// Also write reference samples beside each file (`FILE.reference.safetensors`): rollout
    /// observation histories with quadcl's actions on them, for `scripts/check_export.py`.
    #[arg(long)]
    pub reference: bool,
}

fn reference_path(out: &std::path::Path, wanted: bool) -> Option<PathBuf> {
    wanted.then(|| {
        let mut name = out.file_name().unwrap_or_default().to_os_string();
        name.push(".reference.safetensors");
        out.with_file_name(name)
    })
}

pub fn run(args: ExportArgs) -> anyhow::Result<()> {
    let jobs: Vec<(Option<String>, PathBuf)> = if args.all_tasks {
        std::fs::create_dir_all(&args.out)
            .map_err(|e| anyhow::anyhow!("creating the output folder {}: {e}", args.out.display()))?;
        export::learned_tasks(&args.policy)?
            .into_iter()
            .map(|t| {
                let file = args.out.join(format!("{}.{}", export::task_file_stem(&t), args.format.extension()));
                (Some(t), file)
            })
            .collect()
    } else {
        vec![(args.task.clone(), args.out.clone())]
    };
    for (task, out) in jobs {
        let reference = reference_path(&out, args.reference);
        let done = export::export_task(&args.policy, task.as_deref(), args.format, &out, reference.as_deref())?;
        println!(
            "{}: task {} ({} bytes; dense copy vs the policy: max |diff| {:.1e})",
            done.path.display(),
            done.task,
            done.bytes,
            done.self_check
        );
        if let Some(r) = done.reference {
            println!("{}: reference samples", r.display());
        }
    }
    Ok(())
}
