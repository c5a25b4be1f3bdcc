//! Policy directories: everything needed to recall every task exactly and to
//! go on training (METHOD.md 2.4, 2.5).
//!
//! - `model.safetensors`: per layer "{layer}.weight" f32 (out, in),
//!   "{layer}.score" f32 (out, in) (soft-score means), "{layer}.log_sigma" f32 (1,)
//!   (ln of the soft-score sigma, the trained variable; files written before the
//!   layer trained ln sigma hold "{layer}.sigma" f32 (1,) instead, still read),
//!   "{layer}.state" u32 (out, in) (0 vacant, 1 occupied, 2 + t private to t),
//!   "{layer}.bias.{t}" f32 (out,) per finished task, "{layer}.bias.current"
//!   while a task is in progress; extras as "extra.{name}" f32 (any shape);
//! - `masks.safetensors`: "{layer}.mask.{t}" u8 (ceil(out*in/8),), bit-packed row-major;
//! - `manifest.json`: format version, task names, networks (sizes, activation,
//!   mask settings, layer shapes, task in progress), the run's config, and
//!   the sha256 of both tensor files; `model.safetensors`' metadata holds the
//!   sha256 of the rest of the manifest (`manifest_digest`), so an edited
//!   manifest is refused; `provenance` (which build, run file and machine wrote
//!   it) is stamped afterwards by `write_provenance`, outside that digest.
//!
//! Dense networks (the baselines' shared trunk and per-task heads) are
//! described in `checkpoint/dense.rs`.
//!
//! Every write is atomic; loading checks version, hashes, dtypes and shapes,
//! and reports a corrupt or mismatched file as an error naming it.

use super::bitmask::BitMask;
use super::manifest_digest::{check as check_manifest_digest, manifest_digest, metadata as digest_metadata};
use super::masked::{var_values, MaskedLinear, Training};
use super::mlp::MaskedMlp;
use super::network::{AsNetworkRef, Network, NetworkRef};
use super::state::{ElementState, TaskId};
use crate::config::net::{Activation, MaskConfig};
use crate::util::{sha256_hex, write_atomic};
use anyhow::{bail, ensure, Context};
use candle_core::{Device, Tensor, Var};
use safetensors::Dtype;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

mod dense;
mod provenance;
pub(crate) mod tensors;

pub use provenance::{read_provenance, write_provenance, PROVENANCE_KEY};

use tensors::{f32_raw, serialize, Raw, Reader};

/// Bumped whenever the layout of a policy directory changes.
pub const FORMAT_VERSION: u32 = 1;
pub const MODEL_FILE: &str = "model.safetensors";
pub const MASKS_FILE: &str = "masks.safetensors";
pub const MANIFEST_FILE: &str = "manifest.json";

/// A loaded policy directory.
#[derive(Debug)]
pub struct Policy {
    /// Task names; a [`TaskId`] indexes this list.
    pub tasks: Vec<String>,
    /// The masked networks, then the dense ones.
    pub networks: Vec<Network>,
    /// Named f32 tensors (per-task action std, normaliser statistics, ...).
    pub extras: BTreeMap<String, Tensor>,
    /// The run's configuration, as given to [`save_policy`].
    pub config: serde_json::Value,
}

impl Policy {
    /// The masked network called `name`.
    pub fn network(&self, name: &str) -> anyhow::Result<&MaskedMlp> {
        let net = self
            .networks
            .iter()
            .find(|n| n.name() == name)
            .with_context(|| format!("policy has no network {name:?}"))?;
        net.as_masked().with_context(|| format!("network {name:?} is dense, not masked"))
    }

    /// Takes the network called `name` out of the policy; `dir` names the directory in the error.
    pub fn take_network(&mut self, name: &str, dir: &Path) -> anyhow::Result<Network> {
        let i = self
            .networks
            .iter()
            .position(|n| n.name() == name)
            .with_context(|| format!("{}: no network {name}", dir.display()))?;
        Ok(self.networks.remove(i))
    }
}

