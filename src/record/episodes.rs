//! `quadcl record` and `quadcl view`: a policy's episodes on a task, recorded
//! into a file by its extension (`.mcap` for Foxglove, `.rrd` for Rerun, `.mp4` a video) or
//! streamed to a Rerun viewer. The policy runs deterministically in one env
//! (no pushes, nominal physics) under a held command or the env's own random
//! commands, for a number of seconds or of finished episodes, whichever comes
//! first; a live view runs at the speed of simulated time.

use super::recorder::Recorder;
#[cfg(feature = "rerun")]
use super::rerun::RerunSink;
#[cfg(feature = "rerun")]
use super::rerun_scene::RerunScene;
use crate::config::bounds::{self, Interval};
use crate::config::env::check_command;
use crate::rl::RobotViewer;
use anyhow::Context;
use std::path::Path;
use std::time::{Duration, Instant};

/// The longest recording, simulated seconds (a bound on what a typo can fill a disk with).
pub const MAX_SECONDS: f64 = 3600.0;

/// What to record.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordOptions {
    /// Simulated seconds at most.
    pub seconds: f64,
    /// Stop after this many finished episodes (None: the seconds only).
    pub episodes: Option<u64>,
    /// A held command (vx, vy, wz); None: the env's own random commands.
    pub command: Option<[f32; 3]>,
    /// Seed of the env's reset.
    pub seed: u64,
    /// Replace an existing file.
    pub force: bool,
}

/// A recording's file format, by its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordFormat {
    /// MCAP for Foxglove.
    Mcap,
    /// Rerun's `.rrd`.
    Rrd,
    /// An MP4 video (H.264), rendered on the CPU.
    Mp4,
}

impl RecordFormat {
    /// `mcap` or `rrd`.
    pub fn extension(self) -> &'static str {
        match self {
            RecordFormat::Mcap => "mcap",
            RecordFormat::Rrd => "rrd",
            RecordFormat::Mp4 => "mp4",
        }
    }
}

impl std::str::FromStr for RecordFormat {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> anyhow::Result<Self> {
        match s {
            "mcap" => Ok(RecordFormat::Mcap),
            "rrd" => Ok(RecordFormat::Rrd),
            "mp4" => Ok(RecordFormat::Mp4),
            other => anyhow::bail!("unknown recording format {other:?} (use mcap, rrd or mp4)"),
        }
    }
}

/// What was recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordSummary {
    pub control_steps: usize,
    pub episodes: u64,
    pub sim_seconds: f64,
    pub wall_seconds: f64,
    pub bytes: u64,
}

/// Records `policy` (any policy directory form `quadcl eval` takes) on `task` into `out`
/// (`.mcap`, `.rrd`, or `.mp4`: a video at the default size, [`super::video::record_video`]).
pub fn record_episodes(policy: &Path, task: &str, out: &Path, o: &RecordOptions) -> anyhow::Result<RecordSummary> {
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
    if ext == "mp4" {
        return super::video::record_video(policy, &[task.to_string()], out, Default::default(), o);
    }
    check_options(o)?;
    refuse_existing(out, o.force, "--out")?;
    let viewer = RobotViewer::new(policy, task, o.seed, o.command)?;
    let recorder = match ext {
        "mcap" => Recorder::mcap(out, viewer.env().robot())?,
        #[cfg(feature = "rerun")]
        "rrd" => Recorder::rerun(&[RerunSink::Save(out.to_path_buf())], viewer.env().robot(), &scene(&viewer, policy))?,
        #[cfg(not(feature = "rerun"))]
        "rrd" => anyhow::bail!("{}: this build of quadcl has no Rerun (its `rerun` feature is off)", out.display()),
        other => anyhow::bail!("{}: unknown recording format {other:?} (use .mcap, .rrd or .mp4)", out.display()),
    };
    let mut summary =
        run(viewer, recorder, o, false).with_context(|| format!("recording {task} into {}", out.display()))?;
    summary.bytes = std::fs::metadata(out).map_or(0, |m| m.len());
    Ok(summary)
}

#[cfg(feature = "rerun")]
/// Streams `policy` on `task` to the Rerun `sinks` (a live viewer, a file, or both), pacing
/// the steps at the speed of simulated time while a viewer watches.
pub fn view_policy(policy: &Path, task: &str, sinks: &[RerunSink], o: &RecordOptions) -> anyhow::Result<RecordSummary> {
    check_options(o)?;
    for sink in sinks {
        if let RerunSink::Save(out) = sink {
            refuse_existing(out, o.force, "--save")?;
        }
    }
    let viewer = RobotViewer::new(policy, task, o.seed, o.command)?;
    let recorder = Recorder::rerun(sinks, viewer.env().robot(), &scene(&viewer, policy))?;
    let live = sinks.iter().any(|s| !matches!(s, RerunSink::Save(_)));
    run(viewer, recorder, o, live).with_context(|| format!("streaming {task} to Rerun"))
}

/// An existing `out` is kept unless `force`; `flag` names the option that chose it.
pub(super) fn refuse_existing(out: &Path, force: bool, flag: &str) -> anyhow::Result<()> {
    anyhow::ensure!(
        force || !out.exists(),
        "{} exists: pass --force to replace it, or choose another {flag}",
        out.display()
    );
    Ok(())
}

pub(super) fn check_options(o: &RecordOptions) -> anyhow::Result<()> {
    bounds::check("--seconds", o.seconds, Interval::OpenClosed(0.0, MAX_SECONDS))?;
    anyhow::ensure!(o.episodes != Some(0), "--episodes must be at least 1");
    if let Some(command) = o.command {
        for (option, v) in ["--vx", "--vy", "--wz"].into_iter().zip(command) {
            check_command(option, v)?;
        }
    }
    Ok(())
}

/// What a Rerun recording of `viewer` shows besides the motion.
#[cfg(feature = "rerun")]
fn scene(viewer: &RobotViewer, policy: &Path) -> RerunScene {
    RerunScene { task: viewer.task().to_string(), policy: policy.display().to_string(), masks: viewer.mask_views() }
}

/// Steps `viewer` with `recorder` attached until the seconds or the episodes are done.
fn run(
    mut viewer: RobotViewer,
    recorder: Recorder,
    o: &RecordOptions,
    realtime: bool,
) -> anyhow::Result<RecordSummary> {
    viewer.observe(Box::new(recorder));
    let dt = f64::from(viewer.policy_dt());
    let steps = (o.seconds / dt).round().max(1.0) as usize;
    let start = Instant::now();
    let mut done = 0;
    while done < steps && o.episodes.is_none_or(|n| viewer.episodes() < n) {
        viewer.step()?;
        done += 1;
        if realtime {
            let ahead = Duration::from_secs_f64(done as f64 * dt).saturating_sub(start.elapsed());
            std::thread::sleep(ahead);
        }
    }
    let mut recorder = viewer.take_observer().context("the recorder is attached")?;
    recorder.finish()?;
    Ok(RecordSummary {
        control_steps: done,
        episodes: viewer.episodes(),
        sim_seconds: done as f64 * dt,
        wall_seconds: start.elapsed().as_secs_f64(),
        bytes: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recording_format_parses_from_its_extension_and_an_unknown_one_names_the_choices() {
        for format in [RecordFormat::Mcap, RecordFormat::Rrd, RecordFormat::Mp4] {
            assert_eq!(format.extension().parse::<RecordFormat>().unwrap(), format);
        }
        let err = format!("{:#}", "bag".parse::<RecordFormat>().unwrap_err());
        assert!(err.contains("bag") && err.contains("mcap") && err.contains("rrd") && err.contains("mp4"), "{err}");
    }
}
