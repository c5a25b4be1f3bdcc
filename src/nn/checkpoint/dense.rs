//! The dense networks of a policy directory ([`DenseMlp`], the non-mask
//! baselines), beside the masked ones in the same files.
//!
//! - `model.safetensors`: "{net}.l{i}.weight" f32 (out, in) and "{net}.l{i}.bias"
//!   f32 (out,) per trunk layer; "{net}.head.{t}.weight" / ".bias" per task with
//!   a head; "{net}.head.init.weight" / ".bias", the head a first task copies;
//! - `manifest.json`: `dense_networks` (absent when there are none, so a masked
//!   policy's manifest is what it always was): sizes, activation, the tasks
//!   with heads, finish order, the task in progress and the one that ended last.

use super::{f32_raw, Raw, Reader};
use crate::config::net::Activation;
use crate::nn::dense::{DenseLayer, DenseMlp};
use crate::nn::state::TaskId;
use anyhow::ensure;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Debug, Serialize, Deserialize)]
pub(super) struct DenseEntry {
    pub name: String,
    sizes: Vec<usize>,
    activation: Activation,
    heads: Vec<TaskId>,
    finish_order: Vec<TaskId>,
    current: Option<TaskId>,
    last_ended: Option<TaskId>,
}

fn values(var: &candle_core::Var) -> anyhow::Result<Vec<f32>> {
    Ok(var.as_tensor().flatten_all()?.to_vec1::<f32>()?)
}

fn put_layer(prefix: &str, l: &DenseLayer, model: &mut BTreeMap<String, Raw>) -> anyhow::Result<()> {
    let dims = l.weight.as_tensor().dims().to_vec();
    model.insert(format!("{prefix}.weight"), f32_raw(&values(&l.weight)?, dims.clone()));
    model.insert(format!("{prefix}.bias"), f32_raw(&values(&l.bias)?, vec![dims[0]]));
    Ok(())
}

/// Puts `net`'s tensors into `model`; its manifest entry.
pub(super) fn put_dense(
    net: &DenseMlp,
    tasks: &[String],
    model: &mut BTreeMap<String, Raw>,
) -> anyhow::Result<DenseEntry> {
    let n = net.name();
    for (i, l) in net.trunk().iter().enumerate() {
        put_layer(&format!("{n}.l{i}"), l, model)?;
    }
    for (t, head) in &net.heads {
        ensure!(*t < tasks.len(), "{n}: task {t} has no name (only {} task names given)", tasks.len());
        put_layer(&format!("{n}.head.{t}"), head, model)?;
    }
    put_layer(&format!("{n}.head.init"), &net.initial_head, model)?;
    Ok(DenseEntry {
        name: n.to_string(),
        sizes: net.sizes().to_vec(),
        activation: net.activation(),
        heads: net.heads.keys().copied().collect(),
        finish_order: net.finished_tasks().to_vec(),
        current: net.current_task(),
        last_ended: net.last_ended,
    })
}

fn read_layer(model: &Reader, prefix: &str, out_dim: usize, in_dim: usize) -> anyhow::Result<DenseLayer> {
    DenseLayer::from_values(
        model.f32s(&format!("{prefix}.weight"), &[out_dim, in_dim])?,
        model.f32s(&format!("{prefix}.bias"), &[out_dim])?,
        out_dim,
        in_dim,
    )
}

/// The dense network of manifest entry `e`; `at` names the manifest for errors.
pub(super) fn read_dense(e: &DenseEntry, model: &Reader, n_tasks: usize, at: &str) -> anyhow::Result<DenseMlp> {
    let ctx = format!("{at}: dense network {}", e.name);
    ensure!(
        e.sizes.len() >= 2 && e.sizes.iter().all(|s| *s > 0),
        "{ctx}: sizes {:?} need an input and an output, none zero",
        e.sizes
    );
    let in_range = |t: &TaskId| *t < n_tasks;
    ensure!(
        e.heads.iter().chain(&e.finish_order).chain(&e.current).chain(&e.last_ended).all(in_range),
        "{ctx}: a task id is out of range of the {n_tasks} tasks"
    );
    ensure!(
        e.finish_order.iter().chain(&e.current).chain(&e.last_ended).all(|t| e.heads.contains(t)),
        "{ctx}: a finished, current or last task has no head"
    );
    for (i, t) in e.finish_order.iter().enumerate() {
        ensure!(!e.finish_order[..i].contains(t), "{ctx}: task {t} is listed twice in finish_order");
    }
    let s = &e.sizes;
    let last = s.len() - 2;
    let trunk = (0..last)
        .map(|i| read_layer(model, &format!("{}.l{i}", e.name), s[i + 1], s[i]))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let initial = read_layer(model, &format!("{}.head.init", e.name), s[last + 1], s[last])?;
    let mut net = DenseMlp::from_parts(&e.name, s, e.activation, trunk, initial);
    for &t in &e.heads {
        net.heads.insert(t, read_layer(model, &format!("{}.head.{t}", e.name), s[last + 1], s[last])?);
    }
    net.finish_order = e.finish_order.clone();
    net.current = e.current;
    net.last_ended = e.last_ended;
    Ok(net)
}
