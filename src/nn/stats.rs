//! Mask statistics (printed by `quadcl masks`): per network, per layer, per
//! task, which parameters are used. The JSON shape is documented on [`MaskReport`].
//! A dense network (the baselines) reports its trunk layers as wholly shared by
//! every task and its heads as one layer `{net}.head` private to each task.

use super::dense::DenseMlp;
use super::masked::MaskedLinear;
use super::network::Network;
use super::state::ElementState;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Per network, layer and task, which parameters are used. The JSON shape is
/// stable (scripts read it):
///
/// `{"tasks": [names], "networks": [{"name", "layers": [{"name", "shape": [out, in],
/// "vacant", "occupied", "private": {task: count}, "per_task": [{"task", "selected",
/// "fraction", "from_vacant", "from_occupied"}], "overlap": [[count]]}]}]}`
///
/// `from_vacant` counts a task's elements that no task finished before it
/// used (fresh capacity), `from_occupied` the ones it reused; `overlap[i][j]`
/// counts elements selected by both the i-th and j-th entries of `per_task`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MaskReport {
    pub tasks: Vec<String>,
    pub networks: Vec<NetworkMasks>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NetworkMasks {
    pub name: String,
    pub layers: Vec<LayerMasks>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LayerMasks {
    pub name: String,
    pub shape: [usize; 2],
    pub vacant: usize,
    pub occupied: usize,
    pub private: BTreeMap<String, usize>,
    pub per_task: Vec<TaskMask>,
    pub overlap: Vec<Vec<usize>>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TaskMask {
    pub task: String,
    pub selected: usize,
    /// selected / (out * in), rounded to 6 decimals.
    pub fraction: f64,
    pub from_vacant: usize,
    pub from_occupied: usize,
}

fn task_name(tasks: &[String], t: usize) -> String {
    tasks.get(t).cloned().unwrap_or_else(|| format!("task{t}"))
}

fn layer_masks(l: &MaskedLinear, tasks: &[String]) -> LayerMasks {
    let (out_dim, in_dim) = l.shape();
    let n = out_dim * in_dim;
    let count = |s: ElementState| l.states().iter().filter(|x| **x == s).count();
    let order = &l.finish_order;
    let mut private = BTreeMap::new();
    let mut per_task = Vec::new();
    let mut ids: Vec<usize> = l.masks.keys().copied().collect();
    ids.sort_unstable();
    for &t in &ids {
        private.insert(task_name(tasks, t), count(ElementState::Private(t)));
        let m = &l.masks[&t];
        let pos = order.iter().position(|x| *x == t).unwrap_or(order.len());
        let earlier: Vec<_> = order[..pos].iter().map(|e| &l.masks[e]).collect();
        let from_vacant = (0..n).filter(|&i| m.get(i) && !earlier.iter().any(|e| e.get(i))).count();
        let selected = m.count_ones();
        per_task.push(TaskMask {
            task: task_name(tasks, t),
            selected,
            fraction: (selected as f64 / n as f64 * 1e6).round() / 1e6,
            from_vacant,
            from_occupied: selected - from_vacant,
        });
    }
    let overlap = ids.iter().map(|a| ids.iter().map(|b| l.masks[a].overlap(&l.masks[b])).collect()).collect();
    LayerMasks {
        name: l.name().to_string(),
        shape: [out_dim, in_dim],
        vacant: count(ElementState::Vacant),
        occupied: count(ElementState::Occupied),
        private,
        per_task,
        overlap,
    }
}

/// The statistics of every network; `tasks` names the task ids.
pub fn mask_report(tasks: &[String], networks: &[&Network]) -> MaskReport {
    MaskReport {
        tasks: tasks.to_vec(),
        networks: networks
            .iter()
            .map(|n| NetworkMasks {
                name: n.name().to_string(),
                layers: match n {
                    Network::Masked(n) => n.layers().iter().map(|l| layer_masks(l, tasks)).collect(),
                    Network::Dense(n) => dense_layer_masks(n, tasks),
                },
            })
            .collect(),
    }
}

/// A dense network's trunk layers (every element used by every task with a head, the first
/// to finish counting them as fresh) and its heads (one layer, each task's head private to it).
fn dense_layer_masks(net: &DenseMlp, tasks: &[String]) -> Vec<LayerMasks> {
    let ids: Vec<usize> = net.heads.keys().copied().collect();
    let first = net.finished_tasks().first().copied().or(ids.first().copied());
    let layer = |name: String, out_dim: usize, in_dim: usize, head: bool| {
        let n = out_dim * in_dim;
        let per_task = ids
            .iter()
            .map(|&t| {
                let fresh = head || Some(t) == first;
                TaskMask {
                    task: task_name(tasks, t),
                    selected: n,
                    fraction: 1.0,
                    from_vacant: if fresh { n } else { 0 },
                    from_occupied: if fresh { 0 } else { n },
                }
            })
            .collect();
        let overlap = ids.iter().map(|a| ids.iter().map(|b| if head && a != b { 0 } else { n }).collect()).collect();
        LayerMasks {
            name,
            shape: [out_dim, in_dim],
            vacant: 0,
            occupied: if head { 0 } else { n },
            private: if head { ids.iter().map(|&t| (task_name(tasks, t), n)).collect() } else { BTreeMap::new() },
            per_task,
            overlap,
        }
    };
    let s = net.sizes();
    let last = s.len() - 2;
    let mut out: Vec<_> = (0..last).map(|i| layer(format!("{}.l{i}", net.name()), s[i + 1], s[i], false)).collect();
    out.push(layer(format!("{}.head", net.name()), s[last + 1], s[last], true));
    out
}

impl MaskReport {
    /// The statistics of every network of the policy directory `dir` (what `quadcl masks` prints).
    pub fn of_policy(dir: &std::path::Path) -> anyhow::Result<Self> {
        let policy = super::checkpoint::load_policy(dir)?;
        Ok(mask_report(&policy.tasks, &policy.networks.iter().collect::<Vec<_>>()))
    }

    /// For task `task` in network `network`: per other task, the share of `task`'s selected
    /// elements (over all the network's layers) that the other task selects too.
    pub fn shared_with(&self, network: &str, task: &str) -> Vec<(String, f64)> {
        let Some(net) = self.networks.iter().find(|n| n.name == network) else { return Vec::new() };
        let mut shared: Vec<(String, usize)> = Vec::new();
        let mut own = 0;
        for l in &net.layers {
            let Some(i) = l.per_task.iter().position(|p| p.task == task) else { continue };
            own += l.per_task[i].selected;
            for (j, p) in l.per_task.iter().enumerate().filter(|(j, _)| *j != i) {
                match shared.iter_mut().find(|(n, _)| *n == p.task) {
                    Some(e) => e.1 += l.overlap[i][j],
                    None => shared.push((p.task.clone(), l.overlap[i][j])),
                }
            }
        }
        shared.into_iter().map(|(n, c)| (n, c as f64 / own.max(1) as f64)).collect()
    }

    /// A readable table: one block per layer, one line per task.
    pub fn to_table(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(s, "tasks: {}", self.tasks.join(", "));
        for net in &self.networks {
            for l in &net.layers {
                let total = l.shape[0] * l.shape[1];
                let private: usize = l.private.values().sum();
                let _ = writeln!(
                    s,
                    "\n{} [{} x {}]  vacant {} ({:.1}%)  occupied {} ({:.1}%)  private {} ({:.1}%)",
                    l.name,
                    l.shape[0],
                    l.shape[1],
                    l.vacant,
                    pct(l.vacant, total),
                    l.occupied,
                    pct(l.occupied, total),
                    private,
                    pct(private, total)
                );
                let _ = writeln!(
                    s,
                    "  {:<24} {:>9} {:>9} {:>11} {:>13} {:>8}",
                    "task", "selected", "fraction", "from_vacant", "from_occupied", "private"
                );
                for t in &l.per_task {
                    let _ = writeln!(
                        s,
                        "  {:<24} {:>9} {:>8.1}% {:>11} {:>13} {:>8}",
                        t.task,
                        t.selected,
                        t.fraction * 100.0,
                        t.from_vacant,
                        t.from_occupied,
                        l.private.get(&t.task).copied().unwrap_or(0)
                    );
                }
            }
        }
        s
    }
}

fn pct(a: usize, total: usize) -> f64 {
    100.0 * a as f64 / total.max(1) as f64
}
