//! Figure `plasticity`: the plasticity measures the curves recorded (`plasticity/FAMILY/MEMBER`,
//! issue 31), one panel per family over the whole sequence with its task boundaries. For one
//! run, a line per member (network or layer) with the members' legend beside the panel; for
//! several, one line per run: the mean over the family's members, in the run's colour.

use super::data::{plasticity_parts, Curve, RunData};
use super::header::{draw_header, header_height};
use super::legend::{draw_legend, LegendEntry};
use super::panel::{draw_line_panel, LinePanel};
use super::sequence::{sequence_span, task_boundaries};
use super::style::series_colour;
use super::{run_legend, smoothing_note, PlotOptions};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::BTreeMap;

const WIDTH: u32 = 1600;
const PANEL_HEIGHT: u32 = 340;
/// The members' legend beside each panel of a single run.
const MEMBER_LEGEND_WIDTH: u32 = 300;
/// A family with more members than this (a measure per layer of every network) is drawn as
/// one line per network, the mean over its layers.
const MAX_MEMBER_LINES: usize = 8;

/// The figure's title.
pub const PLASTICITY_TITLE: &str = "Plasticity measures";

/// The families known by name, in the order shown: (family, caption, value axis, values the
/// axis always shows). Others follow in name order, captioned by their name.
const KNOWN: [(&str, &str, &str, &[f64]); 4] = [
    (
        "dormant",
        "dormant units (ReDo: mean |activation| <= 0.1 of the layer's mean)",
        "share of hidden units (0-1)",
        &[0.0],
    ),
    ("effective_rank", "effective rank of the last hidden layer's features", "rank (dimensions)", &[0.0]),
    ("selected_abs_w", "mean |w| of each layer's selected weights", "mean |w| (weight units)", &[0.0]),
    ("trainable_share", "share of the task's selected weights it may still change", "share (0-1)", &[0.0, 1.0]),
];

/// The families the runs recorded, known ones first.
fn families(runs: &[RunData]) -> Vec<String> {
    let mut found: Vec<String> = Vec::new();
    for name in runs.iter().flat_map(|r| &r.steps).flat_map(|s| s.plasticity.keys()) {
        if let Some((family, _)) = plasticity_parts(name) {
            if !found.iter().any(|f| f == family) {
                found.push(family.to_string());
            }
        }
    }
    let rank = |f: &String| KNOWN.iter().position(|k| k.0 == f).unwrap_or(KNOWN.len());
    found.sort_by(|a, b| (rank(a), a).cmp(&(rank(b), b)));
    found
}

/// The family's caption, value axis and fixed values.
fn describe(family: &str) -> (String, String, Vec<f64>) {
    match KNOWN.iter().find(|k| k.0 == family) {
        Some((_, caption, axis, includes)) => (caption.to_string(), axis.to_string(), includes.to_vec()),
        None => (family.to_string(), "value".to_string(), Vec::new()),
    }
}

/// Per member of `family` in `run`, its curve over the whole sequence (steps placed one after
/// another): a piece per step index that recorded it.
fn members(run: &RunData, family: &str, options: &PlotOptions) -> BTreeMap<String, BTreeMap<usize, Curve>> {
    let mut out: BTreeMap<String, BTreeMap<usize, Curve>> = BTreeMap::new();
    for (index, (offset, step)) in run.step_offsets().into_iter().zip(&run.steps).enumerate() {
        for (name, curve) in &step.plasticity {
            if let Some((f, member)) = plasticity_parts(name).filter(|(f, _)| *f == family) {
                let label = if member.is_empty() { f } else { member };
                let placed = curve.smoothed(options.smooth).shifted(offset as f64);
                out.entry(label.to_string()).or_default().insert(index, placed);
            }
        }
    }
    out
}

/// `members` as at most [`MAX_MEMBER_LINES`] lines: as they are when they are few, else
/// grouped by network (the name before the first `.`: `actor.l0` -> `actor`), each group's
/// mean per step, labelled with its number of layers.
fn at_most_a_few(members: BTreeMap<String, BTreeMap<usize, Curve>>) -> BTreeMap<String, BTreeMap<usize, Curve>> {
    if members.len() <= MAX_MEMBER_LINES {
        return members;
    }
    let mut networks: BTreeMap<String, Vec<&BTreeMap<usize, Curve>>> = BTreeMap::new();
    for (name, pieces) in &members {
        let network = name.split_once('.').map_or(name.as_str(), |(n, _)| n);
        networks.entry(network.to_string()).or_default().push(pieces);
    }
    let mut out = BTreeMap::new();
    for (network, layers) in networks {
        let steps: std::collections::BTreeSet<usize> = layers.iter().flat_map(|l| l.keys().copied()).collect();
        let mean = steps
            .into_iter()
            .map(|step| (step, Curve::mean_of(&layers.iter().filter_map(|l| l.get(&step)).collect::<Vec<_>>())))
            .collect();
        let label = if layers.len() == 1 { network } else { format!("{network} ({} layers)", layers.len()) };
        out.insert(label, mean);
    }
    out
}

