//! One learned task of a policy as plain dense networks: what the robot runs
//! for that task, with no masks, no task heads and no quadcl types left.
//!
//! For a masked network each layer's weight is W * M_t with the task's bias
//! b_t (the recall the checkpoint guarantees); for a dense method it is the
//! shared trunk with the task's head. Shapes, for N observations:
//!
//! - input: the observation history (N, H * obs), oldest frame first; its last
//!   frame is the current observation;
//! - normalised: clip((x - mean) * scale, -clip, clip), per feature of a frame
//!   (scale = 1 / sqrt(var + 1e-8)), the same statistics for every frame;
//! - CENet encoder on the normalised history: (N, 3 + 2 L); the context is its
//!   first 3 + L columns (velocity estimate, latent mean);
//! - actor on `[obs | context]`: (N, act) action means;
//! - actions: clip(means, -clip_actions, clip_actions), what the simulator applies;
//! - joint targets: default pose + action_scale * actions, within the joint limits.
//!
//! [`DensePolicy::forward`] computes all of that in plain f32 loops: the
//! reference the exported graphs are written from and tested against.

use crate::config::net::Activation;
use crate::rl::LoadedPolicy;
use anyhow::Context;

/// One linear layer: y = x W^T + b.
#[derive(Debug, Clone)]
pub struct DenseLayer {
    /// (outputs, inputs) row-major, as PyTorch's `nn.Linear.weight`.
    pub weight: Vec<f32>,
    /// (outputs,).
    pub bias: Vec<f32>,
    pub inputs: usize,
    pub outputs: usize,
}

/// An MLP: every layer but the last followed by the activation.
#[derive(Debug, Clone)]
pub struct DenseNet {
    pub layers: Vec<DenseLayer>,
    pub activation: Activation,
}

/// The observation normaliser of a task.
#[derive(Debug, Clone)]
pub struct ObsNormalizer {
    /// (obs,) per-feature mean.
    pub mean: Vec<f32>,
    /// (obs,) 1 / sqrt(var + 1e-8).
    pub scale: Vec<f32>,
    /// Normalised values are clipped to [-clip, clip].
    pub clip: f32,
}

/// A learned task as dense networks and the action transform around them.
#[derive(Debug, Clone)]
pub struct DensePolicy {
    /// The task whose parameters these are.
    pub task: String,
    pub obs_dim: usize,
    pub history_len: usize,
    pub act_dim: usize,
    /// None when the policy was trained on raw observations.
    pub normalizer: Option<ObsNormalizer>,
    /// The CENet encoder and the context width it feeds the actor (3 + latent); None without CENet.
    pub encoder: Option<(DenseNet, usize)>,
    pub actor: DenseNet,
    pub clip_actions: f32,
    pub action_scale: f32,
    /// (act,) the standing pose the actions are offsets from, rad.
    pub default_pose: Vec<f32>,
    /// (act,) joint limits the targets are kept within, rad (infinite when unlimited).
    pub joint_lower: Vec<f32>,
    pub joint_upper: Vec<f32>,
}

/// What [`DensePolicy::forward`] gives for N observation histories.
#[derive(Debug, Clone, PartialEq)]
pub struct PolicyOutput {
    /// (N, act) the clipped actions.
    pub actions: Vec<f32>,
    /// (N, act) joint position targets, rad.
    pub joint_targets: Vec<f32>,
}

impl DenseNet {
    /// The layers of `net` for `task` (a masked network's W * M_t, b_t; a dense one's trunk and head).
    fn of_task(net: &crate::nn::Network, task: crate::nn::TaskId) -> anyhow::Result<Self> {
        let theta: Vec<f32> = net.frozen_weights(Some(task))?.theta().to_vec1()?;
        let sizes = net.sizes();
        let mut layers = Vec::with_capacity(sizes.len() - 1);
        let mut at = 0;
        for pair in sizes.windows(2) {
            let (inputs, outputs) = (pair[0], pair[1]);
            let weight = theta.get(at..at + inputs * outputs).context("weights shorter than the sizes")?.to_vec();
            at += inputs * outputs;
            let bias = theta.get(at..at + outputs).context("weights shorter than the sizes")?.to_vec();
            at += outputs;
            layers.push(DenseLayer { weight, bias, inputs, outputs });
        }
        anyhow::ensure!(at == theta.len(), "{}: {} weights for sizes {sizes:?}", net.name(), theta.len());
        Ok(Self { layers, activation: net.activation() })
    }