#[derive(Debug, Serialize, Deserialize)]
struct Manifest {
    format_version: u32,
    tasks: Vec<String>,
    networks: Vec<NetworkEntry>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    dense_networks: Vec<dense::DenseEntry>,
    extras: Vec<String>,
    config: serde_json::Value,
    files: BTreeMap<String, String>,
}

#[derive(Debug, Serialize, Deserialize)]
struct NetworkEntry {
    name: String,
    sizes: Vec<usize>,
    activation: Activation,
    mask: MaskConfig,
    finish_order: Vec<TaskId>,
    training: Option<TrainingEntry>,
    layers: Vec<LayerEntry>,
}

#[derive(Debug, Serialize, Deserialize)]
struct TrainingEntry {
    task: TaskId,
    /// A repeat of a finished task (the manifest's key keeps its first name).
    #[serde(rename = "fine_tune")]
    repeat: bool,
    iteration: usize,
}

#[derive(Debug, Serialize, Deserialize)]
struct LayerEntry {
    name: String,
    shape: [usize; 2],
    init_bound: f32,
    /// The initialiser's range over the full fan-in (`reinit_range = "initial"`); absent before
    /// issue 31, then derived from `init_bound` and the network's capacity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    full_fan_in_bound: Option<f32>,
}

/// Writes a policy directory (creating it). `tasks` names every TaskId the networks use.
pub fn save_policy(
    dir: &Path,
    tasks: &[String],
    networks: &[&dyn AsNetworkRef],
    extras: &BTreeMap<String, Tensor>,
    config: &serde_json::Value,
) -> anyhow::Result<()> {
    let networks: Vec<NetworkRef> = networks.iter().map(|n| n.as_network_ref()).collect();
    let name = |n: &NetworkRef| match n {
        NetworkRef::Masked(n) => n.name().to_string(),
        NetworkRef::Dense(n) => n.name().to_string(),
    };
    for (i, a) in networks.iter().enumerate() {
        ensure!(
            networks[..i].iter().all(|b| name(b) != name(a)),
            "{}: two networks are called {:?}",
            dir.display(),
            name(a)
        );
    }
    let mut model = BTreeMap::new();
    let mut masks = BTreeMap::new();
    let mut entries = Vec::new();
    let mut dense_entries = Vec::new();
    for net in networks {
        let net = match net {
            NetworkRef::Masked(net) => net,
            NetworkRef::Dense(net) => {
                dense_entries.push(dense::put_dense(net, tasks, &mut model)?);
                continue;
            }
        };
        let mut layers = Vec::new();
        for l in net.layers() {
            let n = &l.name;
            let shape = vec![l.out_dim, l.in_dim];
            model.insert(format!("{n}.weight"), f32_raw(&var_values(&l.weight)?, shape.clone()));
            model.insert(format!("{n}.score"), f32_raw(&var_values(&l.score_mean)?, shape.clone()));
            model.insert(format!("{n}.log_sigma"), f32_raw(&var_values(&l.log_sigma)?, vec![1]));
            let states: Vec<u8> = l.states.iter().flat_map(|s| s.to_code().to_le_bytes()).collect();
            model.insert(format!("{n}.state"), Raw { dtype: Dtype::U32, shape: shape.clone(), bytes: states });
            for (t, b) in &l.biases {
                ensure!(*t < tasks.len(), "{n}: task {t} has no name (only {} task names given)", tasks.len());
                model.insert(format!("{n}.bias.{t}"), f32_raw(b, vec![l.out_dim]));
            }
            if let Some(tr) = &l.training {
                model.insert(format!("{n}.bias.current"), f32_raw(&var_values(&tr.bias)?, vec![l.out_dim]));
            }
            for (t, m) in &l.masks {
                masks.insert(
                    format!("{n}.mask.{t}"),
                    Raw { dtype: Dtype::U8, shape: vec![m.as_bytes().len()], bytes: m.as_bytes().to_vec() },
                );
            }
            layers.push(LayerEntry {
                name: n.clone(),
                shape: [l.out_dim, l.in_dim],
                init_bound: l.init_bound,
                full_fan_in_bound: Some(l.full_fan_in_bound),
            });
        }
        let training = net.layers()[0].training.as_ref().map(|t| TrainingEntry {
            task: t.task,
            repeat: t.repeat,
            iteration: t.iteration,
        });
        if let Some(t) = &training {
            ensure!(
                t.task < tasks.len(),
                "{}: task {} in progress has no name (only {} task names given)",
                net.name(),
                t.task,
                tasks.len()
            );
        }
        entries.push(NetworkEntry {
            name: net.name().to_string(),
            sizes: net.sizes().to_vec(),
            activation: net.activation(),
            mask: net.mask_config().clone(),
            finish_order: net.finished_tasks().to_vec(),
            training,
            layers,
        });
    }
    for (name, t) in extras {
        let v = t.flatten_all()?.to_dtype(candle_core::DType::F32)?.to_vec1::<f32>()?;
        model.insert(format!("extra.{name}"), f32_raw(&v, t.dims().to_vec()));
    }
    let mut manifest = Manifest {
        format_version: FORMAT_VERSION,
        tasks: tasks.to_vec(),
        networks: entries,
        dense_networks: dense_entries,
        extras: extras.keys().cloned().collect(),
        config: config.clone(),
        files: BTreeMap::new(),
    };
    // The model file records the manifest's digest; the manifest then records the files' hashes.
    // Through text, as a loader will see it (an f32 goes to JSON as its shortest decimal).
    let digest = manifest_digest(&serde_json::from_str(&serde_json::to_string(&manifest)?)?);
    let model_bytes = serialize(&model, Some(digest_metadata(digest)))?;
    let mask_bytes = serialize(&masks, None)?;
    manifest.files = BTreeMap::from([
        (MODEL_FILE.to_string(), sha256_hex(&model_bytes)),
        (MASKS_FILE.to_string(), sha256_hex(&mask_bytes)),
    ]);
    write_atomic(&dir.join(MODEL_FILE), &model_bytes)?;
    write_atomic(&dir.join(MASKS_FILE), &mask_bytes)?;
    // The manifest goes last: it names the hashes of the files written before it.
    write_atomic(&dir.join(MANIFEST_FILE), serde_json::to_string_pretty(&manifest)?.as_bytes())
}

