//! The simulated quadruped, in rapier3d only: knows nothing of networks or UI.
//!
//! - `robot`: URDF parsing and validation; `urdf_text` (the tolerant pass over
//!   the text), `urdf_mesh` (meshes to primitives), `urdf_merge` (fixed links
//!   merged), `legs` (trunk, legs and feet found by structure).
//! - [`shipped`]: the robots' files of `scenes/`, compiled in for use away from the sources.
//! - `stand`: the robot settled under PD at its default pose (`quadcl robot`).
//! - `physics`: one robot in one rapier world, implicit PD, state read-back.
//! - `terrain`: the ground.
//! - `tasks`: leg perturbations (crash / invert / noise) and their syntax.
//! - [`obs`]: observation and privileged-observation layouts.
//! - [`reward`]: the paper's Table 1, one function per term.
//! - `env`: `LocomotionEnv`, reset(seed) / step(action); `env/replay` its exact state for
//!   checkpoints (a replay of the current episode); `env_setup` its plain helpers.
//! - `episode`: the step result and the finished-episode summary.
//! - `pose`: the robot's world-frame pose (trunk box, leg joints, feet) for drawing it.
//! - `observe`: a step observer attached to one env (recorders), with every link's world pose.
//! - `vec_env`: a batch of envs stepped in parallel with rayon.

mod env;
mod env_setup;
mod episode;
mod legs;
pub mod obs;
mod observe;
mod physics;
mod pose;
pub mod reward;
mod robot;
pub mod shipped;
mod stand;
mod tasks;
mod terrain;
mod urdf_merge;
mod urdf_mesh;
mod urdf_text;
mod vec_env;

pub use env::{EpisodeReplay, Intervention, LocomotionEnv};
pub use env_setup::{default_pose, joint_gains};
pub use episode::{EpisodeSummary, PhysicsBlowUp, Step};
pub use obs::{ACT_DIM, HISTORY_LEN, OBS_DIM, PRIV_BASE_LIN_VEL, PRIV_OBS_DIM};
pub use observe::{LinkPose, StepInfo, StepObserver};
pub use physics::{Part, PdGains, RawState, WorldShapes};
pub use pose::{LegPose, RobotPose};
pub use robot::{Leg, LegJoint, RobotModel, JOINTS_PER_LEG, NUM_LEGS};
pub use stand::{stand_test, StandReport};
pub use tasks::{Perturbation, PerturbationKind};
pub use urdf_merge::MergedLink;
pub use vec_env::{VecEnv, VecStep};
