//! The PPO agent of `quadcl::rl` (PPO + CENet on the simulated quadruped) as
//! an engine [`Learner`].
//!
//! Per task it keeps what exact recall needs besides the networks (METHOD.md
//! 2.4): the policy's log-std and both observation normalisers, frozen when
//! the task ends. A new task starts from the last trained task's std and
//! statistics; a repeated task (METHOD.md 2.5) starts from its own. Each step
//! gets a fresh optimiser, learner stream and environment batch, all seeded
//! from the step's seed, so a run restored from a checkpoint goes on exactly.
//!
//! Checkpoints are policy directories that `rl::load_policy` and `quadcl eval`
//! read: extras `log_std.t{t}`, `obs_normalizer.t{t}.{mean,var,count}`,
//! `privileged_normalizer.t{t}.{...}` for every learned task t, plus
//! `engine.last_task` (the task whose state the next task starts from), and
//! the method's state as `method.*` (its [`UpdateHooks::state`]).

use super::learner::{Evaluation, Learner, TaskStart};
use super::run_config::{BaseVacant, RunConfig};
use crate::config::net::MaskConfig;
use crate::config::{Config, EnvConfig};
use crate::nn::{
    checkpoint, mask_report, mask_views, transfer_lift, LayerLift, LayerView, MaskReport, NetworkKind, TaskId,
};
use crate::rl::{
    metric_names, Agent, Metrics, NoHooks, PolicyInfo, PpoLearner, RunningNormalizer, SimTrainEnv, TrainEnv,
    TrainingClock, UpdateHooks,
};
use crate::sim::Perturbation;
use crate::util::{derive_seed, Stream};
use anyhow::Context;
use candle_core::{Device, Tensor};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;
use std::path::Path;
use std::str::FromStr;

const LAST_TASK_KEY: &str = "engine.last_task";
/// Checkpoint extras of the method's state are `{METHOD_PREFIX}{its key}`.
pub const METHOD_PREFIX: &str = "method.";

/// What task t needs for exact recall besides the networks.
#[derive(Debug, Clone)]
struct TaskState {
    log_std: Tensor,
    obs: RunningNormalizer,
    privileged: RunningNormalizer,
}

/// The best reward per second a task allows: the tracking rewards' weights (rewards are scaled by dt).
pub fn max_reward_rate(env: &EnvConfig) -> f64 {
    f64::from(env.rewards.lin_vel_tracking.max(0.0) + env.rewards.ang_vel_tracking.max(0.0))
}

/// The best episode return a task allows: [`max_reward_rate`] times the episode length.
/// Normalised performance (METHOD.md 4) is the mean return over this.
pub fn max_episode_return(env: &EnvConfig) -> f64 {
    max_reward_rate(env) * f64::from(env.episode_s)
}

/// PPO + CENet, task by task.
pub struct PpoTaskLearner {
    config: Config,
    /// The environment trained and evaluated on (the config's, or a shifted one).
    env: EnvConfig,
    /// Action latency in control steps (sim-to-real fine-tuning).
    latency_steps: usize,
    eval_episodes: usize,
    /// Masked (`ours`) or dense (the non-mask baselines) networks.
    kind: NetworkKind,
    /// The method inside the update.
    hooks: Box<dyn UpdateHooks>,
    /// The agent between tasks (None while `training` holds it).
    agent: Option<Agent>,
    training: Option<(PpoLearner, Box<dyn TrainEnv + Send>, TaskId)>,
    states: BTreeMap<TaskId, TaskState>,
    last_task: Option<TaskId>,
    iterations_done: usize,
    /// Env steps and wall time of the training step in progress (`charts/env_steps`, `time/wall_s`).
    clock: TrainingClock,
}

