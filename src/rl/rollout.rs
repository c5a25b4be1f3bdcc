//! The rollout buffer of one PPO iteration and generalised advantage
//! estimation (GAE, Schulman et al. 2016) with legged_gym's time-out
//! bootstrapping.
//!
//! Everything is a flat `Vec<f32>` in step-major order: row `t * num_envs + e`
//! is environment `e` at step `t`. Shapes (T = steps per env, N = envs):
//!
//! | field | shape |
//! | --- | --- |
//! | `obs` | (T, N, obs_dim), normalised |
//! | `privileged_obs` | (T, N, priv_obs_dim), normalised |
//! | `obs_history` | (T, N, history_dim), normalised, oldest first |
//! | `context` | (T, N, context), the CENet estimate (velocity, latent sample) the actor saw |
//! | `next_obs` | (T, N, obs_dim), normalised obs reached by the step (before auto-reset) |
//! | `base_velocity` | (T, N, 3), the CENet's velocity target |
//! | `actions`, `action_means` | (T, N, act_dim) |
//! | `log_probs`, `values`, `rewards` | (T, N) |
//! | `terminated`, `truncated` | (T, N) |
//!
//! Time-outs: an episode cut by the time limit did not end in the MDP, so the
//! value of the state it would have continued from is added to its last
//! reward: `r_t += gamma * V(s_t)` (legged_gym's approximation: V(s_t), the
//! value of the state the action was taken in, stands in for the unseen
//! V(s_{t+1})). A termination (a fall) is not bootstrapped.

use rand::seq::SliceRandom;
use rand::Rng;

/// Widths of the per-transition vectors stored in a [`RolloutBuffer`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RolloutDims {
    /// Actor observation width (45 for the A1).
    pub obs: usize,
    /// Privileged (critic) observation width.
    pub privileged_obs: usize,
    /// Width of the CENet's observation history (history length * obs).
    pub obs_history: usize,
    /// Action width (12).
    pub act: usize,
    /// Width of the CENet context the actor sees besides the observation (3 + latent, or 0).
    pub context: usize,
}

/// One iteration's transitions; see the module doc for the layout.
#[derive(Debug, Clone)]
pub struct RolloutBuffer {
    pub(crate) dims: RolloutDims,
    pub(crate) num_steps: usize,
    pub(crate) num_envs: usize,
    /// Steps written so far (0..=num_steps).
    pub(crate) len: usize,
    pub(crate) obs: Vec<f32>,
    pub(crate) privileged_obs: Vec<f32>,
    pub(crate) obs_history: Vec<f32>,
    pub(crate) context: Vec<f32>,
    pub(crate) next_obs: Vec<f32>,
    pub(crate) base_velocity: Vec<f32>,
    pub(crate) actions: Vec<f32>,
    pub(crate) action_means: Vec<f32>,
    pub(crate) log_probs: Vec<f32>,
    pub(crate) values: Vec<f32>,
    pub(crate) rewards: Vec<f32>,
    pub(crate) terminated: Vec<bool>,
    pub(crate) truncated: Vec<bool>,
    /// (T, N), filled by [`RolloutBuffer::compute_returns`].
    pub(crate) advantages: Vec<f32>,
    /// (T, N), advantages + values: the critic's regression target.
    pub(crate) returns: Vec<f32>,
}

/// What the learner observed and decided at one step of all environments.
/// Every slice is row-major with `num_envs` rows.
#[derive(Debug, Clone, Copy)]
pub struct RolloutRow<'a> {
    pub obs: &'a [f32],
    pub privileged_obs: &'a [f32],
    pub obs_history: &'a [f32],
    pub context: &'a [f32],
    pub next_obs: &'a [f32],
    pub base_velocity: &'a [f32],
    pub actions: &'a [f32],
    pub action_means: &'a [f32],
    pub log_probs: &'a [f32],
    pub values: &'a [f32],
    pub rewards: &'a [f32],
    pub terminated: &'a [bool],
    pub truncated: &'a [bool],
}

