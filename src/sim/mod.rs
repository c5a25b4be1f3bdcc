//! The simulated quadruped, in rapier3d only: knows nothing of networks or UI.
//!
//! - `robot`: URDF parsing and validation, legs found by structure.
//! - `physics`: one robot in one rapier world, implicit PD, state read-back.
//! - `terrain`: the ground.
//! - `tasks`: leg perturbations (crash / invert / noise) and their syntax.
//! - [`obs`]: observation and privileged-observation layouts.
//! - [`reward`]: the paper's Table 1, one function per term.
//! - `env`: `LocomotionEnv`, reset(seed) / step(action); `env_setup` its plain helpers.
//! - `episode`: the step result and the finished-episode summary.
//! - `pose`: the robot's world-frame pose (trunk box, leg joints, feet) for drawing it.
//! - `observe`: a step observer attached to one env (recorders), with every link's world pose.
//! - `vec_env`: a batch of envs stepped in parallel with rayon.

mod env;
mod env_setup;
mod episode;
pub mod obs;
mod observe;
mod physics;
mod pose;
pub mod reward;
mod robot;
mod tasks;
mod terrain;
mod vec_env;

pub use env::LocomotionEnv;
pub use episode::{EpisodeSummary, Step};
pub use obs::{ACT_DIM, HISTORY_LEN, OBS_DIM, PRIV_BASE_LIN_VEL, PRIV_OBS_DIM};
pub use observe::{LinkPose, StepInfo, StepObserver};
pub use physics::RawState;
pub use pose::{LegPose, RobotPose};
pub use robot::{Leg, LegJoint, RobotModel, JOINTS_PER_LEG, NUM_LEGS};
pub use tasks::{Perturbation, PerturbationKind};
pub use vec_env::{VecEnv, VecStep};
