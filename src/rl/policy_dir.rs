//! Saving and loading a trained policy directory through `nn::checkpoint`:
//! the four masked networks (base weights, per-task masks and biases), and as
//! extras per task t: `log_std.t{t}` (the policy's action log-std),
//! `obs_normalizer.t{t}.{mean,var,count}` and
//! `privileged_normalizer.t{t}.{mean,var,count}`. The manifest's config is a
//! [`PolicyInfo`]: the run's full [`Config`], the env widths the networks
//! were built for, and iterations trained.

use super::agent::Agent;
use super::env::EnvDims;
use super::normalizer::RunningNormalizer;
use crate::config::Config;
use crate::nn::{checkpoint, TaskId};
use anyhow::Context;
use candle_core::{Device, Tensor};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// What `quadcl train` stores as the checkpoint's config.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PolicyInfo {
    /// The whole configuration of the run.
    pub config: Config,
    /// Environment widths the networks were built for.
    pub dims: EnvDims,
    /// Training iterations completed.
    pub iterations: usize,
}

/// A loaded policy: the agent in recall mode on its task, the task names and the info.
#[derive(Debug)]
pub struct LoadedPolicy {
    pub agent: Agent,
    pub tasks: Vec<String>,
    pub info: PolicyInfo,
}

impl LoadedPolicy {
    /// The learned task whose network acts (`load_for_task` of a task the policy never learned
    /// acts with its last learned task's: this names it).
    pub fn recalled_task(&self) -> Option<&str> {
        self.tasks.get(self.agent.task()).map(String::as_str)
    }
}

fn put_normalizer(prefix: &str, n: &RunningNormalizer, out: &mut BTreeMap<String, Tensor>) -> anyhow::Result<()> {
    out.insert(format!("{prefix}.mean"), Tensor::new(n.mean().as_slice(), &Device::Cpu)?);
    out.insert(format!("{prefix}.var"), Tensor::new(n.var().as_slice(), &Device::Cpu)?);
    out.insert(format!("{prefix}.count"), Tensor::new(&[n.count() as f32], &Device::Cpu)?);
    Ok(())
}

fn get_normalizer(prefix: &str, extras: &BTreeMap<String, Tensor>, clip: f32) -> anyhow::Result<RunningNormalizer> {
    let get = |key: &str| {
        extras.get(&format!("{prefix}.{key}")).with_context(|| format!("missing extra tensor {prefix}.{key}"))
    };
    let count = get("count")?.flatten_all()?.to_vec1::<f32>()?.first().copied().unwrap_or(0.0);
    RunningNormalizer::from_saved(
        &get("mean")?.to_vec1::<f32>()?,
        &get("var")?.to_vec1::<f32>()?,
        f64::from(count),
        clip,
    )
}

/// Writes `agent` after its task ended (`agent.end_task`) to `dir`.
/// `tasks[t]` names task id t.
pub fn save_policy(agent: &Agent, tasks: &[String], info: &PolicyInfo, dir: &Path) -> anyhow::Result<()> {
    anyhow::ensure!(agent.task < tasks.len(), "task id {} has no name among {} tasks", agent.task, tasks.len());
    let t = agent.task;
    let mut extras = BTreeMap::new();
    extras.insert(format!("log_std.t{t}"), agent.log_std.as_tensor().copy()?);
    put_normalizer(&format!("obs_normalizer.t{t}"), &agent.obs_normalizer, &mut extras)?;
    put_normalizer(&format!("privileged_normalizer.t{t}"), &agent.privileged_normalizer, &mut extras)?;
    checkpoint::save_policy(dir, tasks, &agent.saved_networks(), &extras, &serde_json::to_value(info)?)
}

/// Reads a policy directory and returns the agent recalling task `task`
/// (by name; `None`: the last task learned, or the task in training). A task
/// the policy names but has not learned yet (a sequence's checkpoint lists
/// every task of the sequence) is an error. Errors name the directory and what is wrong.
pub fn load_policy(dir: &Path, task: Option<&str>) -> anyhow::Result<LoadedPolicy> {
    let policy = checkpoint::load_policy(dir)?;
    let info: PolicyInfo = serde_json::from_value(policy.config.clone())
        .with_context(|| format!("{}: the manifest's config is not a quadcl training config", dir.display()))?;
    let mut policy = policy;
    let mut agent = Agent::new(info.dims, &info.config, info.config.seed)?;
    agent.actor = policy.take_network("actor", dir)?;
    agent.critic = policy.take_network("critic", dir)?;
    agent.encoder = policy.take_network("cenet_encoder", dir)?;
    agent.decoder = policy.take_network("cenet_decoder", dir)?;
    // A sequence's checkpoint names every task of the sequence, learned or not.
    let learned = learned_tasks(&agent.actor);
    let task_id: TaskId = match task {
        Some(name) => {
            let t = policy
                .tasks
                .iter()
                .position(|t| t == name)
                .with_context(|| format!("{}: no task {name:?}; it has {:?}", dir.display(), policy.tasks))?;
            anyhow::ensure!(
                learned.contains(&t),
                "{}: task {name:?} is not learned yet; learned: {:?}",
                dir.display(),
                task_names(&policy.tasks, &learned)
            );
            t
        }
        None => agent
            .actor
            .current_task()
            .or(learned.last().copied())
            .with_context(|| format!("{}: the policy has learned no task", dir.display()))?,
    };
    let extras = &policy.extras;
    let log_std = extras
        .get(&format!("log_std.t{task_id}"))
        .with_context(|| format!("{}: missing log_std.t{task_id}", dir.display()))?;
    agent.log_std.set(log_std)?;
    let clip = info.config.ppo.obs_clip as f32;
    agent.obs_normalizer = get_normalizer(&format!("obs_normalizer.t{task_id}"), extras, clip)
        .with_context(|| dir.display().to_string())?;
    agent.privileged_normalizer = get_normalizer(&format!("privileged_normalizer.t{task_id}"), extras, clip)
        .with_context(|| dir.display().to_string())?;
    agent.task = task_id;
    agent.recall = true;
    Ok(LoadedPolicy { agent, tasks: policy.tasks, info })
}

