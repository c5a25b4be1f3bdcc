//! `[env.robot]`: what a URDF does not say about a robot, legged_gym style,
//! by joint- and link-name patterns.
//!
//! ```toml
//! [env.robot.default_pose]     # standing angle per joint, rad
//! "*_HAA" = 0.0
//! "LF_HFE" = 0.6               # an exact name beats any pattern
//! "?H_HFE" = -0.6
//! [env.robot.kp]               # PD stiffness per joint (else env.kp)
//! "*_KFE" = 60.0
//! ```
//!
//! A pattern is a joint name with `*` (any run of characters) and `?` (one
//! character). Where several match, the most specific wins: an exact name,
//! else the one with the most characters that are not wildcards; two
//! equally specific patterns with different values are an error.
//! Legs are found from the kinematic tree; `legs` overrides which chain is
//! which by its hip joint's name, and `foot_links` names the links whose
//! frame is the foot point.

use super::bounds::{self, Interval, NON_NEGATIVE, POSITIVE};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Robot settings by name pattern; empty tables keep the defaults of `[env]`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RobotConfig {
    /// Leg (`FL`, `FR`, `RL`, `RR`) -> pattern of its hip joint's name. Empty:
    /// legs are named from where their hips sit (x > 0 front, y > 0 left).
    pub legs: BTreeMap<String, String>,
    /// Joint-name pattern -> standing angle, rad. Empty: `env.default_hip_left`
    /// and the rest (the A1's conventions). When set, every leg joint must match.
    pub default_pose: BTreeMap<String, f32>,
    /// Joint-name pattern -> PD stiffness, N m / rad; unmatched joints use `env.kp`.
    pub kp: BTreeMap<String, f32>,
    /// Joint-name pattern -> PD damping, N m s / rad; unmatched joints use `env.kd`.
    pub kd: BTreeMap<String, f32>,
    /// Link-name patterns of the feet: the foot point is the matching link's
    /// frame origin. Empty: the calf's fixed child link, else its sphere.
    pub foot_links: Vec<String>,
}

impl RobotConfig {
    /// Whether every table is empty (the A1 defaults; not written to files).
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    /// Checks values and keys that make no sense whatever the robot.
    pub fn validate(&self) -> anyhow::Result<()> {
        for leg in self.legs.keys() {
            anyhow::ensure!(
                ["FL", "FR", "RL", "RR"].contains(&leg.as_str()),
                "env.robot.legs: unknown leg '{leg}' (the legs are FL, FR, RL, RR)"
            );
        }
        anyhow::ensure!(
            self.legs.is_empty() || self.legs.len() == 4,
            "env.robot.legs names {} legs; name all four (FL, FR, RL, RR) or none",
            self.legs.len()
        );
        for (table, map, interval) in [
            ("default_pose", &self.default_pose, Interval::Finite),
            ("kp", &self.kp, POSITIVE),
            ("kd", &self.kd, NON_NEGATIVE),
        ] {
            for (pattern, &v) in map {
                bounds::check(&format!("env.robot.{table}.\"{pattern}\""), v, interval)?;
            }
        }
        for (pattern, what) in
            self.legs.values().map(|p| (p, "legs")).chain(self.foot_links.iter().map(|p| (p, "foot_links")))
        {
            anyhow::ensure!(!pattern.is_empty(), "env.robot.{what}: an empty pattern matches no name");
        }
        Ok(())
    }
}

/// Whether `name` matches `pattern` (`*` any run, `?` one character).
pub fn glob_match(pattern: &str, name: &str) -> bool {
    let (p, n): (Vec<char>, Vec<char>) = (pattern.chars().collect(), name.chars().collect());
    // Classic two-pointer wildcard match with backtracking to the last `*`.
    let (mut i, mut j, mut star, mut mark) = (0, 0, None, 0);
    while j < n.len() {
        if i < p.len() && (p[i] == '?' || p[i] == n[j]) {
            i += 1;
            j += 1;
        } else if i < p.len() && p[i] == '*' {
            star = Some(i);
            mark = j;
            i += 1;
        } else if let Some(s) = star {
            i = s + 1;
            mark += 1;
            j = mark;
        } else {
            return false;
        }
    }
    p[i..].iter().all(|&c| c == '*')
}

/// How specific a pattern is: exact names first, then by literal characters.
fn specificity(pattern: &str) -> (bool, usize) {
    let wild = |c: char| c == '*' || c == '?';
    (!pattern.contains(wild), pattern.chars().filter(|&c| !wild(c)).count())
}

