//! `NativeVecEnv`: the batch of environments the Rust learner trains on
//! (`quadcl::sim::VecEnv`: the task's fault, command sampling, Table 1 rewards,
//! pushes, auto-reset), stepped in one call with the GIL released.
//!
//! Shapes, for N environments (W = HISTORY_LEN * OBS_DIM = 5 * 45):
//! - observation: (N, W) f32, every env's observation history, oldest frame
//!   first; the last OBS_DIM columns are the current observation (what the
//!   learner's actor and CENet read, and an exported policy's `obs_history`);
//! - privileged: (N, PRIV_OBS_DIM) f32, the critic's and the CENet's targets;
//! - actions: (N, ACT_DIM) f32, finite (a non-finite action is refused before
//!   any env steps, so a bad call changes nothing);
//! - step: rewards (N,) f32, terminated (N,) bool (fell), truncated (N,) bool
//!   (time-out), and final_observation (N, W), only when a row ended: for a row
//!   that ended, the history it ended with (the row of `observation` is already
//!   the next episode's first); other rows repeat `observation`;
//! - episodes: one dict per episode that ended (its env, return, performance,
//!   length in steps and seconds, tracking errors, whether it fell).

use crate::guard;
use crate::settings::{env_from_toml, parse_task};
use numpy::{PyArray1, PyArray2, PyArray4, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use quadcl::render::{render, Camera, Scene};
use quadcl::sim::{RobotModel, VecEnv, ACT_DIM, HISTORY_LEN, OBS_DIM, PRIV_OBS_DIM};
use rayon::prelude::*;
use std::sync::{Mutex, MutexGuard};

const WIDTH: usize = HISTORY_LEN * OBS_DIM;

/// The Rust batch of environments.
#[pyclass(module = "quadcl._native")]
pub struct NativeVecEnv {
    /// Behind a lock only because a pyclass must be `Sync` (an env's observers are not);
    /// the lock is never contended: every method holds the object exclusively.
    env: Mutex<VecEnv>,
    /// None: rayon's global pool (all cores, or RAYON_NUM_THREADS), or the calling thread
    /// when the batch was made for one thread.
    pool: Option<rayon::ThreadPool>,
    /// The pool `render` draws in when the batch steps on the calling thread (one thread).
    picture_pool: Option<rayon::ThreadPool>,
    task: String,
    control_dt: f64,
    max_return: f64,
    clip_actions: f32,
}

/// (observation, privileged).
type Observed<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<f32>>);

/// One step's arrays: (observation, rewards, terminated, truncated, privileged,
/// final_observation (None when no row ended), episodes).
type StepArrays<'py> = (
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray1<f32>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray2<f32>>,
    Option<Bound<'py, PyArray2<f32>>>,
    Vec<Bound<'py, PyDict>>,
);

impl NativeVecEnv {
    fn env(&self) -> MutexGuard<'_, VecEnv> {
        // A panic inside a call (turned into an exception) may have poisoned it; the env is still whole.
        self.env.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn run<T: Send>(&mut self, f: impl FnOnce(&mut VecEnv) -> anyhow::Result<T> + Send) -> anyhow::Result<T> {
        let env = self.env.get_mut().unwrap_or_else(|e| e.into_inner());
        match &self.pool {
            Some(pool) => pool.install(|| f(env)),
            None => f(env),
        }
    }
}

fn matrix<'py>(py: Python<'py>, data: Vec<f32>, width: usize) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let rows = data.len() / width;
    PyArray1::from_vec(py, data).reshape([rows, width])
}

#[pymethods]
impl NativeVecEnv {
    /// `env_toml`: the `[env]` settings (`env_settings`); `task`: `none`, `crash:FL`, ...;
    /// `num_threads`: the threads stepping the batch (None: rayon's global pool).
    #[new]
    #[pyo3(signature = (env_toml, task, num_envs, seed, num_threads=None))]
    fn new(
        py: Python<'_>,
        env_toml: String,
        task: String,
        num_envs: usize,
        seed: u64,
        num_threads: Option<usize>,
    ) -> PyResult<Self> {
        py.detach(|| {
            guard("NativeVecEnv()", || {
                let cfg = env_from_toml(&env_toml)?;
                let task = parse_task(&task)?;
                anyhow::ensure!(num_threads != Some(0), "num_threads must be at least 1 (or None for every core)");
                let pool = match num_threads {
                    Some(n) => Some(rayon::ThreadPoolBuilder::new().num_threads(n).build()?),
                    None => None,
                };
                let robot = RobotModel::for_config(&cfg)?;
                let make = || VecEnv::new(&cfg, &robot, &task, num_envs, seed);
                let mut env = match &pool {
                    Some(p) => p.install(make)?,
                    None => make()?,
                };
                // One thread: the envs run in order on the calling thread, without a pool whose
                // worker each call would be handed to and waited for (about 75 µs a call); the
                // one-thread pool only built them (rayon's global pool would start a worker per core).
                let on_calling_thread = num_threads == Some(1);
                env.set_on_calling_thread(on_calling_thread);
                // Pictures are drawn by rows in a pool; with one thread, in the one-thread pool.
                let (pool, picture_pool) = if on_calling_thread { (None, pool) } else { (pool, None) };
                Ok(Self {
                    env: Mutex::new(env),
                    pool,
                    picture_pool,
                    task: task.to_string(),
                    control_dt: f64::from(cfg.policy_dt()),
                    max_return: quadcl::engine::max_episode_return(&cfg),
                    clip_actions: cfg.clip_actions,
                })
            })
        })
    }

    #[getter]
    fn num_envs(&self) -> usize {
        self.env().num_envs()
    }

    /// The task's canonical name.
    #[getter]
    fn task(&self) -> String {
        self.task.clone()
    }

