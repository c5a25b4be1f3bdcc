//! `quadcl masks`: per network, layer and task, which parameters are used
//! (the JSON shape is documented on [`quadcl::nn::MaskReport`]).

use clap::Args;
use quadcl::nn::MaskReport;
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
    let report = MaskReport::of_policy(&args.policy)?;
    Ok(if args.json { serde_json::to_string_pretty(&report)? } else { report.to_table() })
}
