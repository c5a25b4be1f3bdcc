//! Reference samples of an export: the observation histories of a short
//! deterministic rollout of the task with the policy itself, and the actions
//! and joint targets quadcl's own forward (the candle networks, the masks
//! applied) gives on them. The export's self-check compares the dense copy with
//! them; `--reference FILE` writes them as safetensors (`obs_history`
//! (rows, H * obs), `actions` (rows, act), `joint_targets` (rows, act)) for a
//! runtime's parity check.

use super::dense_policy::DensePolicy;
use crate::nn::checkpoint::tensors::{f32_raw, serialize};
use crate::rl::{LoadedPolicy, SimTrainEnv, TrainEnv};
use crate::sim::Perturbation;
use anyhow::Context;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Environments of the rollout.
pub const SAMPLE_ENVS: usize = 8;
/// Control steps of the rollout (every environment's history at each is a sample).
pub const SAMPLE_STEPS: usize = 25;

/// Observation histories and the policy's outputs on them.
#[derive(Debug, Clone)]
pub struct Samples {
    /// (rows, H * obs).
    pub obs_history: Vec<f32>,
    /// (rows, act): the policy's means, clipped as the simulator clips them.
    pub actions: Vec<f32>,
    /// (rows, act).
    pub joint_targets: Vec<f32>,
    pub history_width: usize,
    pub act_dim: usize,
}

/// Steps `envs` environments of the policy's task for `steps` control steps with the policy's
/// deterministic actions (commands, randomisation and pushes as its training config has them,
/// seed 0) and keeps every history the policy acted on.
pub fn rollout_samples(
    loaded: &LoadedPolicy,
    policy: &DensePolicy,
    envs: usize,
    steps: usize,
) -> anyhow::Result<Samples> {
    let agent = &loaded.agent;
    let task: Perturbation = policy.task.parse().with_context(|| format!("task {:?}", policy.task))?;
    let mut env = SimTrainEnv::new(&loaded.info.config.env, &task, envs, 0)?;
    let weights = agent.acting_weights()?;
    let mut samples = Samples {
        obs_history: Vec::new(),
        actions: Vec::new(),
        joint_targets: Vec::new(),
        history_width: policy.history_width(),
        act_dim: policy.act_dim,
    };
    for _ in 0..steps {
        let means = agent.act_deterministic_with(&weights, env.observations(), env.obs_histories())?;
        let actions: Vec<f32> = means.iter().map(|a| a.clamp(-policy.clip_actions, policy.clip_actions)).collect();
        samples.obs_history.extend_from_slice(env.obs_histories());
        samples.joint_targets.extend(policy.joint_targets(&actions));
        samples.actions.extend_from_slice(&actions);
        env.step(&means)?;
    }
    Ok(samples)
}

impl Samples {
    /// The largest absolute difference between `policy`'s outputs and the samples'.
    pub fn max_difference(&self, policy: &DensePolicy) -> anyhow::Result<f32> {
        let out = policy.forward(&self.obs_history)?;
        let diff = |a: &[f32], b: &[f32]| a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
        anyhow::ensure!(out.actions.len() == self.actions.len(), "the dense copy gave {} actions", out.actions.len());
        Ok(diff(&out.actions, &self.actions).max(diff(&out.joint_targets, &self.joint_targets)))
    }

    /// Writes the samples as safetensors (atomically), the task in the metadata.
    pub fn save(&self, path: &Path, task: &str) -> anyhow::Result<()> {
        let rows = self.actions.len() / self.act_dim;
        let mut tensors = BTreeMap::new();
        tensors.insert("obs_history".to_string(), f32_raw(&self.obs_history, vec![rows, self.history_width]));
        tensors.insert("actions".to_string(), f32_raw(&self.actions, vec![rows, self.act_dim]));
        tensors.insert("joint_targets".to_string(), f32_raw(&self.joint_targets, vec![rows, self.act_dim]));
        let meta = HashMap::from([("task".to_string(), task.to_string())]);
        crate::util::write_atomic(path, &serialize(&tensors, Some(meta))?)
            .with_context(|| format!("writing {}", path.display()))
    }
}