/// The PPO learner of a run file, and the tasks of its base policy (if any).
pub fn make_ppo_learner(cfg: &RunConfig) -> anyhow::Result<(Box<dyn Learner>, Vec<String>)> {
    let method = crate::cl::method_by_name(&cfg.method, &cfg.method_settings)?;
    let mut learner = PpoTaskLearner::new_of_kind(&cfg.config, cfg.eval.episodes, method.network_kind())?
        .with_hooks(method.update_hooks());
    let learned = match &cfg.run.base_policy {
        Some(dir) => learner.load(dir).with_context(|| format!("loading the base policy {}", dir.display()))?,
        None => Vec::new(),
    };
    if cfg.run.base_vacant == BaseVacant::Redrawn {
        anyhow::ensure!(
            method.network_kind() == NetworkKind::Masked,
            "[run] base_vacant = \"redrawn\": method {} trains dense networks, which have no vacant weights",
            cfg.method
        );
        let mask = cfg.switches.apply(&cfg.config.net.mask)?;
        let mut rng = ChaCha8Rng::seed_from_u64(derive_seed(cfg.config.seed, Stream::BaseVacant));
        learner.agent_mut().redraw_vacant_weights(&mask, &mut rng)?;
    }
    Ok((Box::new(learner), learned))
}

fn dims_probe(env: &EnvConfig) -> anyhow::Result<crate::rl::EnvDims> {
    Ok(SimTrainEnv::new(env, &Perturbation::none(), 1, 0)?.dims())
}

impl PpoTaskLearner {
    /// Fresh networks for `config` (seeded from `config.seed`); evaluations use `eval_episodes` envs.
    pub fn new(config: &Config, eval_episodes: usize) -> anyhow::Result<Self> {
        Self::new_of_kind(config, eval_episodes, config.net.kind)
    }

    /// [`Self::new`] with networks of `kind`.
    pub fn new_of_kind(config: &Config, eval_episodes: usize, kind: NetworkKind) -> anyhow::Result<Self> {
        config.ppo.validate()?;
        let agent = Agent::new_of_kind(dims_probe(&config.env)?, config, config.seed, kind)?;
        Ok(Self {
            config: config.clone(),
            env: config.env.clone(),
            latency_steps: 0,
            eval_episodes,
            kind,
            hooks: Box::new(NoHooks),
            agent: Some(agent),
            training: None,
            states: BTreeMap::new(),
            last_task: None,
            iterations_done: 0,
            clock: TrainingClock::new(0, 0.0),
        })
    }

    /// The learner saved in policy directory `dir`, with the configuration it was trained with; and its task names.
    pub fn from_policy(dir: &Path, eval_episodes: usize) -> anyhow::Result<(Self, Vec<String>)> {
        let policy = checkpoint::load_policy(dir)?;
        let info: PolicyInfo = serde_json::from_value(policy.config)
            .with_context(|| format!("{}: the manifest's config is not a quadcl training config", dir.display()))?;
        // The policy's own kind of network (a baseline's run is dense whatever its [net] says).
        let dense = policy.networks.iter().any(|n| n.as_dense().is_some());
        let kind = if dense { NetworkKind::Dense } else { NetworkKind::Masked };
        let mut learner = Self::new_of_kind(&info.config, eval_episodes, kind)?;
        let tasks = learner.load(dir)?;
        Ok((learner, tasks))
    }

    /// The learner with a method's update hooks (before any task or load).
    pub fn with_hooks(mut self, hooks: Box<dyn UpdateHooks>) -> Self {
        self.hooks = hooks;
        self
    }

    /// Trains and evaluates from now on in the shifted environment (METHOD.md 2.7).
    pub fn set_shift(&mut self, shift: &super::shift::Shift) {
        self.env = shift.apply(&self.config.env);
        self.latency_steps = shift.latency_steps(&self.env);
    }

    /// Whether task `t` has been learned (has its recall state).
    pub fn has_task(&self, t: TaskId) -> bool {
        self.states.contains_key(&t)
    }

    /// The mask settings the networks currently use.
    pub fn mask_config(&self) -> MaskConfig {
        match self.agent_ref().actor.as_masked() {
            Some(net) => net.mask_config().clone(),
            None => self.config.net.mask.clone(),
        }
    }

