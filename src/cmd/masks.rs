//! `quadcl masks`: per network, layer and task, which parameters are used (owned by the `nn` work; skeleton).

use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct MasksArgs {
    /// A policy directory (model.safetensors, masks, manifest.json).
    #[arg(long)]
    pub policy: PathBuf,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: MasksArgs) -> anyhow::Result<()> {
    anyhow::bail!("{}: reading masks is not built yet", args.policy.display())
}
