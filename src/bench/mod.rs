//! The figures printed by `quadcl bench`: each section adds its keys to one
//! JSON object, so scripts can read them by name.

pub mod env;
pub mod gemm;
pub mod nn;
pub mod ppo;
pub mod record;
pub mod tui;
