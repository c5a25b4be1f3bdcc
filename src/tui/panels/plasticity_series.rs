//! The plasticity diagnostics (`plasticity/*`, `rl/plasticity.rs`) and each
//! layer's mask churn (`charts/mask_churn/LAYER`) as the Curves panel draws
//! them: one line per network (dormant units, effective rank) or per layer of
//! one network (selected |w|, trainable share, mask churn; `n` cycles the
//! network, as in the Masks panel), from the steps' curves laid end to end,
//! each step starting where the previous one's iterations ended.

use crate::engine::TaskCurve;

/// One named line: (iteration, value) points.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// What [`plasticity_series`] found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlasticitySeries {
    /// One line per network, or per layer of [`Self::network`].
    pub lines: Vec<Series>,
    /// The x of each boundary between two steps.
    pub bounds: Vec<f64>,
    /// For per-layer metrics: the network shown, its place (from 1) and how many there are.
    pub network: Option<(String, usize, usize)>,
}

/// The iterations a curve covers: its longest series.
fn iterations(curve: &TaskCurve) -> usize {
    curve.plasticity.values().map(Vec::len).chain(std::iter::once(curve.performance.len())).max().unwrap_or(0)
}

/// The network a layer name belongs to ("actor.l0" -> "actor").
fn network_of(layer: &str) -> &str {
    layer.rsplit_once('.').map_or(layer, |(net, _)| net)
}

/// The lines of `prefix` (`plasticity/dormant`, ...) in `curves`, in order. With
/// `per_layer`, only the layers of the `network`-th network (modulo how many appear).
pub fn plasticity_series(curves: &[&TaskCurve], prefix: &str, per_layer: bool, network: usize) -> PlasticitySeries {
    let names = |c: &TaskCurve| -> Vec<String> {
        c.plasticity
            .keys()
            .filter_map(|k| k.strip_prefix(prefix).and_then(|k| k.strip_prefix('/')).map(str::to_string))
            .collect()
    };
    let values = |c: &'_ TaskCurve, name: &str| c.plasticity.get(&format!("{prefix}/{name}")).cloned();
    lines_of(curves, names, values, 0, per_layer, network)
}

/// Each layer's mask churn (the share of an iteration's selected weights the previous
/// iteration had not selected), for the layers of the `network`-th network; a step's churn
/// starts at its second iteration.
pub fn churn_series(curves: &[&TaskCurve], network: usize) -> PlasticitySeries {
    let names = |c: &TaskCurve| c.mask_churn.keys().cloned().collect::<Vec<_>>();
    let values = |c: &'_ TaskCurve, name: &str| c.mask_churn.get(name).cloned();
    lines_of(curves, names, values, 1, true, network)
}

/// The named lines `names` and `values` give in `curves`, each step's values from `offset`
/// iterations into it (see [`plasticity_series`]).
fn lines_of(
    curves: &[&TaskCurve],
    names_of: impl Fn(&TaskCurve) -> Vec<String>,
    values_of: impl Fn(&TaskCurve, &str) -> Option<Vec<f64>>,
    offset: usize,
    per_layer: bool,
    network: usize,
) -> PlasticitySeries {
    let mut names: Vec<String> = Vec::new();
    for c in curves {
        for name in names_of(c) {
            if !names.contains(&name) {
                names.push(name);
            }
        }
    }
    let mut shown = None;
    if per_layer {
        let mut networks: Vec<&str> = Vec::new();
        names.iter().map(|n| network_of(n)).for_each(|n| {
            if !networks.contains(&n) {
                networks.push(n);
            }
        });
        if let Some(net) = networks.get(network % networks.len().max(1)).map(|n| n.to_string()) {
            shown = Some((net.clone(), network % networks.len() + 1, networks.len()));
            names.retain(|n| network_of(n) == net);
        }
    }
    let mut lines: Vec<Series> = names.iter().map(|n| Series { name: n.clone(), points: Vec::new() }).collect();
    let (mut bounds, mut start) = (Vec::new(), 0usize);
    for (i, c) in curves.iter().enumerate() {
        if i > 0 {
            bounds.push(start as f64 - 0.5);
        }
        for line in &mut lines {
            if let Some(values) = values_of(c, &line.name) {
                line.points.extend(values.iter().enumerate().map(|(j, v)| ((start + offset + j) as f64, *v)));
            }
        }
        start += iterations(c);
    }
    lines.retain(|l| !l.points.is_empty());
    PlasticitySeries { lines, bounds, network: shown }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(iterations: usize, keys: &[(&str, f64)]) -> TaskCurve {
        let mut c = TaskCurve { performance: vec![0.5; iterations], ..TaskCurve::default() };
        for (k, v) in keys {
            c.plasticity.insert(k.to_string(), vec![*v; iterations]);
        }
        c
    }

    #[test]
    fn per_network_lines_run_end_to_end_over_the_steps() {
        let a = curve(3, &[("plasticity/dormant/actor", 0.1), ("plasticity/dormant/critic", 0.2)]);
        let b = curve(2, &[("plasticity/dormant/actor", 0.3), ("plasticity/effective_rank/actor", 9.0)]);
        let s = plasticity_series(&[&a, &b], "plasticity/dormant", false, 0);
        assert_eq!(s.lines.iter().map(|l| l.name.as_str()).collect::<Vec<_>>(), ["actor", "critic"]);
        assert_eq!(s.lines[0].points.iter().map(|p| p.0).collect::<Vec<_>>(), [0.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!(s.lines[0].points[3].1, 0.3);
        assert_eq!(s.lines[1].points.len(), 3, "the critic's line ends where its data does");
        assert_eq!((s.bounds, s.network), (vec![2.5], None));
    }

    #[test]
    fn per_layer_lines_show_one_network_at_a_time() {
        let a = curve(
            2,
            &[
                ("plasticity/selected_abs_w/actor.l0", 0.1),
                ("plasticity/selected_abs_w/actor.l1", 0.2),
                ("plasticity/selected_abs_w/critic.l0", 0.3),
            ],
        );
        let s = plasticity_series(&[&a], "plasticity/selected_abs_w", true, 1);
        assert_eq!(s.lines.iter().map(|l| l.name.as_str()).collect::<Vec<_>>(), ["critic.l0"]);
        assert_eq!(s.network, Some(("critic".to_string(), 2, 2)));
        let s = plasticity_series(&[&a], "plasticity/selected_abs_w", true, 2);
        assert_eq!(s.network, Some(("actor".to_string(), 1, 2)), "the count wraps");
        assert_eq!(s.lines.len(), 2);
        assert!(plasticity_series(&[&curve(2, &[])], "plasticity/dormant", false, 0).lines.is_empty());
    }

    #[test]
    fn each_layers_mask_churn_starts_at_its_steps_second_iteration() {
        let mut a = curve(3, &[]);
        a.mask_churn.insert("actor.l0".into(), vec![0.1, 0.2]);
        a.mask_churn.insert("critic.l0".into(), vec![0.3, 0.4]);
        let mut b = curve(2, &[]);
        b.mask_churn.insert("actor.l0".into(), vec![0.05]);
        let s = churn_series(&[&a, &b], 0);
        assert_eq!(s.network, Some(("actor".to_string(), 1, 2)));
        assert_eq!(s.lines.len(), 1);
        assert_eq!(s.lines[0].points, vec![(1.0, 0.1), (2.0, 0.2), (4.0, 0.05)]);
        assert_eq!(s.bounds, vec![2.5]);
    }
}
