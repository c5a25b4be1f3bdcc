//! Every group of a collected sweep against one of them (`quadcl sweep collect
//! DIR --against GROUP`): per group and measure, the mean over seeds of the
//! difference group minus baseline, the two paired by seed (both cells of a seed
//! finished), with the same 90 % bootstrap interval as the table's, resampling
//! the seeds' differences. Pairing takes out what a seed does to every variant
//! alike (a hard task draw, a lucky start), so a difference can be clear where
//! the two groups' own intervals overlap. Written as `DIR/contrast.md` and
//! `.json`; a finding's verdict reads its interval (does it exclude zero?).
//!
//! The baseline may be a group of another sweep folder (`--against-in OTHER`) run
//! at the same seeds, when one figure's variants live in two sweeps (fig8's
//! re-init with entropy is fig5's split rule): then every group of DIR is set
//! against it, and the files are `contrast-vs-OTHER.md` and `.json`, with OTHER's
//! path relative to DIR recorded so the table can be computed again.

use super::bootstrap::{estimate, Estimate, CONFIDENCE, RESAMPLES};
use super::collect::{aligned_table, estimate_text, Collected, CollectedGroup};
use crate::util::write_atomic;
use anyhow::bail;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// `contrast.md`, beside `collected.md`.
pub const CONTRAST_MD: &str = "contrast.md";
/// `contrast.json`.
pub const CONTRAST_JSON: &str = "contrast.json";

/// One group against the baseline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContrastRow {
    pub group: String,
    /// The seeds both it and the baseline finished, in the plan's order.
    pub seeds: Vec<serde_json::Value>,
    /// Per measure, the paired difference (group minus baseline) over those seeds.
    pub differences: BTreeMap<String, Estimate>,
}

/// `contrast.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Contrast {
    pub sweep_file: String,
    /// The baseline group's name.
    pub baseline: String,
    /// The sweep folder holding the baseline, relative to this one, when it is another.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub baseline_sweep: Option<String>,
    pub confidence: f64,
    pub resamples: usize,
    pub measures: Vec<(String, String)>,
    /// Every other group, in the table's order.
    pub rows: Vec<ContrastRow>,
}

/// The group of `table` that `against` names: its exact name, or the one group whose
/// name holds every space-separated part of `against` (`name=ours` in `capacity=0.2 name=ours`).
pub fn find_group<'a>(table: &'a Collected, against: &str) -> anyhow::Result<&'a str> {
    if let Some(g) = table.groups.iter().find(|g| g.name == against) {
        return Ok(&g.name);
    }
    let wanted: Vec<&str> = against.split_whitespace().collect();
    let matching: Vec<&str> = table
        .groups
        .iter()
        .filter(|g| !wanted.is_empty() && wanted.iter().all(|w| g.name.split_whitespace().any(|p| p == *w)))
        .map(|g| g.name.as_str())
        .collect();
    let names: Vec<&str> = table.groups.iter().map(|g| g.name.as_str()).collect();
    match matching.as_slice() {
        [one] => Ok(one),
        [] => bail!("--against {against:?}: no group of {} is named so; its groups: {names:?}", table.sweep_file),
        many => bail!("--against {against:?}: several groups match ({many:?}); name one exactly"),
    }
}

/// Every group of `table` against the group `against` names (see [`find_group`]).
pub fn contrast(table: &Collected, against: &str) -> anyhow::Result<Contrast> {
    let baseline_name = find_group(table, against)?;
    let baseline = table.groups.iter().find(|g| g.name == baseline_name).expect("found above");
    Ok(contrast_with(table, baseline, None))
}

/// Every group of `table` against the group `against` names in `other`, the table of the
/// sweep folder `other_path` (relative to `table`'s, as recorded).
pub fn contrast_across(
    table: &Collected,
    other: &Collected,
    other_path: &str,
    against: &str,
) -> anyhow::Result<Contrast> {
    let baseline_name = find_group(other, against)?;
    let baseline = other.groups.iter().find(|g| g.name == baseline_name).expect("found above");
    Ok(contrast_with(table, baseline, Some(other_path.to_string())))
}

