//! The one [`StepObserver`] every recording format uses: the simulation thread
//! copies each step into a [`Sample`] and queues it; a writer thread of the
//! format (a [`SampleWriter`]: MCAP, Rerun) encodes, compresses and sends. The
//! queue is bounded, so a slow writer slows the simulation instead of filling
//! memory; a writer that fails stops taking steps and reports at finish.

use super::sample::Sample;
use crate::sim::{StepInfo, StepObserver};
use std::sync::mpsc::SyncSender;
use std::thread::JoinHandle;

/// Steps waiting for the writer thread at most (then the simulation waits: memory stays bounded).
const QUEUE: usize = 1024;

/// A recording format's writing side, run on the recorder's own thread.
pub(crate) trait SampleWriter: Send + 'static {
    /// Encodes one step (an error is kept and reported by `finish`).
    fn record(&mut self, sample: &Sample);
    /// The last step was recorded: flush and close; the first error met.
    fn finish(self) -> anyhow::Result<()>;
}

/// Records one env's steps in some format (made by [`Recorder::mcap`] or [`Recorder::rerun`]).
pub struct Recorder {
    queue: Option<SyncSender<Sample>>,
    writer: Option<JoinHandle<anyhow::Result<()>>>,
    format: &'static str,
}

impl Recorder {
    /// Starts `writer` on its own thread; `format` names it in errors.
    pub(crate) fn start<W: SampleWriter>(mut writer: W, format: &'static str) -> Self {
        let (queue, samples) = std::sync::mpsc::sync_channel::<Sample>(QUEUE);
        let thread = std::thread::spawn(move || {
            for sample in samples {
                writer.record(&sample);
            }
            writer.finish()
        });
        Self { queue: Some(queue), writer: Some(thread), format }
    }
}

impl StepObserver for Recorder {
    fn on_reset(&mut self, info: &StepInfo) {
        self.on_step(info);
    }

    fn on_step(&mut self, info: &StepInfo) {
        // A writer thread that stopped (an I/O error) reports it at finish.
        if let Some(q) = &self.queue {
            if q.send(Sample::of(info)).is_err() {
                self.queue = None;
            }
        }
    }

    fn finish(&mut self) -> anyhow::Result<()> {
        self.queue = None;
        match self.writer.take() {
            Some(thread) => thread.join().map_err(|_| anyhow::anyhow!("the {} writer thread panicked", self.format))?,
            None => Ok(()),
        }
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        // Not finished (an error upstream): the writer ends; a file stays under its partial name.
        self.queue = None;
        if let Some(thread) = self.writer.take() {
            let _ = thread.join();
        }
    }
}
