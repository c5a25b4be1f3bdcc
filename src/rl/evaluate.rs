//! Evaluation of a trained policy: deterministic actions (the Gaussian
//! means, the CENet latent at its mean), one episode per environment, so
//! short (fallen) episodes are not over-counted. What `quadcl eval` prints.

use super::agent::Agent;
use super::env::{FinishedEpisode, TrainEnv};
use serde::{Deserialize, Serialize};

/// The figures of one evaluation (the `quadcl eval --json` object).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    /// The task's canonical name (`none`, `crash:FL`, ...).
    pub task: String,
    /// Episodes evaluated (one per environment).
    pub episodes: usize,
    /// Mean episode return (dt-scaled reward sum).
    pub mean_return: f64,
    /// Mean over episodes of the mean |v_xy - v_cmd|, m/s.
    pub lin_vel_err: f64,
    /// Mean over episodes of the mean |w_z - w_cmd|, rad/s.
    pub ang_vel_err: f64,
    /// Fraction of episodes that ended by a fall.
    pub fall_rate: f64,
    /// Mean simulated seconds survived.
    pub survival_s: f64,
    /// Standard deviation of the episode returns.
    pub return_std: f64,
    /// The evaluation seed.
    pub seed: u64,
}

/// Runs every member of `env` for one episode with `agent`'s deterministic
/// policy and summarises them. `max_steps` bounds the loop (an env that never
/// ends an episode is an error, naming how many did).
pub fn evaluate(
    agent: &Agent,
    env: &mut dyn TrainEnv,
    task: &str,
    seed: u64,
    max_steps: usize,
) -> anyhow::Result<EvalReport> {
    let n = env.num_envs();
    let mut first: Vec<Option<FinishedEpisode>> = vec![None; n];
    let mut done = 0;
    for _ in 0..max_steps {
        let actions = agent.act_deterministic(env.observations(), env.obs_histories())?;
        let step = env.step(&actions)?;
        for episode in step.finished {
            anyhow::ensure!(episode.env_index < n, "episode from env {} of {n}", episode.env_index);
            let slot = &mut first[episode.env_index];
            if slot.is_none() {
                *slot = Some(episode);
                done += 1;
            }
        }
        if done == n {
            break;
        }
    }
    anyhow::ensure!(done == n, "evaluation: only {done} of {n} episodes ended within {max_steps} steps");
    let episodes: Vec<FinishedEpisode> = first.into_iter().flatten().collect();
    Ok(summarize(task, seed, &episodes))
}

/// The report over finished episodes.
pub fn summarize(task: &str, seed: u64, episodes: &[FinishedEpisode]) -> EvalReport {
    let count = episodes.len().max(1) as f64;
    let mean = |f: &dyn Fn(&FinishedEpisode) -> f64| episodes.iter().map(f).sum::<f64>() / count;
    let mean_return = mean(&|e| e.episode_return);
    let variance = mean(&|e| (e.episode_return - mean_return).powi(2));
    EvalReport {
        task: task.to_string(),
        episodes: episodes.len(),
        mean_return,
        lin_vel_err: mean(&|e| e.lin_vel_err),
        ang_vel_err: mean(&|e| e.ang_vel_err),
        fall_rate: mean(&|e| f64::from(u8::from(e.fell))),
        survival_s: mean(&|e| e.length_s),
        return_std: variance.sqrt(),
        seed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn episode(ret: f64, fell: bool, len: f64) -> FinishedEpisode {
        FinishedEpisode { env_index: 0, episode_return: ret, length_s: len, lin_vel_err: 0.2, ang_vel_err: 0.4, fell }
    }

    #[test]
    fn summary_averages_returns_falls_and_survival() {
        let r = summarize("none", 3, &[episode(1.0, false, 20.0), episode(3.0, true, 5.0)]);
        assert_eq!(r.episodes, 2);
        assert_eq!(r.mean_return, 2.0);
        assert_eq!(r.return_std, 1.0);
        assert_eq!(r.fall_rate, 0.5);
        assert_eq!(r.survival_s, 12.5);
        assert!((r.lin_vel_err - 0.2).abs() < 1e-12);
    }
}
