//! What a training checkpoint holds beyond the policy, so that `quadcl train
//! --resume` goes on bit for bit as the run would have gone without the
//! interruption: `checkpoint/training_state.safetensors`, beside the policy
//! files. Its tensors (N envs, k episodes, ACT_DIM 12):
//!
//! | name | dtype (shape) | what |
//! | --- | --- | --- |
//! | `learner.rng` | U8 (56) | the learner's random stream (minibatches, action noise, mask draws) |
//! | `adam.NAME.m`, `adam.NAME.v` | F32 (n) | Adam's moments of parameter NAME |
//! | `adam.NAME.step` | U64 (1) | its steps taken |
//! | `normalizer.obs.mean`, `.var`, `.count` | F64 (d), (d), (1) | running statistics at full precision |
//! | `normalizer.privileged.*` | the same | the critic's observation |
//! | `selection.NET.I` | U8 (out * in) | masked layer I's previous hard mask (the churn's reference) |
//! | `episodes`, `episodes.env` | F32 (k, 5 + terms), U64 (k) | the window behind the episode charts |
//! | `envs.rng` | U8 (N, 56) | each env's stream as its episode began |
//! | `envs.steps`, `envs.total_steps` | U64 (N) | steps of its episode so far, and in all |
//! | `envs.actions` | F32 (sum of steps, 12) | the episodes' actions, env after env |
//! | `envs.sim_time` | F64 (N) | simulated seconds |
//! | `envs.interventions`, `envs.intervention_values` | U64 (m, 3), F32 (m, 3) | env, after step, kind (0 push, 1 command); values |
//!
//! An environment that keeps no replays (the toy ones) writes no `envs.*`; a
//! resume then starts its environments afresh and says so.

use super::env::{EpisodeSummary, TrainEnv};
use super::ppo::{PpoLearner, EPISODE_WINDOW};
use crate::nn::checkpoint::tensors::{f32_raw, f64_raw, serialize, u64_raw, u8_raw, Raw, Reader};
use crate::nn::{Moments, Network};
use crate::sim::reward::NUM_TERMS;
use crate::sim::{EpisodeReplay, Intervention, ACT_DIM};
use crate::util::{RngState, RNG_STATE_BYTES};
use anyhow::{ensure, Context};
use safetensors::Dtype;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// The file's name inside `checkpoint/`.
pub const TRAINING_STATE_FILE: &str = "training_state.safetensors";

/// Values per episode row of `episodes`: return, length, the two tracking errors, fell, the terms.
const EPISODE_VALUES: usize = 5 + NUM_TERMS;

/// The state of a run in progress that the policy files do not hold (see the module header).
#[derive(Debug, Clone)]
pub struct TrainingState {
    rng: RngState,
    moments: HashMap<String, Moments>,
    obs_stats: (Vec<f64>, Vec<f64>, f64),
    privileged_stats: (Vec<f64>, Vec<f64>, f64),
    /// (network, layer) -> the layer's previous hard mask.
    selections: BTreeMap<(String, usize), Vec<bool>>,
    episodes: Vec<EpisodeSummary>,
    envs: Option<Vec<EpisodeReplay>>,
}

/// The names the file gives the agent's four networks, in [`super::Agent::networks`] order.
const NETWORK_NAMES: [&str; 4] = ["actor", "critic", "encoder", "decoder"];

impl TrainingState {
    /// The state of `learner` and `env` between two iterations.
    pub fn of(learner: &PpoLearner, env: &dyn TrainEnv) -> anyhow::Result<Self> {
        let a = &learner.agent;
        let stats = |n: &super::RunningNormalizer| {
            let (mean, var, count) = n.exact();
            (mean.to_vec(), var.to_vec(), count)
        };
        let mut selections = BTreeMap::new();
        for (name, net) in NETWORK_NAMES.into_iter().zip(a.networks()) {
            for (i, layer) in net.as_masked().map(|m| m.layers()).unwrap_or_default().iter().enumerate() {
                if let Some(s) = layer.previous_selection() {
                    selections.insert((name.to_string(), i), s.to_vec());
                }
            }
        }
        Ok(Self {
            rng: RngState::of(&learner.rng),
            moments: learner.optimizer.moments().clone(),
            obs_stats: stats(&a.obs_normalizer),
            privileged_stats: stats(&a.privileged_normalizer),
            selections,
            episodes: learner.recent_episodes.iter().cloned().collect(),
            envs: env.replays()?,
        })
    }

