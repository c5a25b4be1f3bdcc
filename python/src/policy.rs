//! A learned task's policy from Python, and quadcl's evaluation of any policy.
//!
//! - `NativePolicy`: a policy directory's task (every form `quadcl eval`
//!   takes) as the deterministic policy `quadcl eval` runs: observation
//!   histories (N, HISTORY_LEN * OBS_DIM) to action means (N, ACT_DIM),
//!   through the Rust masked network, so its actions are the Rust recall's.
//! - `evaluate`: one episode per environment on a task, summarised as
//!   `quadcl eval --json` and `metrics.json` do (performance = mean return over
//!   the largest return an episode can reach). The policy is a `NativePolicy`
//!   (run in Rust, the GIL released) or any Python callable histories -> actions.

use crate::guard;
use crate::settings::{env_from_toml, env_to_toml, parse_task};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use quadcl::rl::{ActingWeights, LoadedPolicy, SimTrainEnv};
use quadcl::sim::{ACT_DIM, HISTORY_LEN, OBS_DIM};
use std::path::Path;

const WIDTH: usize = HISTORY_LEN * OBS_DIM;

/// A learned task's deterministic policy.
#[pyclass(module = "quadcl._native")]
pub struct NativePolicy {
    loaded: LoadedPolicy,
    weights: ActingWeights,
    task: String,
    path: String,
}

impl NativePolicy {
    fn act_rows(&self, histories: &[f32]) -> anyhow::Result<Vec<f32>> {
        let n = histories.len() / WIDTH;
        let obs: Vec<f32> =
            (0..n).flat_map(|i| histories[i * WIDTH + WIDTH - OBS_DIM..(i + 1) * WIDTH].iter().copied()).collect();
        self.loaded.agent.act_deterministic_with(&self.weights, &obs, histories)
    }
}

#[pymethods]
impl NativePolicy {
    /// `path`: a policy directory (or a run's checkpoint); `task`: the task to recall.
    #[new]
    fn new(py: Python<'_>, path: String, task: String) -> PyResult<Self> {
        py.detach(|| {
            guard("load_policy", || {
                let task = parse_task(&task)?.to_string();
                let loaded = quadcl::rl::load_for_task(Path::new(&path), &task)?;
                let dims = loaded.agent.dims();
                anyhow::ensure!(
                    (dims.obs, dims.history_len, dims.act) == (OBS_DIM, HISTORY_LEN, ACT_DIM),
                    "{path}: its networks take {} x {} observations and give {} actions; this simulator has {HISTORY_LEN} x {OBS_DIM} and {ACT_DIM}",
                    dims.history_len,
                    dims.obs,
                    dims.act
                );
                let weights = loaded.agent.acting_weights()?;
                Ok(Self { loaded, weights, task, path })
            })
        })
    }

    /// The task it recalls.
    #[getter]
    fn task(&self) -> String {
        self.task.clone()
    }

    /// The learned task whose network acts: `task` when the policy learned it, else (zero-shot:
    /// a base policy on a perturbation, a checkpoint from before the task) its last learned task.
    #[getter]
    fn recalls(&self) -> Option<String> {
        self.loaded.recalled_task().map(str::to_string)
    }

    /// The tasks the policy directory holds.
    #[getter]
    fn tasks(&self) -> Vec<String> {
        self.loaded.tasks.clone()
    }

    #[getter]
    fn path(&self) -> String {
        self.path.clone()
    }

    /// The `[env]` settings it was trained with, as TOML (what `evaluate` uses by default).
    #[getter]
    fn env_toml(&self) -> PyResult<String> {
        guard("env_toml", || env_to_toml(&self.loaded.info.config.env))
    }

    /// Action means (N, ACT_DIM) f32 for observation histories (N, HISTORY_LEN * OBS_DIM) f32.
    fn act<'py>(
        &self,
        py: Python<'py>,
        histories: PyReadonlyArray2<'py, f32>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f32>>> {
        let shape = histories.shape().to_vec();
        let rows: Vec<f32> = histories.as_array().iter().copied().collect();
        let actions = py.detach(|| {
            guard("act", || {
                anyhow::ensure!(
                    shape.len() == 2 && shape[1] == WIDTH,
                    "observations of shape {shape:?}: a policy takes (N, {WIDTH}), each row {HISTORY_LEN} frames of {OBS_DIM}"
                );
                self.act_rows(&rows)
            })
        })?;
        let n = actions.len() / ACT_DIM;
        PyArray1::from_vec(py, actions).reshape([n, ACT_DIM])
    }
}

