//! Export of learned tasks for deployment (`quadcl export`): one task of a
//! policy directory as plain dense networks with the observation normaliser
//! and the action transform, as an ONNX model (`onnx.rs`) or a safetensors
//! file with PyTorch's key names (`torch.rs`), carrying the deployment
//! contract as metadata (`contract.rs`). `action = f(observation history)` then
//! runs with no quadcl code.
//!
//! Every export checks its dense copy against the policy's own forward on the
//! observations of a short rollout of the task (max abs difference at most
//! [`SELF_CHECK_TOLERANCE`]), and can write those observations with the
//! policy's actions as a reference file (`reference.rs`) for a runtime's parity
//! check (`scripts/check_export.py`).

pub mod contract;
pub mod dense_policy;
pub mod onnx;
pub mod protobuf;
pub mod reference;
pub mod torch;

use crate::rl::LoadedPolicy;
use anyhow::Context;
use dense_policy::DensePolicy;
use std::path::{Path, PathBuf};

/// The largest difference allowed between the dense copy and the policy's own forward.
pub const SELF_CHECK_TOLERANCE: f32 = 1e-5;

/// The file format of an export.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ExportFormat {
    /// An ONNX model (IR 8, opset 17).
    Onnx,
    /// A safetensors file with PyTorch `nn.Sequential` key names.
    Safetensors,
}

impl ExportFormat {
    /// The file extension.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Onnx => "onnx",
            Self::Safetensors => "safetensors",
        }
    }
}

/// What one export wrote.
#[derive(Debug, Clone)]
pub struct ExportedTask {
    pub task: String,
    pub path: PathBuf,
    pub bytes: usize,
    /// Max abs difference of the dense copy's actions from the policy's on the rollout's observations.
    pub self_check: f32,
    /// The reference file, when asked for.
    pub reference: Option<PathBuf>,
}

/// The policy in `dir` recalling `task` (None: its last learned task, or a checkpoint's task
/// in training, ended in memory as `quadcl eval` does). A task the policy has not learned is
/// an error listing the ones it has.
pub fn load_task(dir: &Path, task: Option<&str>) -> anyhow::Result<LoadedPolicy> {
    let Some(task) = task else {
        return Ok(crate::rl::load_policy_or_checkpoint(dir)?.policy);
    };
    let loaded = crate::rl::load_for_task(dir, task)?;
    let recalled = loaded.tasks.get(loaded.agent.task).map(String::as_str);
    anyhow::ensure!(
        recalled == Some(task),
        "{}: has not learned task {task:?}; it has learned {:?}",
        dir.display(),
        crate::rl::learned_task_names(&loaded)
    );
    Ok(loaded)
}

/// The names of the tasks the policy in `dir` has learned, in order.
pub fn learned_tasks(dir: &Path) -> anyhow::Result<Vec<String>> {
    let loaded = crate::rl::load_policy_or_checkpoint(dir)?.policy;
    Ok(crate::rl::learned_task_names(&loaded).into_iter().map(str::to_string).collect())
}

/// A file name for `task` (`crash:FL` -> `crash_FL`).
pub fn task_file_stem(task: &str) -> String {
    task.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '.' { c } else { '_' }).collect()
}

/// Exports `task` of the policy in `dir` to `out` in `format`; with `reference`, also writes
/// the self-check's observations and the policy's actions there.
pub fn export_task(
    dir: &Path,
    task: Option<&str>,
    format: ExportFormat,
    out: &Path,
    reference: Option<&Path>,
) -> anyhow::Result<ExportedTask> {
    let loaded = load_task(dir, task)?;
    let env = &loaded.info.config.env;
    let robot = contract::RobotFacts::of(env).with_context(|| format!("{}: the policy's robot", dir.display()))?;
    let policy = DensePolicy::from_loaded(&loaded, &robot.default_pose, &robot.limits)?;
    let samples = reference::rollout_samples(&loaded, &policy, reference::SAMPLE_ENVS, reference::SAMPLE_STEPS)?;
    let self_check = samples.max_difference(&policy)?;
    anyhow::ensure!(
        self_check <= SELF_CHECK_TOLERANCE,
        "{}: task {}: the exported networks' actions differ from the policy's by {self_check} (more than {SELF_CHECK_TOLERANCE}); nothing written",
        dir.display(),
        policy.task
    );
    let kind = format!("{:?}", loaded.agent.actor.kind()).to_lowercase();
    let metadata = contract::contract(&policy, &robot, env, &kind, &dir.display().to_string());
    let bytes = match format {
        ExportFormat::Onnx => onnx::onnx_model(&policy, &metadata),
        ExportFormat::Safetensors => torch::safetensors_model(&policy, &metadata)?,
    };
    crate::util::write_atomic(out, &bytes).with_context(|| format!("writing {}", out.display()))?;
    if let Some(path) = reference {
        samples.save(path, &policy.task)?;
    }
    Ok(ExportedTask {
        task: policy.task,
        path: out.to_path_buf(),
        bytes: bytes.len(),
        self_check,
        reference: reference.map(Path::to_path_buf),
    })
}