impl RolloutBuffer {
    /// An empty buffer for `num_steps` steps of `num_envs` environments.
    pub fn new(dims: RolloutDims, num_steps: usize, num_envs: usize) -> Self {
        let rows = num_steps * num_envs;
        Self {
            dims,
            num_steps,
            num_envs,
            len: 0,
            obs: Vec::with_capacity(rows * dims.obs),
            privileged_obs: Vec::with_capacity(rows * dims.privileged_obs),
            obs_history: Vec::with_capacity(rows * dims.obs_history),
            context: Vec::with_capacity(rows * dims.context),
            next_obs: Vec::with_capacity(rows * dims.obs),
            base_velocity: Vec::with_capacity(rows * 3),
            actions: Vec::with_capacity(rows * dims.act),
            action_means: Vec::with_capacity(rows * dims.act),
            log_probs: Vec::with_capacity(rows),
            values: Vec::with_capacity(rows),
            rewards: Vec::with_capacity(rows),
            terminated: Vec::with_capacity(rows),
            truncated: Vec::with_capacity(rows),
            advantages: Vec::new(),
            returns: Vec::new(),
        }
    }

    /// Transitions the buffer holds when full.
    pub fn capacity(&self) -> usize {
        self.num_steps * self.num_envs
    }

    /// Forgets every transition (keeps the allocations).
    pub fn clear(&mut self) {
        self.len = 0;
        for v in [
            &mut self.obs,
            &mut self.privileged_obs,
            &mut self.obs_history,
            &mut self.context,
            &mut self.next_obs,
            &mut self.base_velocity,
            &mut self.actions,
            &mut self.action_means,
            &mut self.log_probs,
            &mut self.values,
            &mut self.rewards,
            &mut self.advantages,
            &mut self.returns,
        ] {
            v.clear();
        }
        self.terminated.clear();
        self.truncated.clear();
    }

    /// Appends one step of all environments. Errors if the buffer is full or a
    /// slice has the wrong length (naming the field).
    pub fn push(&mut self, step: &RolloutRow<'_>) -> anyhow::Result<()> {
        anyhow::ensure!(self.len < self.num_steps, "rollout buffer is full ({} steps)", self.num_steps);
        let n = self.num_envs;
        let d = self.dims;
        let check = |name: &str, got: usize, width: usize| {
            anyhow::ensure!(got == n * width, "rollout field {name}: expected {n} x {width} values, got {got}");
            Ok(())
        };
        check("obs", step.obs.len(), d.obs)?;
        check("privileged_obs", step.privileged_obs.len(), d.privileged_obs)?;
        check("obs_history", step.obs_history.len(), d.obs_history)?;
        check("context", step.context.len(), d.context)?;
        check("next_obs", step.next_obs.len(), d.obs)?;
        check("base_velocity", step.base_velocity.len(), 3)?;
        check("actions", step.actions.len(), d.act)?;
        check("action_means", step.action_means.len(), d.act)?;
        check("log_probs", step.log_probs.len(), 1)?;
        check("values", step.values.len(), 1)?;
        check("rewards", step.rewards.len(), 1)?;
        check("terminated", step.terminated.len(), 1)?;
        check("truncated", step.truncated.len(), 1)?;
        self.obs.extend_from_slice(step.obs);
        self.privileged_obs.extend_from_slice(step.privileged_obs);
        self.obs_history.extend_from_slice(step.obs_history);
        self.context.extend_from_slice(step.context);
        self.next_obs.extend_from_slice(step.next_obs);
        self.base_velocity.extend_from_slice(step.base_velocity);
        self.actions.extend_from_slice(step.actions);
        self.action_means.extend_from_slice(step.action_means);
        self.log_probs.extend_from_slice(step.log_probs);
        self.values.extend_from_slice(step.values);
        self.rewards.extend_from_slice(step.rewards);
        self.terminated.extend_from_slice(step.terminated);
        self.truncated.extend_from_slice(step.truncated);
        self.len += 1;
        Ok(())
    }

    /// Fills `advantages` and `returns` with GAE, given the critic's values of
    /// the observations after the last step (`last_values`, (N,)).
    pub fn compute_returns(&mut self, last_values: &[f32], gamma: f32, lambda: f32) -> anyhow::Result<()> {
        anyhow::ensure!(self.len == self.num_steps, "rollout has {} of {} steps", self.len, self.num_steps);
        let (advantages, returns) = gae(
            &self.rewards,
            &self.values,
            &self.terminated,
            &self.truncated,
            last_values,
            self.num_envs,
            gamma,
            lambda,
        )?;
        self.advantages = advantages;
        self.returns = returns;
        Ok(())
    }
}