    fn make_env(&self, task: &Perturbation, num_envs: usize, seed: u64) -> anyhow::Result<Box<dyn TrainEnv + Send>> {
        let env = Box::new(SimTrainEnv::new(&self.env, task, num_envs, seed)?);
        Ok(Box::new(super::shift::DelayedActions::new(env, self.latency_steps)))
    }

    fn agent_mut(&mut self) -> &mut Agent {
        match &mut self.training {
            Some((learner, _, _)) => &mut learner.agent,
            None => self.agent.as_mut().expect("the agent is either idle or training"),
        }
    }

    fn agent_ref(&self) -> &Agent {
        match &self.training {
            Some((learner, _, _)) => &learner.agent,
            None => self.agent.as_ref().expect("the agent is either idle or training"),
        }
    }

    fn install(agent: &mut Agent, state: &TaskState) -> anyhow::Result<()> {
        agent.log_std.set(&state.log_std)?;
        agent.obs_normalizer = state.obs.clone();
        agent.privileged_normalizer = state.privileged.clone();
        Ok(())
    }

    fn capture(agent: &Agent) -> anyhow::Result<TaskState> {
        Ok(TaskState {
            log_std: agent.log_std.as_tensor().copy()?,
            obs: agent.obs_normalizer.clone(),
            privileged: agent.privileged_normalizer.clone(),
        })
    }
}

impl Learner for PpoTaskLearner {
    fn begin_task(&mut self, start: &TaskStart) -> anyhow::Result<()> {
        anyhow::ensure!(self.training.is_none(), "begin_task while a task is in progress");
        let task = Perturbation::from_str(&start.name).map_err(|e| anyhow::anyhow!("task {}: {e}", start.name))?;
        let mut agent = self.agent.take().expect("idle agent");
        let result = (|| {
            agent.set_mask_config(&start.mask)?;
            // A repeat starts from its own state, a new task from the last trained one's.
            if let Some(state) =
                self.states.get(&start.task).or_else(|| self.last_task.and_then(|t| self.states.get(&t)))
            {
                Self::install(&mut agent, state)?;
            }
            agent.begin_task(start.task, &start.related)?;
            Ok::<_, anyhow::Error>(())
        })();
        if let Err(e) = result {
            self.agent = Some(agent);
            return Err(e);
        }
        let env = self.make_env(&task, self.config.ppo.num_envs, derive_seed(start.seed, Stream::StepEnvs))?;
        let mut ppo = self.config.ppo.clone();
        ppo.iterations = start.iterations;
        let learner = PpoLearner::new(ppo, agent, self.config.ppo.num_envs, start.seed)?;
        self.hooks.on_task_start(start.task, &learner.agent.params())?;
        self.training = Some((learner, env, start.task));
        self.iterations_done = 0;
        self.clock = TrainingClock::new(0, 0.0);
        Ok(())
    }

    fn train_iteration(&mut self) -> anyhow::Result<Metrics> {
        // The training curve: the rollout's mean reward per step over the best one, available every
        // iteration (episode statistics only once episodes end); a full-length episode's return over
        // its best is the same number.
        let max_step_reward = max_reward_rate(&self.env) * f64::from(self.env.policy_dt());
        let (learner, env, _) = self.training.as_mut().context("train_iteration without begin_task")?;
        let mut m = learner.train_iteration_with(env.as_mut(), self.hooks.as_mut())?;
        if let Some(r) = m.get("charts/mean_step_reward").copied() {
            m.insert(metric_names::PERFORMANCE.into(), r / max_step_reward);
        }
        self.clock.stamp(&mut m, self.config.ppo.steps_per_env * env.num_envs());
        self.iterations_done += 1;
        Ok(m)
    }

    fn end_task(&mut self) -> anyhow::Result<()> {
        let (mut learner, _, task) = self.training.take().context("end_task without begin_task")?;
        learner.end_task_with(self.hooks.as_mut())?;
        self.states.insert(task, Self::capture(&learner.agent)?);
        self.last_task = Some(task);
        self.agent = Some(learner.agent);
        Ok(())
    }