/// The figure's size for `runs`.
pub fn plasticity_size(runs: &[RunData]) -> (u32, u32) {
    let legend = if runs.len() > 1 { run_legend(runs) } else { Vec::new() };
    (WIDTH, header_height(WIDTH, &legend) + PANEL_HEIGHT * families(runs).len().max(1) as u32)
}

/// Draws the figure for `runs` into `area`.
pub fn draw_plasticity<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    runs: &[RunData],
    options: &PlotOptions,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let single = runs.len() == 1;
    let (title, legend) = match runs {
        [run] => (format!("{PLASTICITY_TITLE}: {}{}", run.label, smoothing_note(options)), Vec::new()),
        _ => (
            format!("{PLASTICITY_TITLE}, each run's mean over its networks or layers{}", smoothing_note(options)),
            run_legend(runs),
        ),
    };
    let body = draw_header(area, &title, &legend)?;
    let families = families(runs);
    let panels = body.split_evenly((families.len().max(1), 1));
    for (family, panel_area) in families.iter().zip(&panels) {
        let (caption, y_desc, y_includes) = describe(family);
        let mut lines = Vec::new();
        let mut member_legend = Vec::new();
        if single {
            for (i, (member, pieces)) in at_most_a_few(members(&runs[0], family, options)).into_iter().enumerate() {
                lines.extend(pieces.into_values().map(|c| (c, series_colour(i))));
                member_legend.push(LegendEntry { label: member, colour: series_colour(i) });
            }
        } else {
            for (i, run) in runs.iter().enumerate() {
                let members = members(run, family, options);
                for (step, _) in run.steps.iter().enumerate() {
                    let pieces: Vec<&Curve> = members.values().filter_map(|p| p.get(&step)).collect();
                    if !pieces.is_empty() {
                        lines.push((Curve::mean_of(&pieces), series_colour(i)));
                    }
                }
            }
        }
        let chart_area = if single {
            let (chart_area, legend_area) = panel_area.split_horizontally(WIDTH - MEMBER_LEGEND_WIDTH);
            draw_legend(&legend_area.margin(30, 0, 10, 10), &member_legend)?;
            chart_area
        } else {
            panel_area.clone()
        };
        let boundaries = task_boundaries(runs);
        let x_desc = "iteration of the sequence".to_string();
        let x_includes = sequence_span(runs);
        let panel = LinePanel { caption, x_desc, y_desc, lines, boundaries, y_includes, x_includes };
        draw_line_panel(&chart_area, &panel)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::StepCurves;

    #[test]
    fn known_families_come_first_and_members_are_placed_in_the_sequence() {
        let step = |names: &[&str], iterations: usize| StepCurves {
            iterations,
            plasticity: names.iter().map(|n| (n.to_string(), Curve::from_values(&[1.0, 2.0], 1))).collect(),
            ..Default::default()
        };
        let run = RunData {
            label: "r".into(),
            source: "x".into(),
            steps: vec![
                step(&["plasticity/zeta/actor", "plasticity/dormant/actor", "plasticity/dormant/critic"], 2),
                step(&["plasticity/dormant/actor"], 2),
            ],
            eval_matrix: None,
            over_seeds: None,
        };
        assert_eq!(families(std::slice::from_ref(&run)), ["dormant", "zeta"]);
        let dormant = members(&run, "dormant", &PlotOptions::default());
        assert_eq!(dormant.keys().collect::<Vec<_>>(), ["actor", "critic"]);
        assert_eq!(dormant["actor"][&1].points, vec![(3.0, 1.0), (4.0, 2.0)]);
        assert_eq!(dormant["critic"].keys().collect::<Vec<_>>(), [&0]);
    }

    #[test]
    fn a_family_of_many_layers_is_drawn_as_each_networks_mean() {
        let layer = |v: f64| BTreeMap::from([(0, Curve::from_values(&[v, v], 1))]);
        let names = ["actor.l0", "actor.l1", "actor.l2", "critic.l0", "critic.l1", "critic.l2", "cenet.l0", "cenet.l1"];
        let few: BTreeMap<String, _> = names.iter().map(|n| (n.to_string(), layer(1.0))).collect();
        assert_eq!(at_most_a_few(few.clone()), few);
        let mut many = few;
        many.insert("actor.l3".into(), layer(5.0));
        let grouped = at_most_a_few(many);
        assert_eq!(grouped.keys().collect::<Vec<_>>(), ["actor (4 layers)", "cenet (2 layers)", "critic (3 layers)"]);
        assert_eq!(grouped["actor (4 layers)"][&0].points, vec![(1.0, 2.0), (2.0, 2.0)]);
    }
}
