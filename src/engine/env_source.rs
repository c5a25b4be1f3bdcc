//! Where a simulated robot's `[env]` settings come from when a program names
//! them instead of training from a run file: a shipped robot by name (`a1`,
//! `aliengo`, `anymal_c`), a URDF file, or the `[env]` table of a run file or
//! a training config. `quadcl robot --config` and the Python package
//! (`quadcl.make_vec(robot=..., config=...)`) read them here.

use crate::config::{Config, EnvConfig};
use anyhow::Context;
use std::path::Path;

/// The robots shipped under `scenes/`: name, and the run file whose `[env]` sets
/// its gains, heights and pose (`None`: the `[env]` defaults, which are the A1's).
pub const SHIPPED_ROBOTS: [(&str, Option<&str>); 3] =
    [("a1", None), ("aliengo", Some("scenes/aliengo.toml")), ("anymal_c", Some("scenes/anymal_c.toml"))];

/// Whether `path` (relative, `scenes/a1.urdf`) names a robot description every build ships
/// (compiled in: found wherever a run starts).
pub fn is_shipped_description(path: &Path) -> bool {
    crate::sim::shipped::is_shipped(path)
}

/// The `[env]` table of a run file (it has `[[task]]`) or of a training config.
/// Errors name the file and the problem.
pub fn env_of_file(path: &Path) -> anyhow::Result<EnvConfig> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading config {}", path.display()))?;
    env_of_text(&text, path)
}

/// [`env_of_file`] of `text`, read from `path` (named in errors).
fn env_of_text(text: &str, path: &Path) -> anyhow::Result<EnvConfig> {
    let value: toml::Table = toml::from_str(text).with_context(|| format!("in config {}", path.display()))?;
    let env = if value.contains_key("task") {
        super::RunConfig::from_toml_str(text).map(|run| run.config.env)
    } else {
        Config::from_toml_str(text).map(|cfg| cfg.env)
    };
    env.with_context(|| format!("in config {}", path.display()))
}

/// The `[env]` settings of `robot`: a shipped robot's name, a `.urdf` file (the
/// `[env]` defaults with that description), or a run file or training config.
/// A shipped robot's files are read beside this crate's sources, or from the
/// copies compiled in (`sim::shipped`) where those are absent.
pub fn env_of_robot(robot: &str) -> anyhow::Result<EnvConfig> {
    if let Some((_, file)) = SHIPPED_ROBOTS.iter().find(|(name, _)| *name == robot) {
        return match file {
            None => Ok(EnvConfig::default()),
            Some(file) => {
                let path = crate::sim::shipped::crate_path(file);
                let text = crate::sim::shipped::read_crate_file(file)
                    .with_context(|| format!("reading config {}", path.display()))?;
                env_of_text(&text, &path)
            }
        };
    }
    let path = Path::new(robot);
    let is_urdf = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("urdf"));
    if !path.exists() {
        let names: Vec<&str> = SHIPPED_ROBOTS.iter().map(|(n, _)| *n).collect();
        anyhow::bail!("unknown robot {robot:?}: not a shipped robot ({}) nor an existing file", names.join(", "));
    }
    if is_urdf {
        let env = EnvConfig { urdf: path.display().to_string(), ..EnvConfig::default() };
        env.validate().with_context(|| format!("the [env] defaults with robot {robot}"))?;
        return Ok(env);
    }
    env_of_file(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_robot_has_settings_and_an_unknown_one_is_an_error_naming_them() {
        for (name, _) in SHIPPED_ROBOTS {
            let env = env_of_robot(name).unwrap();
            assert!(env.urdf.contains(name), "{name}: {}", env.urdf);
        }
        let err = format!("{:#}", env_of_robot("spot").unwrap_err());
        assert!(err.contains("spot") && err.contains("aliengo"), "{err}");
        let urdf = env_of_robot(&crate::sim::shipped::crate_path("scenes/aliengo.urdf").display().to_string()).unwrap();
        assert!(urdf.urdf.ends_with("aliengo.urdf") && urdf.kp == EnvConfig::default().kp);
    }
}
