//! `quadcl view --policy DIR --task T [--seconds S] [--vx V --vy V --wz W]
//! [--connect [URL]] [--spawn] [--save FILE.rrd]`: a policy walking on a task,
//! live in the Rerun viewer at the speed of simulated time (see
//! `record::view_policy`). Without a sink it starts a viewer (`--spawn`; one
//! already running on the default port is reused). `--save` with a live sink
//! keeps the same stream as a file too.

use super::record::EpisodeArgs;
use clap::Args;
use quadcl::record::{view_policy, RerunSink};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct ViewArgs {
    #[command(flatten)]
    pub episode: EpisodeArgs,
    /// Stream to a running viewer (default: the viewer's own address, rerun+http://127.0.0.1:9876/proxy).
    #[arg(long, num_args = 0..=1, default_missing_value = "", value_name = "URL")]
    pub connect: Option<String>,
    /// Start the viewer (`rerun` on PATH) and stream to it.
    #[arg(long, conflicts_with = "connect")]
    pub spawn: bool,
    /// Also (or only) save the stream as an .rrd file.
    #[arg(long, value_name = "FILE.rrd")]
    pub save: Option<PathBuf>,
}

impl ViewArgs {
    fn sinks(&self) -> Vec<RerunSink> {
        let mut sinks = Vec::new();
        match &self.connect {
            Some(url) if url.is_empty() => sinks.push(RerunSink::Connect(RerunSink::default_url())),
            Some(url) => sinks.push(RerunSink::Connect(url.clone())),
            None if self.spawn || self.save.is_none() => sinks.push(RerunSink::Spawn),
            None => {}
        }
        sinks.extend(self.save.clone().map(RerunSink::Save));
        sinks
    }
}

pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    let sinks = args.sinks();
    let into: Vec<String> = sinks
        .iter()
        .map(|s| match s {
            RerunSink::Connect(url) => format!("the viewer at {url}"),
            RerunSink::Spawn => "the viewer on this machine (started if none was running)".to_string(),
            RerunSink::Save(path) => path.display().to_string(),
        })
        .collect();
    let e = &args.episode;
    let s = view_policy(&e.policy, &e.task, &sinks, &e.options())?;
    println!("{}", e.report("streamed", &into.join(" and "), &s));
    Ok(())
}