/// GAE over a (T, N) step-major rollout, returning `(advantages, returns)`.
///
/// Per step: `r' = r + gamma * V(s_t)` if truncated and not terminated;
/// `not_done = 0` if terminated or truncated (the env auto-reset, so the next
/// row belongs to a new episode);
/// `delta = r' + gamma * V_next * not_done - V(s_t)`;
/// `A_t = delta + gamma * lambda * not_done * A_{t+1}`; `R_t = A_t + V(s_t)`.
#[allow(clippy::too_many_arguments)]
pub fn gae(
    rewards: &[f32],
    values: &[f32],
    terminated: &[bool],
    truncated: &[bool],
    last_values: &[f32],
    num_envs: usize,
    gamma: f32,
    lambda: f32,
) -> anyhow::Result<(Vec<f32>, Vec<f32>)> {
    let rows = rewards.len();
    anyhow::ensure!(num_envs > 0 && rows % num_envs == 0, "GAE: {rows} rewards is not a multiple of {num_envs} envs");
    anyhow::ensure!(
        values.len() == rows && terminated.len() == rows && truncated.len() == rows,
        "GAE: rewards, values, terminated, truncated must have the same length ({rows})"
    );
    anyhow::ensure!(
        last_values.len() == num_envs,
        "GAE: last_values has {} entries, expected {num_envs}",
        last_values.len()
    );
    let num_steps = rows / num_envs;
    let mut advantages = vec![0.0f32; rows];
    for (e, &last_value) in last_values.iter().enumerate() {
        let mut next_advantage = 0.0f32;
        let mut next_value = last_value;
        for t in (0..num_steps).rev() {
            let i = t * num_envs + e;
            let bootstrap = truncated[i] && !terminated[i];
            let reward = rewards[i] + if bootstrap { gamma * values[i] } else { 0.0 };
            let not_done = if terminated[i] || truncated[i] { 0.0 } else { 1.0 };
            let delta = reward + gamma * next_value * not_done - values[i];
            next_advantage = delta + gamma * lambda * not_done * next_advantage;
            advantages[i] = next_advantage;
            next_value = values[i];
        }
    }
    let returns = advantages.iter().zip(values).map(|(a, v)| a + v).collect();
    Ok((advantages, returns))
}

/// A random partition of `0..batch` into `minibatches` index lists of
/// near-equal size (sizes differ by at most one), drawn from `rng`.
pub fn minibatch_indices(batch: usize, minibatches: usize, rng: &mut impl Rng) -> Vec<Vec<usize>> {
    let mut order: Vec<usize> = (0..batch).collect();
    order.shuffle(rng);
    let minibatches = minibatches.clamp(1, batch.max(1));
    let mut out = Vec::with_capacity(minibatches);
    let mut start = 0;
    for k in 0..minibatches {
        let size = batch / minibatches + usize::from(k < batch % minibatches);
        out.push(order[start..start + size].to_vec());
        start += size;
    }
    out
}