fn contrast_with(table: &Collected, baseline: &CollectedGroup, baseline_sweep: Option<String>) -> Contrast {
    let rows = table
        .groups
        .iter()
        .filter(|g| baseline_sweep.is_some() || g.name != baseline.name)
        .map(|g| {
            // Pairs of finished cells with the same seed (a sweep without a seed axis pairs none).
            let pairs: Vec<_> = g
                .cells
                .iter()
                .filter(|c| c.finished && c.seed.is_some())
                .filter_map(|c| {
                    let b = baseline.cells.iter().find(|b| b.finished && b.seed == c.seed)?;
                    Some((c, b))
                })
                .collect();
            let differences = table
                .measures
                .iter()
                .filter_map(|(k, _)| {
                    let d: Vec<f64> =
                        pairs.iter().filter_map(|(c, b)| Some(c.measures.get(k)? - b.measures.get(k)?)).collect();
                    Some((k.clone(), estimate(&d)?))
                })
                .collect();
            ContrastRow {
                group: g.name.clone(),
                seeds: pairs.iter().filter_map(|(c, _)| c.seed.clone()).collect(),
                differences,
            }
        })
        .collect();
    Contrast {
        sweep_file: table.sweep_file.clone(),
        baseline: baseline.name.clone(),
        baseline_sweep,
        confidence: CONFIDENCE,
        resamples: RESAMPLES,
        measures: table.measures.clone(),
        rows,
    }
}

/// The files a contrast is written to in its folder: `contrast.md`/`.json`, or
/// `contrast-vs-OTHER.md`/`.json` against another sweep folder OTHER.
pub fn contrast_files(c: &Contrast) -> (String, String) {
    match &c.baseline_sweep {
        None => (CONTRAST_MD.to_string(), CONTRAST_JSON.to_string()),
        Some(other) => {
            let name = Path::new(other).file_name().map_or("other".into(), |n| n.to_string_lossy().into_owned());
            (format!("contrast-vs-{name}.md"), format!("contrast-vs-{name}.json"))
        }
    }
}

/// Writes `c` into the sweep folder `dir` (see [`contrast_files`]); returns the two paths.
pub fn write_contrast(dir: &Path, c: &Contrast) -> anyhow::Result<(PathBuf, PathBuf)> {
    let (md, json) = contrast_files(c);
    let (md, json) = (dir.join(md), dir.join(json));
    write_atomic(&json, serde_json::to_string_pretty(c)?.as_bytes())?;
    write_atomic(&md, contrast_markdown(c).as_bytes())?;
    Ok((md, json))
}

