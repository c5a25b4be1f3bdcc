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
//! - `episodes`: a policy's episodes on a task into a file (`quadcl record`) or a viewer
//!   (`quadcl view`).

mod episodes;
mod foxglove;
mod mcap;
mod recorder;
mod rerun;
mod rerun_scene;
mod sample;

pub use self::mcap::TOPICS;
pub use self::rerun::{RerunSink, CONNECT_WAIT, TIMELINE, VIEWER_INSTALL};
pub use episodes::{record_episodes, view_policy, RecordFormat, RecordOptions, RecordSummary, MAX_SECONDS};
pub use recorder::Recorder;
pub use rerun_scene::{RerunScene, ROBOT_ENTITY};
