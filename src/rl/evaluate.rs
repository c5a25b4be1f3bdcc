//! Evaluation of a trained policy: deterministic actions (the Gaussian
//! means, the CENet latent at its mean), one episode per environment, so
//! short (fallen) episodes are not over-counted. What `quadcl eval` prints.

use super::agent::Agent;
use super::env::{EpisodeSummary, TrainEnv};
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
    /// Standard deviation of the episode returns (absent from the evaluations
    /// of sequence runs written before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub return_std: Option<f64>,
    /// The evaluation seed.
    pub seed: u64,
    /// Envs reset because their physics blew up (their cut-short episodes are
    /// not counted; each env's next episode is). Written only when not 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub physics_resets: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
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
    let weights = agent.acting_weights()?;
    let mut policy = |obs: &[f32], histories: &[f32]| agent.act_deterministic_with(&weights, obs, histories);
    evaluate_with(&mut policy, env, task, seed, max_steps)
}

/// A deterministic policy: observations (N, obs) and histories (N, H * obs) to actions (N, act).
pub type PolicyFn<'a> = dyn FnMut(&[f32], &[f32]) -> anyhow::Result<Vec<f32>> + 'a;

/// [`evaluate`] with any policy: `policy(observations (N, obs), histories (N, H * obs))`
/// gives the actions (N, act); an external program's ([`super::ExternalPolicy`]), say.
pub fn evaluate_with(
    policy: &mut PolicyFn<'_>,
    env: &mut dyn TrainEnv,
    task: &str,
    seed: u64,
    max_steps: usize,
) -> anyhow::Result<EvalReport> {
    let n = env.num_envs();
    let mut first: Vec<Option<EpisodeSummary>> = vec![None; n];
    let mut done = 0;
    let mut physics_resets = 0;
    for _ in 0..max_steps {
        let actions = policy(env.observations(), env.obs_histories())?;
        let step = env.step(&actions)?;
        physics_resets += step.physics_resets.len();
        for episode in step.finished {
            anyhow::ensure!(episode.env < n, "episode from env {} of {n}", episode.env);
            let slot = &mut first[episode.env];
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
    let episodes: Vec<EpisodeSummary> = first.into_iter().flatten().collect();
    Ok(EvalReport { physics_resets, ..summarize(task, seed, &episodes) })
}

/// The report over finished episodes.
pub fn summarize(task: &str, seed: u64, episodes: &[EpisodeSummary]) -> EvalReport {
    let count = episodes.len().max(1) as f64;
    let mean = |f: &dyn Fn(&EpisodeSummary) -> f64| episodes.iter().map(f).sum::<f64>() / count;
    let mean_return = mean(&|e| f64::from(e.episode_return));
    let variance = mean(&|e| (f64::from(e.episode_return) - mean_return).powi(2));
    EvalReport {
        task: task.to_string(),
        episodes: episodes.len(),
        mean_return,
        lin_vel_err: mean(&|e| f64::from(e.lin_vel_err)),
        ang_vel_err: mean(&|e| f64::from(e.ang_vel_err)),
        fall_rate: mean(&|e| f64::from(u8::from(e.fell))),
        survival_s: mean(&|e| f64::from(e.length_s)),
        return_std: Some(variance.sqrt()),
        seed,
        physics_resets: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn episode(ret: f32, fell: bool, len: f32) -> EpisodeSummary {
        EpisodeSummary {
            episode_return: ret,
            length_s: len,
            lin_vel_err: 0.25,
            ang_vel_err: 0.4,
            fell,
            ..Default::default()
        }
    }

    #[test]
    fn summary_averages_returns_falls_and_survival() {
        let r = summarize("none", 3, &[episode(1.0, false, 20.0), episode(3.0, true, 5.0)]);
        assert_eq!(r.episodes, 2);
        assert_eq!(r.mean_return, 2.0);
        assert_eq!(r.return_std, Some(1.0));
        assert_eq!(r.fall_rate, 0.5);
        assert_eq!(r.survival_s, 12.5);
        assert!((r.lin_vel_err - 0.25).abs() < 1e-12, "the episodes report f32 figures: 0.25 is exact");
    }
}