/// The value of the most specific pattern of `table` matching `name`, or
/// `None` when none matches. Errors name the table and both patterns of a tie.
pub fn pattern_value(table: &str, map: &BTreeMap<String, f32>, name: &str) -> anyhow::Result<Option<f32>> {
    let mut best: Option<(&str, f32)> = None;
    for (pattern, &v) in map.iter().filter(|(p, _)| glob_match(p, name)) {
        match best {
            Some((b, bv)) if specificity(b) == specificity(pattern) && bv != v => anyhow::bail!(
                "env.robot.{table}: joint '{name}' matches \"{b}\" ({bv}) and \"{pattern}\" ({v}) equally; \
                 make one more specific"
            ),
            Some((b, _)) if specificity(b) >= specificity(pattern) => {}
            _ => best = Some((pattern, v)),
        }
    }
    Ok(best.map(|(_, v)| v))
}

/// Errors on a pattern of `table` that matches none of `names` (a typo would otherwise be silent).
pub fn check_patterns_match<'a>(
    table: &str,
    patterns: impl IntoIterator<Item = &'a String>,
    names: &[&str],
) -> anyhow::Result<()> {
    for p in patterns {
        anyhow::ensure!(
            names.iter().any(|n| glob_match(p, n)),
            "env.robot.{table}: \"{p}\" matches none of the names ({})",
            names.join(", ")
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wildcards_match_runs_and_single_characters() {
        assert!(glob_match("*_hip_joint", "FL_hip_joint"));
        assert!(glob_match("R*_thigh_joint", "RL_thigh_joint"));
        assert!(!glob_match("R*_thigh_joint", "FL_thigh_joint"));
        assert!(glob_match("?H_HFE", "LH_HFE") && !glob_match("?H_HFE", "LF_HFE"));
        assert!(glob_match("*", "") && glob_match("a*b*c", "axxbyyc") && !glob_match("a*b*c", "axxbyy"));
        assert!(glob_match("FL_calf", "FL_calf") && !glob_match("FL_calf", "FL_calf_joint"));
    }

    #[test]
    fn the_most_specific_pattern_wins_and_equal_ones_that_disagree_are_an_error() {
        let map: BTreeMap<String, f32> =
            [("*_thigh_joint", 0.8), ("R*_thigh_joint", 1.0), ("RL_thigh_joint", 1.2), ("*", 0.0)]
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect();
        assert_eq!(pattern_value("default_pose", &map, "FL_thigh_joint").unwrap(), Some(0.8));
        assert_eq!(pattern_value("default_pose", &map, "RR_thigh_joint").unwrap(), Some(1.0));
        assert_eq!(pattern_value("default_pose", &map, "RL_thigh_joint").unwrap(), Some(1.2));
        assert_eq!(pattern_value("default_pose", &map, "FL_calf_joint").unwrap(), Some(0.0));
        let tie: BTreeMap<String, f32> = [("F*", 1.0), ("*t", 2.0)].into_iter().map(|(k, v)| (k.into(), v)).collect();
        let err = format!("{}", pattern_value("kp", &tie, "Ft").unwrap_err());
        assert!(err.contains("env.robot.kp") && err.contains("\"F*\"") && err.contains("\"*t\""), "{err}");
        assert_eq!(pattern_value("kp", &BTreeMap::new(), "x").unwrap(), None);
    }

    #[test]
    fn bad_tables_are_errors_naming_the_key() {
        let mut cfg = RobotConfig::default();
        cfg.kp.insert("*".into(), 0.0);
        assert!(format!("{}", cfg.validate().unwrap_err()).contains("env.robot.kp.\"*\""));
        let mut cfg = RobotConfig::default();
        cfg.legs.insert("XX".into(), "a".into());
        assert!(format!("{}", cfg.validate().unwrap_err()).contains("unknown leg 'XX'"));
        let mut cfg = RobotConfig::default();
        cfg.default_pose.insert("*".into(), f32::NAN);
        assert!(format!("{}", cfg.validate().unwrap_err()).contains("finite"));
        let err = check_patterns_match("kd", &["*_KEF".to_string()], &["LF_KFE"]).unwrap_err();
        assert!(format!("{err}").contains("\"*_KEF\" matches none"), "{err}");
    }

    #[test]
    fn a_config_with_robot_tables_round_trips_through_toml_and_the_a1_writes_none() {
        let text = "[env]\nurdf = \"x.urdf\"\n[env.robot.default_pose]\n\"*_HAA\" = 0.0\n\"?H_KFE\" = 0.8\n[env.robot.kp]\n\"LF_KFE\" = 60.0\n";
        let cfg = crate::config::Config::from_toml_str(text).unwrap();
        assert_eq!(cfg.env.robot.default_pose.len(), 2);
        assert_eq!(cfg.env.robot.kp["LF_KFE"], 60.0);
        let back = crate::config::Config::from_toml_str(&cfg.to_toml_string()).unwrap();
        assert_eq!(back, cfg);
        assert!(!crate::config::Config::default().to_toml_string().contains("robot"));
    }
}