/// Evaluates `policy` (a `NativePolicy` or a callable (N, W) f32 -> (N, ACT_DIM)) on `task`,
/// one episode on each of `episodes` environments seeded from `seed`, with the `[env]`
/// settings `env_toml` (None: a `NativePolicy`'s own; required for a callable).
#[pyfunction]
#[pyo3(signature = (policy, task, episodes, seed, env_toml=None))]
pub fn evaluate<'py>(
    py: Python<'py>,
    policy: Bound<'py, PyAny>,
    task: String,
    episodes: usize,
    seed: u64,
    env_toml: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let native = policy.cast::<NativePolicy>().ok().map(|p| p.borrow());
    let env_toml = match (&env_toml, &native) {
        (Some(t), _) => t.clone(),
        (None, Some(p)) => env_to_toml_py(p)?,
        (None, None) => return Err(pyo3::exceptions::PyValueError::new_err(
            "evaluate: a Python policy needs the [env] settings (env_toml, or pass robot/config to quadcl.evaluate)",
        )),
    };
    let setup = py.detach(|| {
        guard("evaluate", || {
            anyhow::ensure!(episodes >= 1, "episodes must be at least 1");
            let cfg = env_from_toml(&env_toml)?;
            let perturbation = parse_task(&task)?;
            let env = SimTrainEnv::new(&cfg, &perturbation, episodes, seed)?;
            let max_steps = cfg.evaluation_step_bound();
            Ok((env, max_steps, quadcl::engine::max_episode_return(&cfg), perturbation.to_string()))
        })
    })?;
    let (mut env, max_steps, max_return, task) = setup;
    let report = match &native {
        Some(p) => {
            let p: &NativePolicy = p;
            py.detach(|| {
                guard("evaluate", || {
                    let mut act = |_: &[f32], h: &[f32]| p.act_rows(h);
                    quadcl::rl::evaluate_with(&mut act, &mut env, &task, seed, max_steps)
                })
            })?
        }
        None => {
            // A Python callable: each step hands it the histories and reads its actions back.
            let mut act = |_: &[f32], h: &[f32]| -> anyhow::Result<Vec<f32>> {
                let rows = h.len() / WIDTH;
                let x = PyArray1::from_slice(py, h).reshape([rows, WIDTH]).map_err(|e| anyhow::anyhow!("{e}"))?;
                let out = policy.call1((x,)).map_err(|e| anyhow::anyhow!("the policy raised: {e}"))?;
                let a = out
                    .extract::<numpy::PyArrayLike2<f32, numpy::AllowTypeChange>>()
                    .map_err(|e| anyhow::anyhow!("the policy's actions are not a float array: {e}"))?;
                anyhow::ensure!(
                    a.shape() == [rows, ACT_DIM],
                    "the policy returned actions of shape {:?} for {rows} observations; expected ({rows}, {ACT_DIM})",
                    a.shape()
                );
                let v: Vec<f32> = a.as_array().iter().copied().collect();
                if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                    anyhow::bail!("the policy's action {} for env {} is {}", i % ACT_DIM, i / ACT_DIM, v[i]);
                }
                Ok(v)
            };
            guard("evaluate", || quadcl::rl::evaluate_with(&mut act, &mut env, &task, seed, max_steps))?
        }
    };
    let d = PyDict::new(py);
    d.set_item("task", &report.task)?;
    d.set_item("episodes", report.episodes)?;
    d.set_item("performance", report.mean_return / max_return)?;
    d.set_item("mean_return", report.mean_return)?;
    d.set_item("return_std", report.return_std)?;
    d.set_item("lin_vel_err", report.lin_vel_err)?;
    d.set_item("ang_vel_err", report.ang_vel_err)?;
    d.set_item("fall_rate", report.fall_rate)?;
    d.set_item("survival_s", report.survival_s)?;
    d.set_item("seed", report.seed)?;
    d.set_item("physics_resets", report.physics_resets)?;
    Ok(d)
}

fn env_to_toml_py(p: &NativePolicy) -> PyResult<String> {
    guard("evaluate", || env_to_toml(&p.loaded.info.config.env))
}
