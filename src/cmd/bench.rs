//! `quadcl bench`: throughput figures, as JSON or a readable table.

use clap::Args;
use quadcl::config::bounds::{self, Interval};

/// The longest `--seconds`: the measurements keep a time per step they take.
pub const MAX_BENCH_SECONDS: f64 = 600.0;

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Seconds to spend on each measurement (at most 600).
    #[arg(long, default_value_t = 2.0)]
    pub seconds: f64,
    /// Only these sections (comma-separated: env, accuracy, nn, ppo, record, render, tui); all by default.
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    bounds::check("--seconds", args.seconds, Interval::OpenClosed(0.0, MAX_BENCH_SECONDS))?;
    const SECTIONS: [&str; 7] = ["env", "accuracy", "nn", "ppo", "record", "render", "tui"];
    if let Some(bad) = args.only.iter().find(|s| !SECTIONS.contains(&s.as_str())) {
        anyhow::bail!("--only: unknown section {bad:?} (sections: {})", SECTIONS.join(", "));
    }
    let wanted = |s: &str| args.only.is_empty() || args.only.iter().any(|o| o == s);
    let mut report = serde_json::Map::new();
    if wanted("env") {
        crate::bench::env::measure(args.seconds, &mut report)?;
    }
    if wanted("accuracy") {
        crate::bench::accuracy::measure(&mut report)?;
    }
    if wanted("nn") {
        crate::bench::nn::measure(args.seconds, &mut report)?;
        crate::bench::gemm::measure(args.seconds, &mut report)?;
    }
    if wanted("ppo") {
        crate::bench::ppo::measure(args.seconds, None, &mut report)?;
    }
    if wanted("record") {
        crate::bench::record::measure(args.seconds, &mut report)?;
    }
    if wanted("render") {
        crate::bench::render::measure(args.seconds, &mut report)?;
    }
    if wanted("tui") {
        crate::bench::tui::measure(args.seconds, &mut report)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&serde_json::Value::Object(report))?);
    } else {
        for (key, value) in &report {
            println!("{key:<36} {value}");
        }
    }
    Ok(())
}