/// Reads one tensor file and checks its hash against the manifest.
fn read_checked(dir: &Path, file: &str, manifest: &Manifest) -> anyhow::Result<Vec<u8>> {
    let path = dir.join(file);
    let bytes = std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
    let want = manifest
        .files
        .get(file)
        .with_context(|| format!("{}: manifest lists no hash for {file}", dir.join(MANIFEST_FILE).display()))?;
    let got = sha256_hex(&bytes);
    ensure!(
        &got == want,
        "{}: content hash mismatch (manifest {want}, file {got}): the file is corrupt or from another policy",
        path.display()
    );
    Ok(bytes)
}

fn var(values: Vec<f32>, shape: &[usize]) -> anyhow::Result<Var> {
    Ok(Var::from_tensor(&Tensor::from_vec(values, shape, &Device::Cpu)?)?)
}

/// An integer as a checkpoint extra, exactly: f32 holds integers only up to 2^24, so the
/// tensor is [high, low] 24 bits (counts, step counters).
pub fn integer_tensor(n: u64) -> candle_core::Result<Tensor> {
    Tensor::new(&[(n >> 24) as f32, (n & 0xff_ffff) as f32], &Device::Cpu)
}

/// The integer [`integer_tensor`] wrote; `name` (the extra's key) is in the error.
pub fn tensor_integer(t: &Tensor, name: &str) -> anyhow::Result<u64> {
    match t.flatten_all()?.to_vec1::<f32>()?.as_slice() {
        [hi, lo] => Ok((*hi as u64) << 24 | *lo as u64),
        other => bail!("{name} has {} values, expected 2", other.len()),
    }
}

