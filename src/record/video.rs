//! `quadcl record --format mp4`: a policy's episodes on one or more tasks as an MP4 video, one
//! picture per control step (50 fps at the A1's 0.02 s), rendered on the CPU (`render`), the tasks
//! side by side when there are several (each its own env, same seed and command), with the task,
//! the command, the trunk's velocity and the episode's figures written on every frame.

use super::episodes::{check_options, refuse_existing, RecordOptions, RecordSummary};
use crate::render::{frame_of, Camera, Frame, VideoWriter};
use crate::rl::{RobotFrame, RobotViewer};
use anyhow::Context;
use std::path::Path;
use std::time::Instant;

/// The size of each task's picture, pixels (the video is as wide as the tasks side by side).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VideoSize {
    pub width: usize,
    pub height: usize,
}

impl Default for VideoSize {
    fn default() -> Self {
        Self { width: 480, height: 360 }
    }
}

impl std::str::FromStr for VideoSize {
    type Err = anyhow::Error;
    /// `WIDTHxHEIGHT`, e.g. `480x360`.
    fn from_str(s: &str) -> anyhow::Result<Self> {
        let parse = |v: Option<&str>| v.and_then(|v| v.trim().parse::<usize>().ok());
        let mut parts = s.split('x');
        match (parse(parts.next()), parse(parts.next()), parts.next()) {
            (Some(width), Some(height), None) => Ok(Self { width, height }),
            _ => anyhow::bail!("--size {s:?}: expected WIDTHxHEIGHT, e.g. 480x360"),
        }
    }
}

/// A running tally of one episode for the frame's text.
#[derive(Default)]
struct Tally {
    steps: u32,
    speed_error: f64,
}

/// The lines written on a task's frame.
fn caption(task: &str, f: &RobotFrame, tally: &Tally) -> Vec<String> {
    let [cx, cy, cw] = f.command;
    let [vx, vy, vw] = f.base_velocity;
    let mean_error = tally.speed_error / f64::from(tally.steps.max(1));
    vec![
        format!("{task}   t {:.1} s   episode {}", f.sim_time, f.episode + 1),
        format!("command  vx {cx:+.2}  vy {cy:+.2}  wz {cw:+.2}"),
        format!("trunk    vx {vx:+.2}  vy {vy:+.2}  wz {vw:+.2}"),
        format!("velocity error {mean_error:.3} m/s{}", if f.fell { "   FELL" } else { "" }),
    ]
}

/// Records `policy` on every task of `tasks` side by side into the MP4 file `out` (frames of
/// `size` per task), for `o`'s seconds or episodes (counted on the first task).
pub fn record_video(
    policy: &Path,
    tasks: &[String],
    out: &Path,
    size: VideoSize,
    o: &RecordOptions,
) -> anyhow::Result<RecordSummary> {
    check_options(o)?;
    refuse_existing(out, o.force, "--out")?;
    anyhow::ensure!(!tasks.is_empty(), "no task to record");
    crate::render::frame::check_size(size.width * tasks.len(), size.height)?;
    let mut viewers =
        tasks.iter().map(|t| RobotViewer::new(policy, t, o.seed, o.command)).collect::<anyhow::Result<Vec<_>>>()?;
    let names: Vec<String> = viewers.iter().map(|v| v.task().to_string()).collect();
    let dt = f64::from(viewers[0].policy_dt());
    let mut video = VideoWriter::create(out, size.width * tasks.len(), size.height, 1.0 / dt)?;
    let camera = Camera::default();
    let text_size = (size.height as f64 / 22.0).max(9.0);
    let steps = (o.seconds / dt).round().max(1.0) as usize;
    let mut tallies: Vec<Tally> = viewers.iter().map(|_| Tally::default()).collect();
    let start = Instant::now();
    let mut done = 0;
    while done < steps && o.episodes.is_none_or(|n| viewers[0].episodes() < n) {
        let mut pictures = Vec::with_capacity(viewers.len());
        for ((viewer, tally), name) in viewers.iter_mut().zip(&mut tallies).zip(&names) {
            let before = viewer.episodes();
            let f = viewer.step()?;
            if viewer.episodes() != before {
                *tally = Tally::default();
            }
            tally.steps += 1;
            let [cx, cy, _] = f.command;
            let [vx, vy, _] = f.base_velocity;
            tally.speed_error += f64::from(((vx - cx).powi(2) + (vy - cy).powi(2)).sqrt());
            let mut picture = frame_of(viewer.env(), &camera, size.width, size.height)?;
            picture.write_lines(&caption(name, &f, tally), text_size)?;
            pictures.push(picture);
        }
        let frame =
            if pictures.len() == 1 { pictures.pop().expect("one picture") } else { Frame::side_by_side(&pictures)? };
        video.push(&frame).with_context(|| format!("recording {} into {}", names.join(", "), out.display()))?;
        done += 1;
    }
    let bytes = video.finish()?;
    Ok(RecordSummary {
        control_steps: done,
        episodes: viewers[0].episodes(),
        sim_seconds: done as f64 * dt,
        wall_seconds: start.elapsed().as_secs_f64(),
        bytes,
    })
}

/// A filmstrip's pictures: how many per task, how far apart, after how long a walk, how large.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Filmstrip {
    pub frames: usize,
    /// Simulated seconds between pictures.
    pub every_s: f64,
    /// Simulated seconds walked before the first picture (the gait settled).
    pub after_s: f64,
    pub size: VideoSize,
    /// The command held (vx, vy, wz).
    pub command: [f32; 3],
}

impl Default for Filmstrip {
    /// Six pictures 0.06 s apart (about one trot cycle) after 2 s at 0.5 m/s forward, 200 x 150.
    fn default() -> Self {
        Self {
            frames: 6,
            every_s: 0.06,
            after_s: 2.0,
            size: VideoSize { width: 200, height: 150 },
            command: [0.5, 0.0, 0.0],
        }
    }
}

/// `policy`'s gait on each of `tasks` as one picture: a row of `strip.frames` pictures per
/// task, the task and the time on each row's first.
pub fn filmstrip(policy: &Path, tasks: &[String], strip: &Filmstrip) -> anyhow::Result<Frame> {
    anyhow::ensure!(!tasks.is_empty() && strip.frames > 0, "a filmstrip of no task or no picture");
    // Closer than a video's camera: the pictures are small.
    let camera = Camera { distance: 1.1, ..Default::default() };
    let mut rows = Vec::with_capacity(tasks.len());
    for task in tasks {
        let mut viewer = RobotViewer::new(policy, task, 1, Some(strip.command))?;
        let dt = f64::from(viewer.policy_dt());
        let steps = |s: f64| (s / dt).round().max(1.0) as usize;
        for _ in 0..steps(strip.after_s) {
            viewer.step()?;
        }
        let mut pictures = Vec::with_capacity(strip.frames);
        for i in 0..strip.frames {
            if i > 0 {
                for _ in 0..steps(strip.every_s) {
                    viewer.step()?;
                }
            }
            let mut p = frame_of(viewer.env(), &camera, strip.size.width, strip.size.height)?;
            let at = strip.after_s + i as f64 * steps(strip.every_s) as f64 * dt;
            let label = if i == 0 { format!("{task}  {at:.2} s") } else { format!("{at:.2} s") };
            p.write_lines(&[label], (strip.size.height as f64 / 12.0).max(9.0))?;
            pictures.push(p);
        }
        rows.push(Frame::side_by_side(&pictures)?);
    }
    Frame::stacked(&rows)
}
