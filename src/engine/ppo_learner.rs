//! The PPO agent of `quadcl::rl` as an engine [`Learner`](super::learner::Learner).
//! (Waits for issue 4's learner to land on main.)

use super::learner::Learner;
use super::run_config::RunConfig;

/// The PPO learner for a run file, with the base policy's tasks.
pub fn make(_cfg: &RunConfig) -> anyhow::Result<(Box<dyn Learner>, Vec<String>)> {
    anyhow::bail!("the PPO learner (issue 4) is not merged yet; use [run] learner = \"toy\"")
}
