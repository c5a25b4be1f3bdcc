//! The simulated quadruped, in rapier3d only: knows nothing of networks or UI.
//!
//! - [`robot`]: URDF parsing and validation, legs found by structure.
//! - [`physics`]: one robot in one rapier world, PD motors, state read-back.
//! - [`terrain`]: the ground.

pub mod physics;
pub mod robot;
pub mod terrain;

pub use robot::{Leg, RobotModel};
