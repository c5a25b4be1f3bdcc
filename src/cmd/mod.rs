//! One file per CLI subcommand: thin glue between the command line and the modules.

pub mod bench;
pub mod eval;
pub mod export;
pub mod finetune;
pub mod gait;
pub mod masks;
pub mod plot;
pub mod record;
pub mod robot;
pub mod run;
pub mod sweep;
pub mod train;
pub mod tui;
pub mod view;
pub mod welcome;
