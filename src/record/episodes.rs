//! `quadcl record`: a policy's episodes on a task, recorded into a file by
//! its extension (`.mcap`; `.rrd` comes with the Rerun recorder). The policy
//! runs deterministically in one env (no pushes, nominal physics) under a
//! held command or the env's own random commands, for a number of seconds
//! or of finished episodes, whichever comes first.

use super::mcap::McapRecorder;
use crate::rl::RobotViewer;
use crate::sim::StepObserver;
use anyhow::Context;
use std::path::Path;
use std::time::Instant;

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

/// What was recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordSummary {
    pub control_steps: usize,
    pub episodes: u64,
    pub sim_seconds: f64,
    pub wall_seconds: f64,
    pub bytes: u64,
}

/// Records `policy` (any policy directory form `quadcl eval` takes) on `task` into `out`.
pub fn record_episodes(policy: &Path, task: &str, out: &Path, o: &RecordOptions) -> anyhow::Result<RecordSummary> {
    anyhow::ensure!(
        o.seconds.is_finite() && o.seconds > 0.0 && o.seconds <= MAX_SECONDS,
        "--seconds must be in (0, {MAX_SECONDS}], got {}",
        o.seconds
    );
    anyhow::ensure!(o.episodes != Some(0), "--episodes must be at least 1");
    anyhow::ensure!(
        o.force || !out.exists(),
        "{} exists: pass --force to replace it, or choose another --out",
        out.display()
    );
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
    let mut viewer = RobotViewer::new(policy, task, o.seed, o.command)?;
    let recorder: Box<dyn StepObserver> = match ext {
        "mcap" => Box::new(McapRecorder::create(out, viewer.env().robot())?),
        "rrd" => anyhow::bail!(
            "{}: .rrd recordings (Rerun) are not built yet; record to an .mcap file (Foxglove) instead",
            out.display()
        ),
        other => anyhow::bail!("{}: unknown recording format {other:?} (use .mcap)", out.display()),
    };
    viewer.observe(recorder);
    let dt = f64::from(viewer.policy_dt());
    let steps = (o.seconds / dt).round().max(1.0) as usize;
    let start = Instant::now();
    let mut done = 0;
    while done < steps && o.episodes.is_none_or(|n| viewer.episodes() < n) {
        viewer.step().with_context(|| format!("recording {task} into {}", out.display()))?;
        done += 1;
    }
    let mut recorder = viewer.take_observer().context("the recorder is attached")?;
    recorder.finish()?;
    Ok(RecordSummary {
        control_steps: done,
        episodes: viewer.episodes(),
        sim_seconds: done as f64 * dt,
        wall_seconds: start.elapsed().as_secs_f64(),
        bytes: std::fs::metadata(out).map_or(0, |m| m.len()),
    })
}
