//! A sweep file (TOML, under `scenes/`): a base run file and the axes to cross.
//!
//! ```toml
//! base = "smoke.toml"          # relative to the sweep file, or absolute
//! [axes]
//! seed = [1, 2]
//! "net.mask.capacity" = [0.2, 0.3]
//! ```
//!
//! An axis is any key of a run file by its dotted path (`seed`, `method.name`,
//! `net.mask.capacity`, `task.0.iterations` with an index into `[[task]]`) and the
//! values it takes. The axis `arm` takes named sets of keys instead, for variants that
//! are not a cross of values (a ladder of settings):
//!
//! ```toml
//! arm = [
//!   { name = "5%" },
//!   { name = "20%-settled", "net.mask.capacity" = 0.4, "net.mask.vacant_share" = 0.5, "method.entropy" = false },
//! ]
//! ```
//!
//! Each arm sets its keys (every arm's name unique; a cell's name says `arm=20%-settled`);
//! it crosses with the other axes like any axis. Axes cross in the order of their keys with `seed` last, so the
//! seeds of one setting are neighbouring cells. Every problem is an error naming the
//! sweep file and the key; whether a value is one the run file accepts is checked
//! when the sweep is planned (`plan`), before anything runs.

use anyhow::Context;
use std::path::{Path, PathBuf};

/// The axis whose cells form one group of seeds (`sweep collect` averages over it).
pub const SEED_AXIS: &str = "seed";

/// The axis whose values are named sets of keys (see the module doc).
pub const ARM_AXIS: &str = "arm";

/// One axis: a run file key and the values it takes.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// The dotted path of the key in the run file (`net.mask.capacity`).
    pub key: String,
    /// The values, in the file's order (none twice).
    pub values: Vec<toml::Value>,
}

/// A parsed sweep file.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepFile {
    /// The sweep file itself.
    pub path: PathBuf,
    /// The base run file (resolved against the sweep file's folder).
    pub base: PathBuf,
    /// The axes, in the order they cross (keys sorted, `seed` last).
    pub axes: Vec<Axis>,
    /// The sweep file's text, as read.
    pub text: String,
}

impl SweepFile {
    /// Reads and parses the sweep file `path`.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading sweep file {}", path.display()))?;
        Self::parse(path, &text)
    }

    /// Parses `text`, read from (or standing for) the sweep file `path`.
    pub fn parse(path: &Path, text: &str) -> anyhow::Result<Self> {
        let shown = path.display();
        let mut table: toml::Table = toml::from_str(text).map_err(|e| anyhow::anyhow!("sweep file {shown}: {e}"))?;
        let base = match table.remove("base") {
            Some(toml::Value::String(s)) if !s.trim().is_empty() => PathBuf::from(s),
            Some(other) => anyhow::bail!("sweep file {shown}: base = {other}: expected the path of a run file"),
            None => anyhow::bail!("sweep file {shown}: no `base` (the run file the axes change)"),
        };
        let base = if base.is_relative() { path.parent().unwrap_or(Path::new(".")).join(base) } else { base };
        let axes_table = match table.remove("axes") {
            Some(toml::Value::Table(t)) => t,
            Some(other) => anyhow::bail!("sweep file {shown}: axes = {other}: expected an [axes] table"),
            None => anyhow::bail!("sweep file {shown}: no [axes] table (the run file keys to cross)"),
        };
        if let Some(key) = table.keys().next() {
            anyhow::bail!("sweep file {shown}: unknown key `{key}` (a sweep file has `base` and [axes])");
        }
        anyhow::ensure!(!axes_table.is_empty(), "sweep file {shown}: [axes] is empty: name at least one key to cross");
        let mut axes = Vec::new();
        for (key, values) in axes_table {
            let where_ = || format!("sweep file {shown}: [axes] \"{key}\"");
            check_key(&key).with_context(where_)?;
            let toml::Value::Array(values) = values else {
                anyhow::bail!("{}: {values} is not a list of values (write [{values}] for one)", where_())
            };
            anyhow::ensure!(!values.is_empty(), "{}: the axis is empty (give it at least one value)", where_());
            for (i, v) in values.iter().enumerate() {
                anyhow::ensure!(!values[..i].contains(v), "{}: the value {v} is listed twice", where_());
                if key == ARM_AXIS {
                    check_arm(v, &values[..i]).with_context(where_)?;
                } else {
                    anyhow::ensure!(
                        !matches!(v, toml::Value::Table(_)),
                        "{}: {v} is a table, expected a value (named sets of keys go in the `arm` axis)",
                        where_()
                    );
                }
            }
            axes.push(Axis { key, values });
        }
        // Sorted by key (a TOML table's order), then the seeds last: they vary fastest.
        axes.sort_by_key(|a| a.key == SEED_AXIS);
        Ok(Self { path: path.to_path_buf(), base, axes, text: text.to_string() })
    }

    /// The number of cells (the product of the axes' lengths).
    pub fn cell_count(&self) -> usize {
        self.axes.iter().map(|a| a.values.len()).product()
    }
}