/// [`MaskConfig::fill_in_pre_issue_13`], [`MaskConfig::fill_in_pre_issue_31`],
/// [`MaskConfig::fill_in_pre_issue_39`] and [`MaskConfig::fill_in_pre_issue_60`] on every
/// network's `mask` and on the run configuration's `net.mask` of a manifest.
fn fill_in_old_masks(manifest: &mut serde_json::Value) {
    let fill = |mask: &mut serde_json::Value| {
        MaskConfig::fill_in_pre_issue_13(mask);
        MaskConfig::fill_in_pre_issue_31(mask);
        MaskConfig::fill_in_pre_issue_39(mask);
        MaskConfig::fill_in_pre_issue_60(mask);
    };
    if let Some(networks) = manifest.get_mut("networks").and_then(|n| n.as_array_mut()) {
        networks.iter_mut().filter_map(|n| n.get_mut("mask")).for_each(fill);
    }
    if let Some(mask) = manifest.pointer_mut("/config/config/net/mask") {
        fill(mask);
    }
}

/// Loads a policy directory written by [`save_policy`].
pub fn load_policy(dir: &Path) -> anyhow::Result<Policy> {
    let manifest_path = dir.join(MANIFEST_FILE);
    let text =
        std::fs::read_to_string(&manifest_path).with_context(|| format!("reading {}", manifest_path.display()))?;
    let manifest_json: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not a valid manifest", manifest_path.display()))?;
    // Masks saved before issue 13 ran with sigma in score units, before issue 31 with every
    // score redrawn at a task's end (the digest below is of the file as written).
    let mut upgraded = manifest_json.clone();
    fill_in_old_masks(&mut upgraded);
    let manifest = Manifest::deserialize(&upgraded)
        .with_context(|| format!("{}: not a valid manifest", manifest_path.display()))?;
    ensure!(
        manifest.format_version == FORMAT_VERSION,
        "{}: format version {} is not supported (this build reads {FORMAT_VERSION})",
        manifest_path.display(),
        manifest.format_version
    );
    let model_bytes = read_checked(dir, MODEL_FILE, &manifest)?;
    let mask_bytes = read_checked(dir, MASKS_FILE, &manifest)?;
    let model = Reader::new(&dir.join(MODEL_FILE), &model_bytes)?;
    let mask_file = Reader::new(&dir.join(MASKS_FILE), &mask_bytes)?;
    let n_tasks = manifest.tasks.len();
    let mut networks = Vec::new();
    for e in &manifest.networks {
        let ctx = || format!("{}: network {}", manifest_path.display(), e.name);
        e.mask.validate().with_context(ctx)?;
        ensure!(
            e.sizes.len() == e.layers.len() + 1,
            "{}: {} sizes for {} layers",
            ctx(),
            e.sizes.len(),
            e.layers.len()
        );
        ensure!(
            !e.layers.is_empty() && e.sizes.iter().all(|s| *s > 0),
            "{}: no layers, or a zero size in {:?}",
            ctx(),
            e.sizes
        );
        ensure!(
            e.finish_order.iter().all(|t| *t < n_tasks),
            "{}: a finished task id is out of range of the {n_tasks} tasks",
            ctx()
        );
        for (i, t) in e.finish_order.iter().enumerate() {
            ensure!(!e.finish_order[..i].contains(t), "{}: task {t} is listed twice in finish_order", ctx());
        }
        if let Some(tr) = &e.training {
            ensure!(
                tr.task < n_tasks,
                "{}: the task in progress ({}) is out of range of the {n_tasks} tasks",
                ctx(),
                tr.task
            );
            // A finished task can only be repeated; a new one has no mask to repeat.
            let finished = e.finish_order.contains(&tr.task);
            ensure!(
                tr.repeat == finished,
                "{}: task {} in progress has fine_tune = {}, but it has {}finished",
                ctx(),
                tr.task,
                tr.repeat,
                if finished { "" } else { "not " }
            );
        }
        let mut layers = Vec::new();
        for (i, le) in e.layers.iter().enumerate() {
            let [out_dim, in_dim] = le.shape;
            ensure!(
                [e.sizes[i + 1], e.sizes[i]] == le.shape,
                "{}: layer {} shape {:?} does not match sizes {:?}",
                ctx(),
                le.name,
                le.shape,
                e.sizes
            );
            // The re-initialisation draws from U(-init_bound, init_bound).
            ensure!(
                le.init_bound.is_finite() && le.init_bound > 0.0,
                "{}: layer {} has init_bound {}, expected a finite value > 0",
                ctx(),
                le.name,
                le.init_bound
            );
            // sqrt(g / F) = sqrt(g / (c F)) * sqrt(c F / F), c F at least 1 as the layer made it.
            let derived = || le.init_bound * ((e.mask.capacity * in_dim as f64).max(1.0) / in_dim as f64).sqrt() as f32;
            let full_fan_in_bound = le.full_fan_in_bound.unwrap_or_else(derived);
            ensure!(
                full_fan_in_bound.is_finite() && full_fan_in_bound > 0.0,
                "{}: layer {} has full_fan_in_bound {full_fan_in_bound}, expected a finite value > 0",
                ctx(),
                le.name
            );
            let n = &le.name;
            let shape = [out_dim, in_dim];
            let states = model
                .u32s(&format!("{n}.state"), &shape)?
                .into_iter()
                .map(|c| {
                    let s = ElementState::from_code(c);
                    match s {
                        ElementState::Private(t) if t >= n_tasks => bail!(
                            "{}: {n}.state names private task {t}, but there are {n_tasks} tasks",
                            dir.join(MODEL_FILE).display()
                        ),
                        _ => Ok(s),
                    }
                })
                .collect::<anyhow::Result<Vec<_>>>()?;
            let mut masks = BTreeMap::new();
            let mut biases = BTreeMap::new();
            for &t in &e.finish_order {
                let key = format!("{n}.mask.{t}");
                let bytes = mask_file.raw(&key, Dtype::U8, &mask_file.shape_of(&key)?)?.to_vec();
                let m = BitMask::from_bytes(out_dim * in_dim, bytes)
                    .with_context(|| format!("{}: tensor {key}", dir.join(MASKS_FILE).display()))?;
                let bad = (0..m.len()).find(|&i| {
                    m.get(i) && !matches!(states[i], ElementState::Occupied) && states[i] != ElementState::Private(t)
                });
                ensure!(
                    bad.is_none(),
                    "{}: {key} selects element {} whose state is {:?}",
                    dir.join(MASKS_FILE).display(),
                    bad.unwrap_or(0),
                    states[bad.unwrap_or(0)]
                );
                masks.insert(t, m);
                biases.insert(t, model.f32s(&format!("{n}.bias.{t}"), &[out_dim])?);
            }
            let training = match &e.training {
                Some(tr) => Some(Training::new(
                    tr.task,
                    tr.repeat,
                    tr.iteration,
                    var(model.f32s(&format!("{n}.bias.current"), &[out_dim])?, &[out_dim])?,
                )),
                None => None,
            };
            layers.push(MaskedLinear {
                name: n.clone(),
                out_dim,
                in_dim,
                cfg: e.mask.clone(),
                init_bound: le.init_bound,
                full_fan_in_bound,
                weight: var(model.f32s(&format!("{n}.weight"), &shape)?, &shape)?,
                score_mean: var(model.f32s(&format!("{n}.score"), &shape)?, &shape)?,
                log_sigma: var(model.log_sigma(n)?, &[1])?,
                states,
                masks,
                biases,
                finish_order: e.finish_order.clone(),
                training,
            });
        }
        networks.push(Network::Masked(MaskedMlp {
            name: e.name.clone(),
            sizes: e.sizes.clone(),
            activation: e.activation,
            cfg: e.mask.clone(),
            layers,
        }));
    }
    for e in &manifest.dense_networks {
        ensure!(
            networks.iter().all(|n| n.name() != e.name),
            "{}: two networks are called {:?}",
            manifest_path.display(),
            e.name
        );
        networks.push(Network::Dense(dense::read_dense(e, &model, n_tasks, &manifest_path.display().to_string())?));
    }
    let mut extras = BTreeMap::new();
    for name in &manifest.extras {
        let key = format!("extra.{name}");
        let shape = model.shape_of(&key)?;
        extras.insert(name.clone(), Tensor::from_vec(model.f32s(&key, &shape)?, shape, &Device::Cpu)?);
    }
    // Last, so that a manifest edited into an inconsistent state gets the more specific error above.
    check_manifest_digest(&model_bytes, &manifest_json, &manifest_path)?;
    Ok(Policy { tasks: manifest.tasks, networks, extras, config: manifest.config })
}
