//! Recorders: observers of simulation steps (`sim::StepObserver`) that keep
//! episodes to open again or stream them to a viewer. The simulator knows
//! nothing of them. Every format is a [`Recorder`]: the simulation thread
//! copies each step, the format's writer thread encodes it.
//!
//! - `mcap`: episodes as MCAP with JSON messages and JSON-schema channels that
//!   Foxglove reads (`foxglove.FrameTransforms`, `foxglove.SceneUpdate`, joint
//!   states, the command, reward terms, contacts); log time = simulation time.
//! - `foxglove`: the link shapes and frames in Foxglove's message shapes, and the schemas.
//! - `rerun`, `rerun_scene`: the robot in Rerun (live viewer over gRPC, `.rrd` files): the
//!   URDF through Rerun's importer, a transform per joint per step, contacts, command and
//!   velocity arrows, pushes, reward terms, tracking errors, torques, the task's masks.
//! - The Rerun modules are built with the `rerun` feature (on by default; the Python
//!   package leaves it off, and an `.rrd` is then an error naming the feature).
//! - `episodes`: a policy's episodes on a task into a file (`quadcl record`) or a viewer
//!   (`quadcl view`).
//! - `video`: a policy's episodes on one or more tasks side by side as an MP4 video, rendered
//!   on the CPU (`quadcl record --format mp4`, `quadcl eval --video`).

mod episodes;
mod foxglove;
mod mcap;
mod recorder;
#[cfg(feature = "rerun")]
mod rerun;
#[cfg(feature = "rerun")]
mod rerun_scene;
mod sample;
mod video;

pub use self::mcap::TOPICS;
#[cfg(feature = "rerun")]
pub use self::rerun::{RerunSink, CONNECT_WAIT, TIMELINE, VIEWER_INSTALL};
#[cfg(feature = "rerun")]
pub use episodes::view_policy;
pub use episodes::{record_episodes, RecordFormat, RecordOptions, RecordSummary, MAX_SECONDS};
pub use recorder::Recorder;
#[cfg(feature = "rerun")]
pub use rerun_scene::{RerunScene, ROBOT_ENTITY};
pub use video::{filmstrip, record_video, Filmstrip, VideoSize};