/// The tasks a network has learned or is training, in the order they were first trained.
fn learned_tasks(net: &crate::nn::Network) -> Vec<TaskId> {
    let mut tasks = net.finished_tasks().to_vec();
    tasks.extend(net.current_task().filter(|t| !tasks.contains(t)));
    tasks
}

fn task_names<'a>(tasks: &'a [String], ids: &[TaskId]) -> Vec<&'a str> {
    ids.iter().filter_map(|&t| tasks.get(t).map(String::as_str)).collect()
}

/// The names of the tasks `policy` has learned (or is training), in the order they were first trained.
pub fn learned_task_names(policy: &LoadedPolicy) -> Vec<&str> {
    task_names(&policy.tasks, &learned_tasks(&policy.agent.actor))
}

/// Reads a checkpoint written while its last task was still training (see
/// `trainer`) and returns the agent ready to go on training that task: the
/// networks keep their soft scores and training state, the observation
/// statistics follow the data again. A policy whose tasks all ended is an
/// error: a finished task can only be repeated (METHOD 2.5), not resumed.
pub fn load_training_checkpoint(dir: &Path) -> anyhow::Result<LoadedPolicy> {
    into_training(load_policy(dir, None)?, dir)
}

/// The checks and mode changes of [`load_training_checkpoint`] on a policy already read from `dir`.
fn into_training(mut loaded: LoadedPolicy, dir: &Path) -> anyhow::Result<LoadedPolicy> {
    let task = loaded.agent.task;
    for net in loaded.agent.networks() {
        anyhow::ensure!(
            net.current_task() == Some(task),
            "{}: network {} is not training task {} ({:?}): not a checkpoint of a run in progress",
            dir.display(),
            net.name(),
            loaded.tasks[task],
            net.current_task()
        );
    }
    loaded.agent.recall = false;
    loaded.agent.obs_normalizer.unfreeze();
    loaded.agent.privileged_normalizer.unfreeze();
    Ok(loaded)
}

/// A policy, or a training checkpoint whose task was ended in memory.
#[derive(Debug)]
pub struct PolicyOrCheckpoint {
    pub policy: LoadedPolicy,
    /// Whether `dir` was a checkpoint of a task still training.
    pub in_progress: bool,
}

/// Loads a policy directory (its last task), or a training checkpoint (`RUN/checkpoint` of
/// `quadcl train`) as if its task ended now: METHOD 2.4's masks, the top-k of the current
/// score means without noise. How a long run is evaluated while it trains.
pub fn load_policy_or_checkpoint(dir: &Path) -> anyhow::Result<PolicyOrCheckpoint> {
    let loaded = load_policy(dir, None)?;
    if loaded.agent.networks().iter().all(|n| n.current_task().is_none()) {
        return Ok(PolicyOrCheckpoint { policy: loaded, in_progress: false });
    }
    let mut policy = into_training(loaded, dir)?;
    tracing::info!(
        "{}: task {:?} is still training; using the masks its score means give now",
        dir.display(),
        policy.tasks[policy.agent.task]
    );
    // end_task also redraws the vacant weights for a next task: they play no part in this one.
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(0);
    policy.agent.end_task(&mut rng)?;
    Ok(PolicyOrCheckpoint { policy, in_progress: true })
}

/// What `quadcl eval` and `quadcl gait` run on `task`: a policy that learned `task` recalls
/// it; any other policy (a base policy run on a perturbation, or a sequence's checkpoint
/// from before `task`) uses its last learned task; a checkpoint still training uses its
/// task, ended in memory ([`load_policy_or_checkpoint`]).
pub fn load_for_task(dir: &Path, task: &str) -> anyhow::Result<LoadedPolicy> {
    let loaded = load_policy_or_checkpoint(dir)?;
    let learned = learned_task_names(&loaded.policy);
    if !loaded.in_progress && learned.len() > 1 && learned.contains(&task) {
        return load_policy(dir, Some(task));
    }
    Ok(loaded.policy)
}
