//! `quadcl masks`: per network, layer and task, which parameters are used
//! (the JSON shape is documented in [`crate::nn::stats`]).

use crate::nn::checkpoint::load_policy;
use crate::nn::stats::mask_report;
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct MasksArgs {
    /// A policy directory (model.safetensors, masks.safetensors, manifest.json).
    #[arg(long)]
    pub policy: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Prints the mask statistics of a policy directory.
pub fn run(args: MasksArgs) -> anyhow::Result<()> {
    println!("{}", render(&args)?);
    Ok(())
}

/// The text `quadcl masks` prints (JSON or table).
pub fn render(args: &MasksArgs) -> anyhow::Result<String> {
    let policy = load_policy(&args.policy)?;
    let nets: Vec<_> = policy.networks.iter().collect();
    let report = mask_report(&policy.tasks, &nets);
    Ok(if args.json { serde_json::to_string_pretty(&report)? } else { report.to_table() })
}
