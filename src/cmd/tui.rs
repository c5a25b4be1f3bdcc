//! `quadcl tui [--run DIR] [--config FILE] [--continues DIR]` (and `quadcl`
//! alone): opens the workbench; `quadcl tui --sweep DIR` opens a sweep's Sweep screen. Without options it opens `runs/workbench`,
//! which on first use continues the shipped 4-task run `policies/sequence-a1-adapter`
//! with the rest of the default 12-task sequence `scenes/sequence-a1.toml`.
//! Without a terminal it says what to run instead.

use clap::Args;
use quadcl::tui::OpenSpec;
use std::io::IsTerminal;
use std::path::PathBuf;

/// The workbench's run folder when none is named.
pub const DEFAULT_RUN: &str = "runs/workbench";
/// The sequence it trains when none is named.
pub const DEFAULT_CONFIG: &str = "scenes/sequence-a1.toml";
/// The shipped run it continues.
pub const DEFAULT_CONTINUES: &str = "policies/sequence-a1-adapter";

#[derive(Debug, Args, Default)]
pub struct TuiArgs {
    /// Run folder: what is trained lands here (reopening it continues the run).
    #[arg(long)]
    pub run: Option<PathBuf>,
    /// Run file for a new folder (a folder that holds a run uses its own run.toml).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// A finished shorter run whose steps begin --config's sequence: a new folder continues it.
    #[arg(long)]
    pub continues: Option<PathBuf>,
    /// A sweep folder (`quadcl sweep plan`): its cells with status and progress, the collected table; Enter opens a cell's run.
    #[arg(long, conflicts_with_all = ["run", "config", "continues"])]
    pub sweep: Option<PathBuf>,
}

/// The run the options name (the defaults when none is given).
pub fn spec(args: TuiArgs) -> OpenSpec {
    let defaults = args.run.is_none() && args.config.is_none();
    let run_dir = args.run.unwrap_or_else(|| match &args.config {
        Some(c) => PathBuf::from("runs").join(c.file_stem().unwrap_or_default()),
        None => PathBuf::from(DEFAULT_RUN),
    });
    OpenSpec {
        run_dir,
        config: args.config.or_else(|| defaults.then(|| DEFAULT_CONFIG.into())),
        continues: args.continues.or_else(|| defaults.then(|| DEFAULT_CONTINUES.into())),
    }
}

pub fn run(args: TuiArgs) -> anyhow::Result<()> {
    let terminal = std::io::stdout().is_terminal() && std::io::stdin().is_terminal();
    if let Some(dir) = args.sweep {
        anyhow::ensure!(
            terminal,
            "the Sweep screen needs a terminal: without one, `quadcl sweep status {}` prints where the cells stand",
            dir.display()
        );
        return quadcl::tui::run_sweep(dir);
    }
    if !terminal {
        crate::cmd::welcome::run();
        return Ok(());
    }
    quadcl::tui::run(spec(args))
}