    /// Seconds of simulated time per step (the policy's control period).
    #[getter]
    fn control_dt(&self) -> f64 {
        self.control_dt
    }

    /// Actions are clipped to [-clip_actions, clip_actions] before they are scaled.
    #[getter]
    fn clip_actions(&self) -> f32 {
        self.clip_actions
    }

    /// The largest return an episode can reach: a return over it is `performance`.
    #[getter]
    fn max_episode_return(&self) -> f64 {
        self.max_return
    }

    /// Reseeds and resets every env (env i from (seed, i)): (observation, privileged).
    fn reset<'py>(&mut self, py: Python<'py>, seed: u64) -> PyResult<Observed<'py>> {
        py.detach(|| guard("reset", || self.run(|env| env.reset(seed))))?;
        let env = self.env();
        Ok((
            matrix(py, env.obs_histories().to_vec(), WIDTH)?,
            matrix(py, env.privileged_observations().to_vec(), PRIV_OBS_DIM)?,
        ))
    }

    /// Pictures of the envs `envs` (all when None) as they stand, from the tracking camera of
    /// `quadcl record` (`quadcl::render`, on the CPU): (K, height, width, 3) uint8, RGB.
    #[pyo3(signature = (width, height, envs=None))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        width: usize,
        height: usize,
        envs: Option<Vec<usize>>,
    ) -> PyResult<Bound<'py, PyArray4<u8>>> {
        let scenes = guard("render", || {
            let env = self.env();
            let n = env.num_envs();
            let wanted = envs.unwrap_or_else(|| (0..n).collect());
            if let Some(bad) = wanted.iter().find(|&&i| i >= n) {
                anyhow::bail!("render: env {bad} of a batch of {n}");
            }
            Ok(wanted.iter().map(|&i| Scene::of_env(&env.envs()[i])).collect::<Vec<_>>())
        })?;
        let k = scenes.len();
        let bytes = py.detach(|| {
            guard("render", || {
                let draw = || {
                    scenes
                        .par_iter()
                        .map(|s| render(s, &Camera::default(), width, height))
                        .collect::<anyhow::Result<Vec<_>>>()
                };
                let frames = match self.pool.as_ref().or(self.picture_pool.as_ref()) {
                    Some(pool) => pool.install(draw)?,
                    None => draw()?,
                };
                Ok(frames.into_iter().flat_map(|f| f.rgb).collect::<Vec<u8>>())
            })
        })?;
        PyArray1::from_vec(py, bytes).reshape([k, height, width, 3])
    }

    /// Steps every env with its row of `actions` (N, ACT_DIM) f32; envs that end are reset.
    fn step<'py>(&mut self, py: Python<'py>, actions: PyReadonlyArray2<'py, f32>) -> PyResult<StepArrays<'py>> {
        let n = self.env().num_envs();
        let shape = actions.shape().to_vec();
        let actions: Vec<f32> = match actions.as_slice() {
            Ok(s) => s.to_vec(),
            Err(_) => actions.as_array().iter().copied().collect(),
        };
        let outcome = py.detach(|| {
            guard("step", || {
                anyhow::ensure!(
                    shape == [n, ACT_DIM],
                    "actions of shape {shape:?}: the batch takes ({n}, {ACT_DIM}), one row of joint actions per env"
                );
                if let Some(i) = actions.iter().position(|a| !a.is_finite()) {
                    anyhow::bail!(
                        "action {} of env {} is {}: actions must be finite (nothing was stepped)",
                        i % ACT_DIM,
                        i / ACT_DIM,
                        actions[i]
                    );
                }
                // The histories before the step: an ending row's final history continues its row.
                let before = self.env().obs_histories().to_vec();
                let step = self.run(|env| env.step(&actions))?;
                let obs = self.env().obs_histories().to_vec();
                let ended = |i: usize| step.terminated[i] || step.truncated[i];
                let final_obs = (0..n).any(ended).then(|| {
                    let mut final_obs = obs.clone();
                    for i in (0..n).filter(|&i| ended(i)) {
                        let row = &mut final_obs[i * WIDTH..(i + 1) * WIDTH];
                        row[..WIDTH - OBS_DIM].copy_from_slice(&before[i * WIDTH + OBS_DIM..(i + 1) * WIDTH]);
                        row[WIDTH - OBS_DIM..]
                            .copy_from_slice(&step.next_obs_before_reset[i * OBS_DIM..(i + 1) * OBS_DIM]);
                    }
                    final_obs
                });
                let privileged = self.env().privileged_observations().to_vec();
                Ok((obs, step, final_obs, privileged))
            })
        })?;
        let (obs, step, final_obs, privileged) = outcome;
        let episodes = step
            .finished
            .iter()
            .map(|e| {
                let d = PyDict::new(py);
                d.set_item("env", e.env)?;
                d.set_item("return", e.episode_return)?;
                d.set_item("performance", f64::from(e.episode_return) / self.max_return)?;
                d.set_item("length_s", e.length_s)?;
                d.set_item("steps", (f64::from(e.length_s) / self.control_dt).round() as u64)?;
                d.set_item("lin_vel_err", e.lin_vel_err)?;
                d.set_item("ang_vel_err", e.ang_vel_err)?;
                d.set_item("fell", e.fell)?;
                Ok(d)
            })
            .collect::<PyResult<Vec<_>>>()?;
        Ok((
            matrix(py, obs, WIDTH)?,
            PyArray1::from_vec(py, step.reward),
            PyArray1::from_vec(py, step.terminated),
            PyArray1::from_vec(py, step.truncated),
            matrix(py, privileged, PRIV_OBS_DIM)?,
            final_obs.map(|f| matrix(py, f, WIDTH)).transpose()?,
            episodes,
        ))
    }
}