/// An arm: a table with a `name` no earlier arm has and dotted run file keys set to values.
fn check_arm(arm: &toml::Value, earlier: &[toml::Value]) -> anyhow::Result<()> {
    let toml::Value::Table(table) = arm else {
        anyhow::bail!("{arm} is not an arm: expected {{ name = \"...\", \"key\" = value, ... }}")
    };
    let name = match table.get("name") {
        Some(toml::Value::String(n)) if !n.trim().is_empty() => n,
        _ => anyhow::bail!("{arm}: an arm needs a `name` (a non-empty string)"),
    };
    anyhow::ensure!(!earlier.iter().any(|e| arm_name(e) == Some(name.as_str())), "two arms are named {name:?}");
    for (key, value) in table.iter().filter(|(k, _)| *k != "name") {
        check_key(key).with_context(|| format!("arm {name:?}: key {key:?}"))?;
        anyhow::ensure!(key != SEED_AXIS && key != ARM_AXIS, "arm {name:?}: `{key}` cannot be set by an arm");
        anyhow::ensure!(!matches!(value, toml::Value::Table(_)), "arm {name:?}: {key} = {value} is a table");
    }
    Ok(())
}

/// The name of an arm (`arm` axis value).
pub fn arm_name(arm: &toml::Value) -> Option<&str> {
    arm.get("name").and_then(|n| n.as_str())
}

/// Sets the keys an `axis` value gives on a run file: the value at the axis's key, or an
/// arm's keys.
pub fn apply_axis_value(root: &mut toml::Value, axis: &str, value: &toml::Value) -> anyhow::Result<()> {
    if axis != ARM_AXIS {
        return set_dotted(root, axis, value.clone());
    }
    let table = value.as_table().context("an arm is a table")?;
    for (key, v) in table.iter().filter(|(k, _)| *k != "name") {
        set_dotted(root, key, v.clone()).with_context(|| format!("arm {:?}: {key}", arm_name(value)))?;
    }
    Ok(())
}

/// A dotted path of non-empty segments of letters, digits, `_` and `-`.
fn check_key(key: &str) -> anyhow::Result<()> {
    for segment in key.split('.') {
        anyhow::ensure!(
            !segment.is_empty() && segment.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-'),
            "not a dotted path of run file keys (like net.mask.capacity)"
        );
    }
    Ok(())
}

/// `value` as it reads in a cell's name: strings without quotes, numbers as TOML writes them,
/// an arm by its name.
pub fn value_label(value: &toml::Value) -> String {
    match value {
        toml::Value::String(s) => s.clone(),
        toml::Value::Table(_) if arm_name(value).is_some() => arm_name(value).unwrap_or_default().to_string(),
        other => other.to_string(),
    }
}

