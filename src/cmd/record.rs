//! `quadcl record --policy DIR --task T --seconds S --out FILE.mcap|FILE.rrd|FILE.mp4
//! [--format F] [--size WxH] [--episodes N] [--vx V --vy V --wz W] [--force]`: a policy's
//! episodes on a task into a file (see `record::record_episodes`; a video of one or more tasks
//! side by side: `record::record_video`), then a line saying what was written. [`EpisodeArgs`] are the options `quadcl view` shares.

use clap::Args;
use quadcl::record::{record_episodes, record_video, RecordFormat, RecordOptions, RecordSummary, VideoSize};
use std::path::{Path, PathBuf};

/// Which policy runs on which task, for how long, under which command.
#[derive(Debug, Args)]
pub struct EpisodeArgs {
    /// Policy directory (any form `quadcl eval` takes: a policy, a training checkpoint, a sequence's checkpoint).
    #[arg(long)]
    pub policy: PathBuf,
    /// Task to run on: `none`, `crash:FL`, ... (a video: several, comma-separated, side by side)
    #[arg(long, default_value = "none")]
    pub task: String,
    /// Simulated seconds at most (in (0, 3600]).
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Stop after this many finished episodes (falls or time-outs).
    #[arg(long)]
    pub episodes: Option<u64>,
    /// Hold this forward velocity command, m/s, in [-10, 10] (with --vy and --wz; without any, the env's random commands).
    #[arg(long, allow_hyphen_values = true)]
    pub vx: Option<f32>,
    /// Held lateral velocity command, m/s, in [-10, 10].
    #[arg(long, allow_hyphen_values = true)]
    pub vy: Option<f32>,
    /// Held yaw rate command, rad/s, in [-10, 10].
    #[arg(long, allow_hyphen_values = true)]
    pub wz: Option<f32>,
    /// Seed of the environment's reset.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Replace an existing output file.
    #[arg(long)]
    pub force: bool,
}

impl EpisodeArgs {
    pub fn options(&self) -> RecordOptions {
        let held = self.vx.is_some() || self.vy.is_some() || self.wz.is_some();
        let command = held.then(|| [self.vx.unwrap_or(0.0), self.vy.unwrap_or(0.0), self.wz.unwrap_or(0.0)]);
        RecordOptions { seconds: self.seconds, episodes: self.episodes, command, seed: self.seed, force: self.force }
    }

    /// The line saying what was done.
    pub fn report(&self, verb: &str, into: &str, s: &RecordSummary) -> String {
        let size = if s.bytes > 0 { format!(" ({:.1} MB)", s.bytes as f64 / 1e6) } else { String::new() };
        format!(
            "{verb} {} control steps ({:.1} s simulated, {} episodes ended) of {} into {into}{size} in {:.1} s",
            s.control_steps, s.sim_seconds, s.episodes, self.task, s.wall_seconds
        )
    }
}

#[derive(Debug, Args)]
pub struct RecordArgs {
    #[command(flatten)]
    pub episode: EpisodeArgs,
    /// Output file: `.mcap` (Foxglove), `.rrd` (Rerun) or `.mp4` (a video, through ffmpeg).
    #[arg(long)]
    pub out: PathBuf,
    /// The format (`mcap`, `rrd`, `mp4`); by default the output file's extension. Given, it must
    /// agree with the extension, or names the extension of a file that has none.
    #[arg(long)]
    pub format: Option<RecordFormat>,
    /// A video's picture size per task, WIDTHxHEIGHT (even numbers); several tasks
    /// (`--task none,crash:FL`) stand side by side.
    #[arg(long, default_value = "480x360")]
    pub size: VideoSize,
}

/// The output file `out` in `format`: its own extension when it has one (which must be the
/// format's), else `out` with the format's extension.
pub fn output_file(out: &Path, format: Option<RecordFormat>) -> anyhow::Result<PathBuf> {
    let ext = out.extension().and_then(|e| e.to_str());
    match (format, ext) {
        (None, _) => Ok(out.to_path_buf()),
        (Some(f), None) => Ok(out.with_extension(f.extension())),
        (Some(f), Some(e)) if e == f.extension() => Ok(out.to_path_buf()),
        (Some(f), Some(e)) => {
            anyhow::bail!(
                "--out {} is a .{e} file but --format is {}: give one or make them agree",
                out.display(),
                f.extension()
            )
        }
    }
}

pub fn run(args: RecordArgs) -> anyhow::Result<()> {
    let e = &args.episode;
    let out = output_file(&args.out, args.format)?;
    let s = if out.extension().is_some_and(|x| x == "mp4") {
        let tasks: Vec<String> = e.task.split(',').map(|t| t.trim().to_string()).collect();
        record_video(&e.policy, &tasks, &out, args.size, &e.options())?
    } else {
        anyhow::ensure!(
            !e.task.contains(','),
            "--task {}: several tasks side by side are for a video (.mp4) only",
            e.task
        );
        record_episodes(&e.policy, &e.task, &out, &e.options())?
    };
    println!("{}", e.report("recorded", &out.display().to_string(), &s));
    Ok(())
}
