//! MP4 (H.264) files from frames, through an `ffmpeg` found on PATH: raw RGB frames go to its
//! standard input, libx264 encodes them (yuv420p, so every player reads the file), and the file
//! appears at its path only once ffmpeg has finished it (written beside it, then renamed).
//!
//! Why ffmpeg and not an encoder crate: the maintained H.264 crate (`openh264`) compiles Cisco's
//! C++ encoder into every build and gives a raw stream that still needs an MP4 muxer; ffmpeg is
//! on every cluster and workstation a researcher uses, muxes, and costs the build nothing.
//! Without it, a video is a clear error saying how to install it; nothing else needs it.

use super::frame::Frame;
use anyhow::Context;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};

/// The ffmpeg program (`QUADCL_FFMPEG` overrides the name found on PATH).
pub fn ffmpeg_program() -> String {
    std::env::var("QUADCL_FFMPEG").unwrap_or_else(|_| "ffmpeg".to_string())
}

/// An MP4 file being written.
pub struct VideoWriter {
    out: PathBuf,
    part: PathBuf,
    /// ffmpeg, until [`Self::finish`] waits for it.
    child: Option<Child>,
    stdin: Option<ChildStdin>,
    width: usize,
    height: usize,
    frames: usize,
}

impl VideoWriter {
    /// Starts `out` (an `.mp4`) for frames of `width` x `height` (both even: H.264's 4:2:0
    /// chroma halves each side) at `fps` frames a second.
    pub fn create(out: &Path, width: usize, height: usize, fps: f64) -> anyhow::Result<Self> {
        anyhow::ensure!(
            width % 2 == 0 && height % 2 == 0,
            "{}: a video of {width} x {height} pixels: H.264 needs an even width and height",
            out.display()
        );
        anyhow::ensure!(fps.is_finite() && fps > 0.0, "{}: {fps} frames a second", out.display());
        let name = out.file_name().context("a video needs a file name")?.to_string_lossy();
        let part = out.with_file_name(format!(".{name}.part"));
        if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).with_context(|| format!("creating folder {}", parent.display()))?;
        }
        let program = ffmpeg_program();
        let child = Command::new(&program)
            .args(["-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24"])
            .args(["-s", &format!("{width}x{height}"), "-framerate", &format!("{fps}"), "-i", "-"])
            .args(["-c:v", "libx264", "-preset", "veryfast", "-crf", "23", "-pix_fmt", "yuv420p"])
            .args(["-movflags", "+faststart", "-f", "mp4"])
            .arg(&part)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| match e.kind() {
                std::io::ErrorKind::NotFound => anyhow::anyhow!(
                    "{}: an MP4 video needs ffmpeg, and {program:?} was not found: install it (apt-get install \
                     ffmpeg, brew install ffmpeg, conda install ffmpeg) or name it in QUADCL_FFMPEG",
                    out.display()
                ),
                _ => anyhow::anyhow!("{}: starting {program}: {e}", out.display()),
            })?;
        let mut child = child;
        let stdin = child.stdin.take();
        Ok(Self { out: out.to_path_buf(), part, child: Some(child), stdin, width, height, frames: 0 })
    }

    /// Appends `frame` (of the writer's size).
    pub fn push(&mut self, frame: &Frame) -> anyhow::Result<()> {
        anyhow::ensure!(
            frame.width == self.width && frame.height == self.height,
            "{}: a {} x {} frame in a {} x {} video",
            self.out.display(),
            frame.width,
            frame.height,
            self.width,
            self.height
        );
        let stdin = self.stdin.as_mut().context("the video is finished")?;
        if let Err(e) = stdin.write_all(&frame.rgb) {
            let why = self.stop_and_read_errors();
            anyhow::bail!("{}: ffmpeg stopped taking frames ({e}){why}", self.out.display());
        }
        self.frames += 1;
        Ok(())
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Ends the stream, waits for ffmpeg and moves the finished file to its path; returns its size in bytes.
    pub fn finish(mut self) -> anyhow::Result<u64> {
        anyhow::ensure!(self.frames > 0, "{}: a video of no frame", self.out.display());
        drop(self.stdin.take());
        let child = self.child.take().context("the video is finished")?;
        let output = child.wait_with_output().with_context(|| format!("{}: waiting for ffmpeg", self.out.display()))?;
        anyhow::ensure!(
            output.status.success(),
            "{}: ffmpeg failed ({}): {}",
            self.out.display(),
            output.status,
            String::from_utf8_lossy(&output.stderr).trim()
        );
        std::fs::rename(&self.part, &self.out)
            .with_context(|| format!("moving {} to {}", self.part.display(), self.out.display()))?;
        Ok(std::fs::metadata(&self.out).map_or(0, |m| m.len()))
    }

    fn stop_and_read_errors(&mut self) -> String {
        drop(self.stdin.take());
        let mut text = String::new();
        if let Some(mut child) = self.child.take() {
            if let Some(mut err) = child.stderr.take() {
                let _ = std::io::Read::read_to_string(&mut err, &mut text);
            }
            let _ = child.wait();
        }
        if text.trim().is_empty() {
            String::new()
        } else {
            format!(": {}", text.trim())
        }
    }
}

impl Drop for VideoWriter {
    /// A video left unfinished (an error on the way) leaves no partial file.
    fn drop(&mut self) {
        drop(self.stdin.take());
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
        let _ = std::fs::remove_file(&self.part);
    }
}
