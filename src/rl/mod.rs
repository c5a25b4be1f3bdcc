//! The learner: PPO with a privileged critic and a context estimator
//! (DreamWaQ's CENet), issue 4.
//!
//! | file | what |
//! | --- | --- |
//! | [`rollout`] | the rollout buffer of one iteration, GAE with time-out bootstrapping |
//! | [`normalizer`] | running observation statistics, frozen when a task ends |
//! | [`losses`] | the PPO loss pieces (Gaussian log-prob/entropy, clipped surrogate, value loss, KL, adaptive lr) |
//! | [`cenet_loss`] | the CENet's output split, reparameterisation and beta-VAE loss |

pub mod cenet_loss;
pub mod losses;
pub mod normalizer;
pub mod rollout;

pub use normalizer::RunningNormalizer;
pub use rollout::{gae, RolloutBuffer, RolloutDims, StepRecord};