    /// (N, inputs) -> (N, outputs).
    pub fn forward(&self, x: &[f32]) -> Vec<f32> {
        let last = self.layers.len() - 1;
        let mut h = x.to_vec();
        for (i, l) in self.layers.iter().enumerate() {
            let rows = h.len() / l.inputs;
            let mut out = vec![0.0f32; rows * l.outputs];
            for r in 0..rows {
                let row = &h[r * l.inputs..(r + 1) * l.inputs];
                for o in 0..l.outputs {
                    let w = &l.weight[o * l.inputs..(o + 1) * l.inputs];
                    let z = l.bias[o] + row.iter().zip(w).map(|(a, b)| a * b).sum::<f32>();
                    out[r * l.outputs + o] = if i < last { activate(self.activation, z) } else { z };
                }
            }
            h = out;
        }
        h
    }
}

fn activate(a: Activation, z: f32) -> f32 {
    match a {
        Activation::Elu => {
            if z > 0.0 {
                z
            } else {
                z.exp_m1()
            }
        }
        Activation::Relu => z.max(0.0),
        Activation::Tanh => z.tanh(),
        Activation::Identity => z,
    }
}

impl DensePolicy {
    /// The task `loaded` recalls, with the robot's standing pose and joint limits.
    pub fn from_loaded(loaded: &LoadedPolicy, default_pose: &[f32], limits: &[(f32, f32)]) -> anyhow::Result<Self> {
        let agent = &loaded.agent;
        let dims = agent.dims;
        let task = loaded.tasks.get(agent.task).context("the policy's task has no name")?.clone();
        let env = &loaded.info.config.env;
        let normalizer = agent.normalizes().then(|| {
            let n = &agent.obs_normalizer;
            ObsNormalizer { mean: n.mean(), scale: n.scale(), clip: n.clip() }
        });
        let encoder = if agent.use_cenet {
            Some((DenseNet::of_task(&agent.encoder, agent.task)?, 3 + agent.latent_dim))
        } else {
            None
        };
        anyhow::ensure!(
            default_pose.len() == dims.act && limits.len() == dims.act,
            "the robot has not {} joints",
            dims.act
        );
        Ok(Self {
            task,
            obs_dim: dims.obs,
            history_len: dims.history_len,
            act_dim: dims.act,
            normalizer,
            encoder,
            actor: DenseNet::of_task(&agent.actor, agent.task)?,
            clip_actions: env.clip_actions,
            action_scale: env.action_scale,
            default_pose: default_pose.to_vec(),
            joint_lower: limits.iter().map(|l| l.0).collect(),
            joint_upper: limits.iter().map(|l| l.1).collect(),
        })
    }

    /// Width of the input: H * obs.
    pub fn history_width(&self) -> usize {
        self.history_len * self.obs_dim
    }

    /// Actions and joint targets for observation histories (N, H * obs).
    pub fn forward(&self, history: &[f32]) -> anyhow::Result<PolicyOutput> {
        let width = self.history_width();
        anyhow::ensure!(
            !history.is_empty() && history.len() % width == 0,
            "{} values are not rows of an observation history ({width})",
            history.len()
        );
        let mut h = history.to_vec();
        if let Some(n) = &self.normalizer {
            for frame in h.chunks_exact_mut(self.obs_dim) {
                for ((x, m), s) in frame.iter_mut().zip(&n.mean).zip(&n.scale) {
                    *x = ((*x - m) * s).clamp(-n.clip, n.clip);
                }
            }
        }
        let rows = h.len() / width;
        let context = match &self.encoder {
            Some((net, context)) => {
                let out = net.forward(&h);
                let width = out.len() / rows;
                out.chunks_exact(width).flat_map(|r| r[..*context].to_vec()).collect()
            }
            None => Vec::new(),
        };
        let context_width = context.len() / rows;
        let actor_in: Vec<f32> = (0..rows)
            .flat_map(|r| {
                let obs = &h[(r + 1) * width - self.obs_dim..(r + 1) * width];
                obs.iter().chain(&context[r * context_width..(r + 1) * context_width]).copied().collect::<Vec<_>>()
            })
            .collect();
        let means = self.actor.forward(&actor_in);
        let actions: Vec<f32> = means.iter().map(|a| a.clamp(-self.clip_actions, self.clip_actions)).collect();
        let joint_targets = self.joint_targets(&actions);
        Ok(PolicyOutput { actions, joint_targets })
    }

    /// Joint targets (N, act) for clipped actions (N, act): what the simulator's PD motors track.
    pub fn joint_targets(&self, actions: &[f32]) -> Vec<f32> {
        actions
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let j = i % self.act_dim;
                (self.default_pose[j] + self.action_scale * a).clamp(self.joint_lower[j], self.joint_upper[j])
            })
            .collect()
    }
}