    fn evaluate(&mut self, task: TaskId, name: &str, seed: u64) -> anyhow::Result<Evaluation> {
        let state =
            self.states.get(&task).cloned().with_context(|| format!("task {task} ({name}) has not been learned"))?;
        let perturbation = Perturbation::from_str(name).map_err(|e| anyhow::anyhow!("task {name}: {e}"))?;
        let env_cfg = self.env.clone();
        let episodes = self.eval_episodes;
        let mut env = self.make_env(&perturbation, episodes, seed)?;
        let agent = self.agent_mut();
        let saved = (Self::capture(agent)?, agent.task, agent.recall);
        Self::install(agent, &state)?;
        agent.task = task;
        agent.recall = true;
        let max_steps = env_cfg.evaluation_step_bound();
        let report = crate::rl::evaluate(agent, env.as_mut(), name, seed, max_steps);
        Self::install(agent, &saved.0)?;
        agent.task = saved.1;
        agent.recall = saved.2;
        let report = report?;
        Ok(Evaluation { performance: report.mean_return / max_episode_return(&env_cfg), report })
    }

    fn mask_report(&self, tasks: &[String]) -> MaskReport {
        mask_report(tasks, &self.agent_ref().networks())
    }

    fn mask_views(&self, task: TaskId) -> Vec<LayerView> {
        mask_views(&self.agent_ref().masked_networks(), task)
    }

    fn transfer_lift(&self, related: &[TaskId]) -> Vec<LayerLift> {
        transfer_lift(&self.agent_ref().masked_networks(), related)
    }

    fn save(&self, dir: &Path, tasks: &[String]) -> anyhow::Result<()> {
        anyhow::ensure!(self.training.is_none(), "the PPO learner saves between tasks only");
        let agent = self.agent_ref();
        let mut extras = BTreeMap::new();
        for (t, s) in &self.states {
            extras.insert(format!("log_std.t{t}"), s.log_std.copy()?);
            put_normalizer(&format!("obs_normalizer.t{t}"), &s.obs, &mut extras)?;
            put_normalizer(&format!("privileged_normalizer.t{t}"), &s.privileged, &mut extras)?;
        }
        if let Some(t) = self.last_task {
            extras.insert(LAST_TASK_KEY.into(), Tensor::new(&[t as f32], &Device::Cpu)?);
        }
        for (k, v) in self.hooks.state()? {
            extras.insert(format!("{METHOD_PREFIX}{k}"), v);
        }
        let info = PolicyInfo { config: self.config.clone(), dims: agent.dims, iterations: self.iterations_done };
        checkpoint::save_policy(dir, tasks, &agent.saved_networks(), &extras, &serde_json::to_value(info)?)
    }

