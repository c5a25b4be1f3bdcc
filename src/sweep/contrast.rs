//! Every group of a collected sweep against one of them (`quadcl sweep collect
//! DIR --against GROUP`): per group and measure, the mean over seeds of the
//! difference group minus baseline, the two paired by seed (both cells of a seed
//! finished), with the same 90 % bootstrap interval as the table's, resampling
//! the seeds' differences. Pairing takes out what a seed does to every variant
//! alike (a hard task draw, a lucky start), so a difference can be clear where
//! the two groups' own intervals overlap. Written as `DIR/contrast.md` and
//! `.json`; a finding's verdict reads its interval (does it exclude zero?).

use super::bootstrap::{estimate, Estimate, CONFIDENCE, RESAMPLES};
use super::collect::{aligned_table, estimate_text, Collected};
use crate::util::write_atomic;
use anyhow::bail;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

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
    let baseline_name = find_group(table, against)?.to_string();
    let baseline = table.groups.iter().find(|g| g.name == baseline_name).expect("found above");
    let rows = table
        .groups
        .iter()
        .filter(|g| g.name != baseline_name)
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
    Ok(Contrast {
        sweep_file: table.sweep_file.clone(),
        baseline: baseline_name,
        confidence: CONFIDENCE,
        resamples: RESAMPLES,
        measures: table.measures.clone(),
        rows,
    })
}

/// Contrasts `table` against `against` and writes `contrast.json` and `.md` into `dir`.
pub fn contrast_and_write(dir: &Path, table: &Collected, against: &str) -> anyhow::Result<Contrast> {
    let c = contrast(table, against)?;
    write_atomic(&dir.join(CONTRAST_JSON), serde_json::to_string_pretty(&c)?.as_bytes())?;
    write_atomic(&dir.join(CONTRAST_MD), contrast_markdown(&c).as_bytes())?;
    Ok(c)
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
        c.baseline,
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
    fn a_baseline_no_group_or_several_groups_match_is_an_error_listing_the_groups() {
        let t = table(vec![group("lambda=0.25 name=ours", &[]), group("lambda=free name=ours", &[])]);
        let none = format!("{:#}", contrast(&t, "name=ewc").unwrap_err());
        assert!(none.contains("lambda=free name=ours") && none.contains("s.toml"), "{none}");
        let many = format!("{:#}", contrast(&t, "name=ours").unwrap_err());
        assert!(many.contains("several"), "{many}");
        assert_eq!(find_group(&t, "lambda=free").unwrap(), "lambda=free name=ours");
    }
}