/// Sets the key at the dotted path `key` of a run file (`root`, its top table as a value) to
/// `value`, creating tables on the way; a number segment indexes an array (`task.0.iterations`).
pub fn set_dotted(root: &mut toml::Value, key: &str, value: toml::Value) -> anyhow::Result<()> {
    let segments: Vec<&str> = key.split('.').collect();
    let (last, path) = segments.split_last().context("an empty key")?;
    let mut here = root;
    for (depth, segment) in path.iter().enumerate() {
        let walked = segments[..=depth].join(".");
        here = match here {
            toml::Value::Table(t) => {
                t.entry(segment.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            toml::Value::Array(items) => {
                let i: usize =
                    segment.parse().with_context(|| format!("`{walked}`: expected an index into the list"))?;
                let n = items.len();
                items.get_mut(i).with_context(|| format!("`{walked}`: the list has {n} entries"))?
            }
            other => anyhow::bail!("`{}` is {other}, not a table", segments[..depth].join(".")),
        };
    }
    match here {
        toml::Value::Table(t) => {
            t.insert(last.to_string(), value);
        }
        toml::Value::Array(items) => {
            let i: usize = last.parse().with_context(|| format!("`{key}`: expected an index into the list"))?;
            let n = items.len();
            *items.get_mut(i).with_context(|| format!("`{key}`: the list has {n} entries"))? = value;
        }
        other => anyhow::bail!("`{}` is {other}, not a table", path.join(".")),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> anyhow::Result<SweepFile> {
        SweepFile::parse(Path::new("scenes/sweep-test.toml"), text)
    }

    #[test]
    fn axes_cross_in_key_order_with_the_seeds_last_and_the_base_beside_the_file() {
        let f = parse("base = \"smoke.toml\"\n[axes]\nseed = [1, 2]\n\"net.mask.capacity\" = [0.2, 0.3]\n\"method.name\" = [\"ours\", \"wsn\"]\n").unwrap();
        let keys: Vec<&str> = f.axes.iter().map(|a| a.key.as_str()).collect();
        assert_eq!(keys, ["method.name", "net.mask.capacity", "seed"]);
        assert_eq!(f.base, Path::new("scenes/smoke.toml"));
        assert_eq!(f.cell_count(), 8);
    }

    #[test]
    fn a_bad_sweep_file_is_an_error_naming_the_file_and_the_key() {
        for (text, needle) in [
            ("[axes]\nseed = [1]\n", "no `base`"),
            ("base = \"a.toml\"\n", "no [axes]"),
            ("base = \"a.toml\"\n[axes]\n", "[axes] is empty"),
            ("base = \"a.toml\"\n[axes]\nseed = []\n", "\"seed\": the axis is empty"),
            ("base = \"a.toml\"\n[axes]\nseed = 3\n", "\"seed\": 3 is not a list"),
            ("base = \"a.toml\"\n[axes]\nseed = [1, 1]\n", "listed twice"),
            ("base = \"a.toml\"\n[axes]\n\"net..x\" = [1]\n", "\"net..x\": not a dotted path"),
            ("base = \"a.toml\"\nsed = 1\n[axes]\nseed = [1]\n", "unknown key `sed`"),
        ] {
            let err = format!("{:#}", parse(text).unwrap_err());
            assert!(err.contains("scenes/sweep-test.toml") && err.contains(needle), "{needle}: {err}");
        }
    }

    #[test]
    fn an_arm_sets_its_own_keys_and_is_named_by_its_name() {
        let f = parse(
            "base = \"smoke.toml\"\n[axes]\nseed = [1]\narm = [{ name = \"5%\" }, \
             { name = \"20%\", \"net.mask.capacity\" = 0.4, \"net.mask.vacant_share\" = 0.5 }]\n",
        )
        .unwrap();
        assert_eq!(f.cell_count(), 2);
        let arms = &f.axes[0];
        assert_eq!(arms.key, "arm");
        assert_eq!(arms.values.iter().map(value_label).collect::<Vec<_>>(), ["5%", "20%"]);
        let mut root: toml::Value = toml::from_str("seed = 1\n").unwrap();
        apply_axis_value(&mut root, "arm", &arms.values[1]).unwrap();
        assert_eq!(root["net"]["mask"]["capacity"].as_float(), Some(0.4));
        assert_eq!(root["net"]["mask"]["vacant_share"].as_float(), Some(0.5));
        assert!(root.get("name").is_none(), "the arm's name is a label, not a key");
        for (arms, needle) in [
            ("[{ name = \"a\" }, { name = \"a\", seed = 2 }]", "two arms are named"),
            ("[{ \"net.mask.capacity\" = 0.4 }]", "needs a `name`"),
            ("[{ name = \"a\", seed = 2 }]", "cannot be set by an arm"),
            ("[3]", "not an arm"),
        ] {
            let err = format!("{:#}", parse(&format!("base = \"s.toml\"\n[axes]\narm = {arms}\n")).unwrap_err());
            assert!(err.contains(needle), "{needle}: {err}");
        }
    }

    #[test]
    fn a_dotted_key_sets_nested_tables_and_list_entries() {
        let mut root: toml::Value = toml::from_str("seed = 1\n[[task]]\nname = \"a\"\n").unwrap();
        set_dotted(&mut root, "net.mask.capacity", toml::Value::Float(0.3)).unwrap();
        set_dotted(&mut root, "task.0.iterations", toml::Value::Integer(7)).unwrap();
        set_dotted(&mut root, "seed", toml::Value::Integer(2)).unwrap();
        assert_eq!(root["net"]["mask"]["capacity"].as_float(), Some(0.3));
        assert_eq!(root["task"][0]["iterations"].as_integer(), Some(7));
        assert_eq!(root["seed"].as_integer(), Some(2));
        let err = format!("{:#}", set_dotted(&mut root, "seed.x", toml::Value::Integer(1)).unwrap_err());
        assert!(err.contains("`seed` is 2, not a table"), "{err}");
        let err = format!("{:#}", set_dotted(&mut root, "task.3.name", toml::Value::Integer(1)).unwrap_err());
        assert!(err.contains("1 entries"), "{err}");
    }
}