    fn load(&mut self, dir: &Path) -> anyhow::Result<Vec<String>> {
        anyhow::ensure!(self.training.is_none(), "load while a task is in progress");
        let policy = checkpoint::load_policy(dir)?;
        let info: PolicyInfo = serde_json::from_value(policy.config.clone())
            .with_context(|| format!("{}: the manifest's config is not a quadcl training config", dir.display()))?;
        // The policy's weights recall exactly, but only under the settings it learned to act with.
        let differences = crate::rl::acting_settings_differences(&info.config, &self.config);
        anyhow::ensure!(
            differences.is_empty(),
            "{}: the policy was trained to act under other settings than this run's: {}; give the run the \
             policy's values",
            dir.display(),
            differences.join(", ")
        );
        let clip = self.config.ppo.obs_clip as f32;
        let mut states = BTreeMap::new();
        for t in 0..policy.tasks.len() {
            let Some(log_std) = policy.extras.get(&format!("log_std.t{t}")) else { continue };
            let at = || format!("{}: task {t}", dir.display());
            states.insert(
                t,
                TaskState {
                    log_std: log_std.copy()?,
                    obs: get_normalizer(&format!("obs_normalizer.t{t}"), &policy.extras, clip).with_context(at)?,
                    privileged: get_normalizer(&format!("privileged_normalizer.t{t}"), &policy.extras, clip)
                        .with_context(at)?,
                },
            );
        }
        let last_task = match policy.extras.get(LAST_TASK_KEY) {
            Some(v) => Some(v.flatten_all()?.to_vec1::<f32>()?.first().copied().unwrap_or(0.0) as TaskId),
            None => states.keys().next_back().copied(),
        };
        let mut agent = Agent::new(info.dims, &self.config, self.config.seed)?;
        anyhow::ensure!(
            agent.dims == self.agent_ref().dims,
            "{}: the policy was built for other observation/action widths",
            dir.display()
        );
        let mut policy = policy;
        let fresh_sizes: Vec<Vec<usize>> = agent.networks().iter().map(|n| n.sizes().to_vec()).collect();
        agent.actor = policy.take_network("actor", dir)?;
        agent.critic = policy.take_network("critic", dir)?;
        agent.encoder = policy.take_network("cenet_encoder", dir)?;
        agent.decoder = policy.take_network("cenet_decoder", dir)?;
        // A dense method starts from a masked base policy as its dense equivalent; a masked
        // method cannot continue a dense run (the masks are gone).
        match (self.kind, agent.network_kind()) {
            (NetworkKind::Dense, NetworkKind::Masked) => agent = agent.into_dense()?,
            (NetworkKind::Masked, NetworkKind::Dense) => anyhow::bail!(
                "{}: the policy's networks are dense (a baseline's); a masked method cannot continue from it",
                dir.display()
            ),
            _ => {}
        }
        for (net, sizes) in agent.networks().iter().zip(&fresh_sizes) {
            anyhow::ensure!(
                net.sizes() == sizes.as_slice(),
                "{}: network {} has sizes {:?}, the run's config wants {sizes:?}",
                dir.display(),
                net.name(),
                net.sizes()
            );
        }
        if let Some(state) = last_task.and_then(|t| states.get(&t)) {
            Self::install(&mut agent, state)?;
            agent.task = last_task.unwrap_or(0);
            agent.recall = true;
        }
        self.hooks
            .load_state(&method_state(&policy.extras))
            .with_context(|| format!("{}: the method's state", dir.display()))?;
        self.agent = Some(agent);
        self.states = states;
        self.last_task = last_task;
        Ok(policy.tasks)
    }
}

/// The method's state among a checkpoint's extras, its prefix taken off.
pub fn method_state(extras: &BTreeMap<String, Tensor>) -> BTreeMap<String, Tensor> {
    extras.iter().filter_map(|(k, v)| Some((k.strip_prefix(METHOD_PREFIX)?.to_string(), v.clone()))).collect()
}

fn put_normalizer(prefix: &str, n: &RunningNormalizer, out: &mut BTreeMap<String, Tensor>) -> anyhow::Result<()> {
    out.insert(format!("{prefix}.mean"), Tensor::new(n.mean().as_slice(), &Device::Cpu)?);
    out.insert(format!("{prefix}.var"), Tensor::new(n.var().as_slice(), &Device::Cpu)?);
    out.insert(format!("{prefix}.count"), Tensor::new(&[n.count() as f32], &Device::Cpu)?);
    // The row count exactly (f32 holds integers only up to 2^24).
    out.insert(format!("{prefix}.count_exact"), checkpoint::integer_tensor(n.count() as u64)?);
    Ok(())
}

fn get_normalizer(prefix: &str, extras: &BTreeMap<String, Tensor>, clip: f32) -> anyhow::Result<RunningNormalizer> {
    let get = |key: &str| {
        extras.get(&format!("{prefix}.{key}")).with_context(|| format!("missing extra tensor {prefix}.{key}"))
    };
    let count = match extras.get(&format!("{prefix}.count_exact")) {
        Some(t) => checkpoint::tensor_integer(t, &format!("{prefix}.count_exact"))? as f64,
        None => f64::from(get("count")?.flatten_all()?.to_vec1::<f32>()?.first().copied().unwrap_or(0.0)),
    };
    let mut n =
        RunningNormalizer::from_saved(&get("mean")?.to_vec1::<f32>()?, &get("var")?.to_vec1::<f32>()?, count, clip)?;
    n.freeze();
    Ok(n)
}
