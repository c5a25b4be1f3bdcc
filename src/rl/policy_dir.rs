//! Saving and loading a trained policy directory: `model.safetensors`
//! (every network parameter by name, `log_std`, normaliser statistics) and
//! `manifest.json` (format version, task, the full config, env dims, the
//! sha256 of the weights file).
//!
//! Interim format of the single-task learner; once `nn::checkpoint` lands
//! the masked networks, bit-packed masks and per-task extras go through it.

use super::agent::Agent;
use super::env::EnvDims;
use super::normalizer::RunningNormalizer;
use crate::config::Config;
use crate::util::{sha256_hex, write_atomic};
use anyhow::Context;
use candle_core::{Device, Tensor};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Version of this directory layout.
pub const POLICY_FORMAT_VERSION: u32 = 1;
const WEIGHTS_FILE: &str = "model.safetensors";
const MANIFEST_FILE: &str = "manifest.json";

/// `manifest.json` of a policy directory.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PolicyManifest {
    pub format_version: u32,
    /// The task the policy was trained on (canonical perturbation name).
    pub task: String,
    /// Training iterations completed.
    pub iterations: usize,
    /// Environment widths the networks were built for.
    pub dims: ManifestDims,
    /// The whole configuration of the run.
    pub config: Config,
    /// sha256 of each file, by name.
    pub sha256: BTreeMap<String, String>,
}

/// Serialisable copy of [`EnvDims`].
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct ManifestDims {
    pub obs: usize,
    pub privileged_obs: usize,
    pub history_len: usize,
    pub act: usize,
    pub base_velocity_offset: usize,
    pub control_dt: f64,
}

impl From<EnvDims> for ManifestDims {
    fn from(d: EnvDims) -> Self {
        Self {
            obs: d.obs,
            privileged_obs: d.privileged_obs,
            history_len: d.history_len,
            act: d.act,
            base_velocity_offset: d.base_velocity_offset,
            control_dt: d.control_dt,
        }
    }
}
impl From<ManifestDims> for EnvDims {
    fn from(d: ManifestDims) -> Self {
        Self {
            obs: d.obs,
            privileged_obs: d.privileged_obs,
            history_len: d.history_len,
            act: d.act,
            base_velocity_offset: d.base_velocity_offset,
            control_dt: d.control_dt,
        }
    }
}

fn normalizer_tensors(prefix: &str, n: &RunningNormalizer, out: &mut Vec<(String, Tensor)>) -> anyhow::Result<()> {
    out.push((format!("{prefix}.mean"), Tensor::new(n.mean().as_slice(), &Device::Cpu)?));
    out.push((format!("{prefix}.var"), Tensor::new(n.var().as_slice(), &Device::Cpu)?));
    out.push((format!("{prefix}.count"), Tensor::new(&[n.count()], &Device::Cpu)?));
    Ok(())
}

fn normalizer_from(prefix: &str, tensors: &std::collections::HashMap<String, Tensor>, clip: f32) -> anyhow::Result<RunningNormalizer> {
    let get = |key: &str| tensors.get(&format!("{prefix}.{key}")).with_context(|| format!("missing tensor {prefix}.{key}"));
    let count = get("count")?.to_vec1::<f64>()?.first().copied().unwrap_or(0.0);
    RunningNormalizer::from_saved(&get("mean")?.to_vec1::<f32>()?, &get("var")?.to_vec1::<f32>()?, count, clip)
}

/// Writes `agent` (its normalisers as they are: freeze them first to end a
/// task) to `dir`, creating it.
pub fn save_policy(agent: &Agent, config: &Config, task: &str, iterations: usize, dir: &Path) -> anyhow::Result<()> {
    let mut tensors: Vec<(String, Tensor)> =
        agent.params().into_iter().map(|p| (p.name, p.var.as_tensor().copy())).map(|(n, t)| t.map(|t| (n, t))).collect::<candle_core::Result<_>>()?;
    normalizer_tensors("obs_normalizer", &agent.obs_normalizer, &mut tensors)?;
    normalizer_tensors("privileged_normalizer", &agent.privileged_normalizer, &mut tensors)?;
    let bytes = safetensors::serialize(tensors.iter().map(|(n, t)| (n.clone(), t)), None)
        .with_context(|| format!("serialising weights for {}", dir.display()))?;
    write_atomic(&dir.join(WEIGHTS_FILE), &bytes)?;
    let manifest = PolicyManifest {
        format_version: POLICY_FORMAT_VERSION,
        task: task.to_string(),
        iterations,
        dims: agent.dims.into(),
        config: config.clone(),
        sha256: BTreeMap::from([(WEIGHTS_FILE.to_string(), sha256_hex(&bytes))]),
    };
    write_atomic(&dir.join(MANIFEST_FILE), serde_json::to_string_pretty(&manifest)?.as_bytes())
}

/// Reads a policy directory: the agent (normalisers frozen) and its manifest.
/// Errors name the directory and what is wrong (missing file, hash mismatch,
/// missing or misshapen tensor).
pub fn load_policy(dir: &Path) -> anyhow::Result<(Agent, PolicyManifest)> {
    let manifest_path = dir.join(MANIFEST_FILE);
    let text = std::fs::read_to_string(&manifest_path).with_context(|| format!("reading {}", manifest_path.display()))?;
    let manifest: PolicyManifest =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", manifest_path.display()))?;
    anyhow::ensure!(
        manifest.format_version == POLICY_FORMAT_VERSION,
        "{}: format version {} (this build reads {POLICY_FORMAT_VERSION})",
        manifest_path.display(),
        manifest.format_version
    );
    let weights_path = dir.join(WEIGHTS_FILE);
    let bytes = std::fs::read(&weights_path).with_context(|| format!("reading {}", weights_path.display()))?;
    if let Some(expected) = manifest.sha256.get(WEIGHTS_FILE) {
        anyhow::ensure!(&sha256_hex(&bytes) == expected, "{}: sha256 does not match the manifest", weights_path.display());
    }
    let tensors = candle_core::safetensors::load_buffer(&bytes, &Device::Cpu)
        .with_context(|| format!("decoding {}", weights_path.display()))?;
    let ppo = &manifest.config.ppo;
    let mut agent = Agent::new(manifest.dims.into(), ppo, manifest.config.seed)?;
    for p in agent.params() {
        let t = tensors.get(&p.name).with_context(|| format!("{}: missing tensor {}", weights_path.display(), p.name))?;
        anyhow::ensure!(
            t.dims() == p.var.as_tensor().dims(),
            "{}: tensor {} has shape {:?}, the config builds {:?}",
            weights_path.display(),
            p.name,
            t.dims(),
            p.var.as_tensor().dims()
        );
        p.var.set(t)?;
    }
    let clip = ppo.obs_clip as f32;
    agent.obs_normalizer = normalizer_from("obs_normalizer", &tensors, clip).with_context(|| weights_path.display().to_string())?;
    agent.privileged_normalizer =
        normalizer_from("privileged_normalizer", &tensors, clip).with_context(|| weights_path.display().to_string())?;
    Ok((agent, manifest))
}