/// The contrast as aligned Markdown, with a line saying what it shows.
pub fn contrast_markdown(c: &Contrast) -> String {
    let mut header = vec!["group".to_string(), "paired seeds".to_string()];
    header.extend(c.measures.iter().map(|(_, h)| h.clone()));
    let rows: Vec<Vec<String>> = c
        .rows
        .iter()
        .map(|r| {
            let mut row = vec![r.group.clone(), r.seeds.len().to_string()];
            row.extend(c.measures.iter().map(|(k, _)| r.differences.get(k).map_or("-".into(), estimate_text)));
            row
        })
        .collect();
    format!(
        "Sweep {}: each group minus {}, paired by seed: mean difference [{:.0} % bootstrap interval, {} resamples of the seeds]\n\n{}",
        c.sweep_file,
        match &c.baseline_sweep {
            None => c.baseline.clone(),
            Some(other) => format!("{} of the sweep {other}", c.baseline),
        },
        c.confidence * 100.0,
        c.resamples,
        aligned_table(&header, &rows)
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::collect::{CollectedCell, CollectedGroup};

    fn group(name: &str, values: &[(i64, Option<f64>)]) -> CollectedGroup {
        let cells: Vec<CollectedCell> = values
            .iter()
            .enumerate()
            .map(|(i, (seed, v))| CollectedCell {
                index: i,
                seed: Some(serde_json::json!(seed)),
                run: format!("runs/{i}"),
                finished: v.is_some(),
                measures: v.iter().map(|v| ("forgetting".to_string(), *v)).collect(),
            })
            .collect();
        CollectedGroup {
            name: name.into(),
            values: BTreeMap::new(),
            planned: cells.len(),
            finished: cells.iter().filter(|c| c.finished).count(),
            cells,
            measures: BTreeMap::new(),
        }
    }

    fn table(groups: Vec<CollectedGroup>) -> Collected {
        Collected {
            sweep_file: "s.toml".into(),
            confidence: CONFIDENCE,
            resamples: RESAMPLES,
            measures: vec![("forgetting".into(), "forgetting".into())],
            groups,
            left_out: Vec::new(),
        }
    }

    #[test]
    fn differences_pair_cells_by_seed_and_skip_seeds_either_side_has_not_finished() {
        let t = table(vec![
            group("name=ours", &[(1, Some(0.0)), (2, Some(0.0)), (3, Some(0.0))]),
            // Seed 2 unfinished; seeds listed in another order than the baseline's.
            group("name=ewc", &[(3, Some(0.30)), (2, None), (1, Some(0.10))]),
        ]);
        let c = contrast(&t, "name=ours").unwrap();
        assert_eq!(c.baseline, "name=ours");
        assert_eq!(c.rows.len(), 1);
        assert_eq!(c.rows[0].seeds, vec![serde_json::json!(3), serde_json::json!(1)]);
        let d = c.rows[0].differences["forgetting"];
        assert_eq!(d.n, 2);
        assert!((d.mean - 0.2).abs() < 1e-12, "{d:?}");
        assert!(d.low >= 0.1 - 1e-12 && d.high <= 0.3 + 1e-12, "{d:?}");
    }

    #[test]
    fn a_paired_difference_is_clear_where_the_groups_own_spreads_overlap() {
        // Seeds move both groups alike; the group is 0.05 above at every seed.
        let t = table(vec![
            group("a", &[(1, Some(0.2)), (2, Some(0.5)), (3, Some(0.8))]),
            group("b", &[(1, Some(0.25)), (2, Some(0.55)), (3, Some(0.85))]),
        ]);
        let d = contrast(&t, "a").unwrap().rows[0].differences["forgetting"];
        assert!((d.low - 0.05).abs() < 1e-9 && (d.high - 0.05).abs() < 1e-9, "{d:?}");
    }

    #[test]
    fn against_another_sweeps_group_every_group_is_set_against_it_and_written_beside() {
        let here = table(vec![group("reinit=both", &[(1, Some(0.2)), (2, Some(0.3)), (3, Some(0.1))])]);
        let other = table(vec![
            group("lambda=0.25", &[(1, Some(0.1)), (2, Some(0.1)), (3, Some(0.1))]),
            group("lambda=free", &[(1, Some(0.9)), (2, Some(0.9)), (3, Some(0.9))]),
        ]);
        let c = contrast_across(&here, &other, "../fig5-selection", "lambda=0.25").unwrap();
        assert_eq!(c.rows.len(), 1);
        assert!((c.rows[0].differences["forgetting"].mean - 0.1).abs() < 1e-12);
        assert_eq!(
            contrast_files(&c),
            ("contrast-vs-fig5-selection.md".into(), "contrast-vs-fig5-selection.json".into())
        );
        assert!(contrast_markdown(&c).contains("minus lambda=0.25 of the sweep ../fig5-selection"));
    }

    #[test]
    fn a_baseline_no_group_or_several_groups_match_is_an_error_listing_the_groups() {
        let t = table(vec![group("lambda=0.25 name=ours", &[]), group("lambda=free name=ours", &[])]);
        let none = format!("{:#}", contrast(&t, "name=ewc").unwrap_err());
        assert!(none.contains("lambda=free name=ours") && none.contains("s.toml"), "{none}");
        let many = format!("{:#}", contrast(&t, "name=ours").unwrap_err());
        assert!(many.contains("several"), "{many}");
        assert_eq!(find_group(&t, "lambda=free").unwrap(), "lambda=free name=ours");
    }
}
