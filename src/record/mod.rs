//! Recorders: observers of simulation steps (`sim::StepObserver`) that keep
//! episodes to open again. The simulator knows nothing of them.
//!
//! - `mcap`: episodes as MCAP with JSON messages and JSON-schema channels that
//!   Foxglove reads (`foxglove.FrameTransforms`, `foxglove.SceneUpdate`, joint
//!   states, the command, reward terms, contacts); log time = simulation time.
//! - `foxglove`: the link shapes and frames in Foxglove's message shapes, and the schemas.
//! - `episodes`: a policy's episodes on a task into a file (`quadcl record`).

mod episodes;
mod foxglove;
mod mcap;

pub use self::mcap::{McapRecorder, TOPICS};
pub use episodes::{record_episodes, RecordOptions, RecordSummary, MAX_SECONDS};