    /// Whether the environments' state is kept (else a resume reseeds them).
    pub fn has_envs(&self) -> bool {
        self.envs.is_some()
    }

    /// Environment steps a restore replays.
    pub fn replay_steps(&self) -> usize {
        self.envs.as_ref().map_or(0, |e| e.iter().map(EpisodeReplay::steps).sum())
    }

    /// Puts `learner` and `env` (already built from the checkpoint's policy and config) in this
    /// state. Errors name what does not fit (a parameter, a layer, the env count).
    pub fn restore(self, learner: &mut PpoLearner, env: &mut dyn TrainEnv) -> anyhow::Result<()> {
        learner.rng = self.rng.rng();
        // Moments of parameters that no longer train (ln sigma after the entropy phase) are kept
        // as the optimiser keeps them; those of parameters that train must fit them.
        let params = learner.agent.params();
        for (name, mom) in &self.moments {
            if let Some(p) = params.iter().find(|p| &p.name == name) {
                let size = p.var.as_tensor().elem_count();
                ensure!(mom.m.len() == size, "Adam moments of {name}: {} values for {size} elements", mom.m.len());
            }
        }
        learner.optimizer.restore_moments(self.moments)?;
        let (mean, var, count) = self.obs_stats;
        learner.agent.obs_normalizer.restore_exact(mean, var, count).context("the observation statistics")?;
        let (mean, var, count) = self.privileged_stats;
        learner.agent.privileged_normalizer.restore_exact(mean, var, count).context("the privileged statistics")?;
        for (name, net) in NETWORK_NAMES.into_iter().zip(learner.agent.networks_mut()) {
            let Network::Masked(m) = net else { continue };
            for (i, layer) in m.layers.iter_mut().enumerate() {
                if let Some(s) = self.selections.get(&(name.to_string(), i)) {
                    layer.set_previous_selection(s.clone())?;
                }
            }
        }
        ensure!(
            self.episodes.len() <= EPISODE_WINDOW,
            "{} recent episodes, at most {EPISODE_WINDOW}",
            self.episodes.len()
        );
        learner.recent_episodes = self.episodes.into_iter().collect();
        if let Some(replays) = &self.envs {
            env.restore(replays)?;
        }
        Ok(())
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> anyhow::Result<Vec<u8>> {
        let mut t: BTreeMap<String, Raw> = BTreeMap::new();
        t.insert("learner.rng".into(), u8_raw(self.rng.to_bytes().to_vec(), vec![RNG_STATE_BYTES]));
        for (name, mom) in &self.moments {
            t.insert(format!("adam.{name}.m"), f32_raw(&mom.m, vec![mom.m.len()]));
            t.insert(format!("adam.{name}.v"), f32_raw(&mom.v, vec![mom.v.len()]));
            t.insert(format!("adam.{name}.step"), u64_raw(&[mom.step as u64], vec![1]));
        }
        for (which, (mean, var, count)) in [("obs", &self.obs_stats), ("privileged", &self.privileged_stats)] {
            t.insert(format!("normalizer.{which}.mean"), f64_raw(mean, vec![mean.len()]));
            t.insert(format!("normalizer.{which}.var"), f64_raw(var, vec![var.len()]));
            t.insert(format!("normalizer.{which}.count"), f64_raw(&[*count], vec![1]));
        }
        for ((net, i), s) in &self.selections {
            t.insert(format!("selection.{net}.{i}"), u8_raw(s.iter().map(|b| u8::from(*b)).collect(), vec![s.len()]));
        }
        let rows: Vec<f32> = self.episodes.iter().flat_map(episode_row).collect();
        t.insert("episodes".into(), f32_raw(&rows, vec![self.episodes.len(), EPISODE_VALUES]));
        let envs: Vec<u64> = self.episodes.iter().map(|e| e.env as u64).collect();
        t.insert("episodes.env".into(), u64_raw(&envs, vec![envs.len()]));
        if let Some(replays) = &self.envs {
            write_replays(replays, &mut t);
        }
        serialize(&t, None)
    }

    /// Reads a file written from [`Self::to_bytes`]; errors name the file and the tensor.
    pub fn read(path: &Path) -> anyhow::Result<Self> {
        let data = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
        Self::from_bytes(path, &data)
    }

    /// [`Self::read`] on bytes already read from `path`.
    pub fn from_bytes(path: &Path, data: &[u8]) -> anyhow::Result<Self> {
        let r = Reader::new(path, data)?;
        let bytes = |name: &str| -> anyhow::Result<&[u8]> {
            let shape = r.shape_of(name)?;
            r.raw(name, Dtype::U8, &shape)
        };
        let rng = RngState::from_bytes(bytes("learner.rng")?)
            .with_context(|| format!("{}: learner.rng is not {RNG_STATE_BYTES} bytes", path.display()))?;
        let mut moments = HashMap::new();
        let mut selections = BTreeMap::new();
        for name in r.names() {
            if let Some(param) = name.strip_prefix("adam.").and_then(|n| n.strip_suffix(".step")) {
                let m = r.f32s(&format!("adam.{param}.m"), &r.shape_of(&format!("adam.{param}.m"))?)?;
                let v = r.f32s(&format!("adam.{param}.v"), &[m.len()])?;
                let step = r.u64s(name, &[1])?[0];
                let step = i32::try_from(step).with_context(|| format!("{}: {name} = {step}", path.display()))?;
                moments.insert(param.to_string(), Moments { m, v, step });
            } else if let Some(rest) = name.strip_prefix("selection.") {
                let (net, layer) =
                    rest.rsplit_once('.').with_context(|| format!("{}: tensor {name}", path.display()))?;
                let layer: usize = layer.parse().with_context(|| format!("{}: tensor {name}", path.display()))?;
                selections.insert((net.to_string(), layer), bytes(name)?.iter().map(|b| *b != 0).collect());
            }
        }
        let stats = |which: &str| -> anyhow::Result<(Vec<f64>, Vec<f64>, f64)> {
            let mean_name = format!("normalizer.{which}.mean");
            let mean = r.f64s(&mean_name, &r.shape_of(&mean_name)?)?;
            let var = r.f64s(&format!("normalizer.{which}.var"), &[mean.len()])?;
            Ok((mean, var, r.f64s(&format!("normalizer.{which}.count"), &[1])?[0]))
        };
        let k = r.shape_of("episodes.env")?.first().copied().unwrap_or(0);
        let rows = r.f32s("episodes", &[k, EPISODE_VALUES])?;
        let envs = r.u64s("episodes.env", &[k])?;
        let episodes = rows.chunks_exact(EPISODE_VALUES).zip(envs).map(|(row, env)| episode_of(row, env)).collect();
        let replays = match r.shape_of("envs.steps") {
            Ok(_) => Some(read_replays(&r).with_context(|| path.display().to_string())?),
            Err(_) => None,
        };
        Ok(Self {
            rng,
            moments,
            obs_stats: stats("obs")?,
            privileged_stats: stats("privileged")?,
            selections,
            episodes,
            envs: replays,
        })
    }
}

fn episode_row(e: &EpisodeSummary) -> Vec<f32> {
    let mut row = vec![e.episode_return, e.length_s, e.lin_vel_err, e.ang_vel_err, f32::from(u8::from(e.fell))];
    row.extend_from_slice(&e.term_sums);
    row
}

fn episode_of(row: &[f32], env: u64) -> EpisodeSummary {
    EpisodeSummary {
        env: env as usize,
        episode_return: row[0],
        length_s: row[1],
        lin_vel_err: row[2],
        ang_vel_err: row[3],
        fell: row[4] != 0.0,
        term_sums: std::array::from_fn(|i| row[5 + i]),
    }
}

fn write_replays(replays: &[EpisodeReplay], t: &mut BTreeMap<String, Raw>) {
    let n = replays.len();
    let rngs: Vec<u8> = replays.iter().flat_map(|r| r.start_rng.to_bytes()).collect();
    t.insert("envs.rng".into(), u8_raw(rngs, vec![n, RNG_STATE_BYTES]));
    let steps: Vec<u64> = replays.iter().map(|r| r.steps() as u64).collect();
    t.insert("envs.steps".into(), u64_raw(&steps, vec![n]));
    let total: Vec<u64> = replays.iter().map(|r| r.total_steps).collect();
    t.insert("envs.total_steps".into(), u64_raw(&total, vec![n]));
    let time: Vec<f64> = replays.iter().map(|r| r.sim_time).collect();
    t.insert("envs.sim_time".into(), f64_raw(&time, vec![n]));
    let actions: Vec<f32> = replays.iter().flat_map(|r| r.actions.iter().copied()).collect();
    t.insert("envs.actions".into(), f32_raw(&actions, vec![actions.len() / ACT_DIM, ACT_DIM]));
    let (mut at, mut values) = (Vec::new(), Vec::new());
    for (env, r) in replays.iter().enumerate() {
        for (step, what) in &r.interventions {
            let (kind, v) = match *what {
                Intervention::Push([x, y]) => (0, [x, y, 0.0]),
                Intervention::Command(c) => (1, c),
            };
            at.extend([env as u64, *step as u64, kind]);
            values.extend(v);
        }
    }
    t.insert("envs.interventions".into(), u64_raw(&at, vec![at.len() / 3, 3]));
    t.insert("envs.intervention_values".into(), f32_raw(&values, vec![values.len() / 3, 3]));
}

fn read_replays(r: &Reader) -> anyhow::Result<Vec<EpisodeReplay>> {
    let n = r.shape_of("envs.steps")?.first().copied().unwrap_or(0);
    let steps = r.u64s("envs.steps", &[n])?;
    let total_steps = r.u64s("envs.total_steps", &[n])?;
    let sim_time = r.f64s("envs.sim_time", &[n])?;
    let rngs = r.raw("envs.rng", Dtype::U8, &[n, RNG_STATE_BYTES])?;
    let all_steps = steps.iter().try_fold(0usize, |sum, s| sum.checked_add(usize::try_from(*s).ok()?));
    let all_steps = all_steps.context("envs.steps: more steps than this machine can count")?;
    let actions = r.f32s("envs.actions", &[all_steps, ACT_DIM])?;
    let m = r.shape_of("envs.interventions")?.first().copied().unwrap_or(0);
    let at = r.u64s("envs.interventions", &[m, 3])?;
    let values = r.f32s("envs.intervention_values", &[m, 3])?;
    let mut replays = Vec::with_capacity(n);
    let mut offset = 0;
    for i in 0..n {
        let len = steps[i] as usize * ACT_DIM;
        let start_rng = RngState::from_bytes(&rngs[i * RNG_STATE_BYTES..(i + 1) * RNG_STATE_BYTES])
            .context("envs.rng: a stream state of the wrong size")?;
        replays.push(EpisodeReplay {
            start_rng,
            actions: actions[offset..offset + len].to_vec(),
            interventions: Vec::new(),
            total_steps: total_steps[i],
            sim_time: sim_time[i],
        });
        offset += len;
    }
    for (a, v) in at.chunks_exact(3).zip(values.chunks_exact(3)) {
        let env = usize::try_from(a[0])
            .ok()
            .filter(|e| *e < n)
            .with_context(|| format!("envs.interventions: env {} of {n}", a[0]))?;
        let what = match a[2] {
            0 => Intervention::Push([v[0], v[1]]),
            1 => Intervention::Command([v[0], v[1], v[2]]),
            k => anyhow::bail!("envs.interventions: unknown kind {k}"),
        };
        replays[env].interventions.push((a[1] as usize, what));
    }
    Ok(replays)
}