/// Gathers rows `indices` of a row-major `(rows, width)` matrix into a new
/// contiguous `(indices.len(), width)` one.
pub fn gather_rows(data: &[f32], width: usize, indices: &[usize]) -> Vec<f32> {
    let mut out = Vec::with_capacity(indices.len() * width);
    for &i in indices {
        out.extend_from_slice(&data[i * width..(i + 1) * width]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn close(a: &[f32], b: &[f32]) {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() < 1e-5, "{a:?} vs {b:?}");
        }
    }

    /// One env, three steps, no episode end: hand-computed with
    /// gamma = 0.5, lambda = 0.5.
    /// delta_2 = 1 + 0.5*4 - 3 = 0;  A_2 = 0
    /// delta_1 = 2 + 0.5*3 - 2 = 1.5; A_1 = 1.5 + 0.25*0 = 1.5
    /// delta_0 = 0 + 0.5*2 - 1 = 0;   A_0 = 0 + 0.25*1.5 = 0.375
    #[test]
    fn gae_matches_hand_computed_values_without_episode_end() {
        let (adv, ret) =
            gae(&[0.0, 2.0, 1.0], &[1.0, 2.0, 3.0], &[false; 3], &[false; 3], &[4.0], 1, 0.5, 0.5).unwrap();
        close(&adv, &[0.375, 1.5, 0.0]);
        close(&ret, &[1.375, 3.5, 3.0]);
    }

    /// Two envs interleaved (step-major). Env 0 falls at step 0 (no
    /// bootstrap, the chain is cut); env 1 times out at step 0 (reward gets
    /// gamma * V(s_0), chain cut). gamma = 0.5, lambda = 0.5.
    /// env 0: t=1: delta = 1 + 0.5*10 - 2 = 4, A = 4; t=0 terminated: delta = 1 - 1 = 0, A = 0
    /// env 1: t=1: delta = 0 + 0.5*8 - 4 = 0, A = 0; t=0 truncated: r' = 1 + 0.5*2 = 2,
    ///        delta = 2 - 2 = 0, A = 0.
    #[test]
    fn gae_cuts_at_falls_and_bootstraps_time_outs() {
        let rewards = [1.0, 1.0, 1.0, 0.0];
        let values = [1.0, 2.0, 2.0, 4.0];
        let terminated = [true, false, false, false];
        let truncated = [false, true, false, false];
        let (adv, ret) = gae(&rewards, &values, &terminated, &truncated, &[10.0, 8.0], 2, 0.5, 0.5).unwrap();
        close(&adv, &[0.0, 0.0, 4.0, 0.0]);
        close(&ret, &[1.0, 2.0, 6.0, 4.0]);
    }

    #[test]
    fn a_fall_at_the_time_limit_is_not_bootstrapped() {
        let (adv, _) = gae(&[1.0], &[3.0], &[true], &[true], &[100.0], 1, 0.9, 0.95).unwrap();
        close(&adv, &[1.0 - 3.0]);
    }

    #[test]
    fn gae_with_lambda_one_equals_discounted_return_minus_value() {
        let rewards = [1.0, 2.0, 3.0];
        let values = [0.5, -1.0, 2.0];
        let (adv, _) = gae(&rewards, &values, &[false; 3], &[false; 3], &[5.0], 1, 0.9, 1.0).unwrap();
        let g2 = 3.0 + 0.9 * 5.0;
        let g1 = 2.0 + 0.9 * g2;
        let g0 = 1.0 + 0.9 * g1;
        close(&adv, &[g0 - 0.5, g1 + 1.0, g2 - 2.0]);
    }

    #[test]
    fn gae_rejects_mismatched_lengths() {
        assert!(gae(&[1.0, 2.0], &[1.0], &[false; 2], &[false; 2], &[0.0], 1, 0.9, 0.9).is_err());
    }

    #[test]
    fn minibatches_partition_every_index_exactly_once() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let parts = minibatch_indices(10, 4, &mut rng);
        let sizes: Vec<usize> = parts.iter().map(Vec::len).collect();
        assert_eq!(sizes, vec![3, 3, 2, 2]);
        let mut all: Vec<usize> = parts.concat();
        all.sort_unstable();
        assert_eq!(all, (0..10).collect::<Vec<_>>());
    }

    #[test]
    fn push_rejects_a_field_of_the_wrong_width_by_name() {
        let dims = RolloutDims { obs: 2, privileged_obs: 3, obs_history: 4, act: 1, context: 2 };
        let mut buf = RolloutBuffer::new(dims, 1, 1);
        let z = [0.0f32; 8];
        let b = [false];
        let mut step = RolloutRow {
            obs: &z[..2],
            privileged_obs: &z[..3],
            obs_history: &z[..4],
            context: &z[..2],
            next_obs: &z[..2],
            base_velocity: &z[..3],
            actions: &z[..1],
            action_means: &z[..1],
            log_probs: &z[..1],
            values: &z[..1],
            rewards: &z[..1],
            terminated: &b,
            truncated: &b,
        };
        step.privileged_obs = &z[..2];
        let err = buf.push(&step).unwrap_err().to_string();
        assert!(err.contains("privileged_obs"), "{err}");
        step.privileged_obs = &z[..3];
        buf.push(&step).unwrap();
        assert!(buf.push(&step).is_err(), "a full buffer must refuse another step");
        buf.compute_returns(&[0.0], 0.99, 0.95).unwrap();
        assert_eq!(buf.returns.len(), 1);
    }
}
