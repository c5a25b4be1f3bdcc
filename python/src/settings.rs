//! Settings from Python's arguments: a robot's `[env]` table as TOML text (what
//! `NativeVecEnv` and `evaluate` take), a task's canonical name, and a run
//! file's sequence.

use crate::guard;
use pyo3::prelude::*;
use quadcl::config::EnvConfig;
use quadcl::sim::Perturbation;
use std::path::Path;

/// The `[env]` settings as TOML for `robot` (a shipped robot's name or a URDF
/// file) or `config` (a run file or training config), never both.
#[pyfunction]
#[pyo3(signature = (robot=None, config=None))]
pub fn env_settings(py: Python<'_>, robot: Option<String>, config: Option<String>) -> PyResult<String> {
    py.detach(|| {
        guard("env_settings", || {
            let env = match (robot.as_deref(), config.as_deref()) {
                (Some(r), Some(c)) => {
                    anyhow::bail!("give robot ({r:?}) or config ({c:?}), not both: a config's [env] names its robot")
                }
                (_, Some(c)) => quadcl::engine::env_of_file(Path::new(c))?,
                (r, None) => quadcl::engine::env_of_robot(r.unwrap_or("a1"))?,
            };
            env_to_toml(&env)
        })
    })
}

/// `[env]` settings as TOML text (f32 values round-trip exactly).
pub fn env_to_toml(env: &EnvConfig) -> anyhow::Result<String> {
    Ok(toml::to_string(env)?)
}

/// `[env]` settings from [`env_to_toml`]'s text, checked.
pub fn env_from_toml(text: &str) -> anyhow::Result<EnvConfig> {
    let env: EnvConfig = toml::from_str(text).map_err(|e| anyhow::anyhow!("in the [env] settings: {e}"))?;
    env.validate()?;
    Ok(env)
}

/// A task's canonical name (`crash:FL`, `invert:RR+noise:FR`, `none`); an unknown one is a `ValueError`.
#[pyfunction]
pub fn task_name(task: &str) -> PyResult<String> {
    guard("task_name", || Ok(parse_task(task)?.to_string()))
}

pub fn parse_task(task: &str) -> anyhow::Result<Perturbation> {
    task.parse::<Perturbation>().map_err(|e| anyhow::anyhow!("task {:?}: {e:#}", quadcl::util::text::clip(task)))
}

/// A run file's sequence: (`[env]` TOML, seed, [(task, iterations)], method).
type SequenceParts = (String, u64, Vec<(String, usize)>, String);

/// A run file's sequence: (`[env]` TOML, seed, [(task, iterations)], method).
#[pyfunction]
pub fn sequence_of(py: Python<'_>, path: String) -> PyResult<SequenceParts> {
    py.detach(|| {
        guard("sequence_of", || {
            let run = quadcl::engine::RunConfig::load(Path::new(&path))?;
            let tasks = (0..run.sequence.tasks.len())
                .map(|i| (run.sequence.tasks[i].name.clone(), run.sequence.iterations_of(i)))
                .collect();
            Ok((env_to_toml(&run.config.env)?, run.config.seed, tasks, run.method.clone()))
        })
    })
}
