//! A run file (`quadcl run --config FILE`): one TOML file holding the
//! experiment [`Config`] (`seed`, `[env]`, `[net]`, `[ppo]`), the method and
//! its switches (`[method]`), the evaluation (`[eval]`), the learner and the
//! forward-transfer reference (`[run]`), and the sequence (`iterations`,
//! `[[task]]`, see `cl::sequence`).
//!
//! ```toml
//! seed = 1
//! iterations = 300            # default budget per task
//! [method]
//! name = "ours"               # or finetune, ewc, si (`quadcl run --method` overrides it)
//! reinit_weights = true       # switches of cl::ours; unset ones follow [net.mask]
//! lambda = "0.25"
//! [method.ewc]                # each method's settings in its own table
//! lambda = 1e4
//! [eval]
//! episodes = 16
//! [[task]]
//! name = "crash:FL"
//! ```
//!
//! Every key is optional except the tasks; an unknown key is an error naming
//! the file and the key.

use crate::cl::{ContinualMethod, KnownBefore, MethodSettings, Sequence, SwitchOverrides, Switches};
use crate::config::net::{MaskConfig, NetworkKind};
use crate::config::Config;
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Which learner a run trains.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LearnerKind {
    /// PPO + CENet on the simulated quadruped.
    #[default]
    Ppo,
    /// The tiny masked regression learner (tests, trying the engine).
    Toy,
}

/// `[eval]`: how every learned task is evaluated after every task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EvalConfig {
    /// Episodes per evaluation (one per parallel environment).
    pub episodes: usize,
}

impl Default for EvalConfig {
    fn default() -> Self {
        Self { episodes: 16 }
    }
}

/// `[run]`: the learner and where its knowledge starts.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RunSection {
    /// `ppo` (the quadruped) or `toy` (the masked regression learner).
    pub learner: LearnerKind,
    /// A `metrics.json` of single-task runs from scratch: its curves are the
    /// forward-transfer references (METHOD.md 4); without it forward transfer is null.
    pub reference: Option<PathBuf>,
    /// A policy directory (e.g. `policies/base-a1-flat`) whose networks the
    /// sequence starts from; its tasks are kept (the base task stays recallable).
    pub base_policy: Option<PathBuf>,
    /// Keep only the newest checkpoint (all a `--resume` needs; it recalls every
    /// task) instead of one per step, e.g. for a run committed under `policies/`.
    pub keep_last_checkpoint_only: bool,
    /// What the base policy's VACANT weights are when the run starts: `as_saved` (the default:
    /// drawn when the base's last task ended, at the base's own fresh-weight range), or
    /// `redrawn` at this run's (`[net.mask] reinit_range` times `reinit_scale`, 0: zero), so a
    /// first task's fresh weights follow the run's reading (docs/method.md). Masked methods only.
    pub base_vacant: BaseVacant,
    /// After each task, a short video of the task just learned (`videos/TASK.mp4`: 6 s at
    /// 320 x 240, the env's random commands; rendered on the CPU and encoded by an `ffmpeg` on
    /// PATH). A video that fails (no ffmpeg) is a warning in the log, never the run's failure.
    pub videos: bool,
}

/// `[run] base_vacant`: the base policy's vacant weights at the run's start.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BaseVacant {
    /// As the base policy saved them.
    #[default]
    AsSaved,
    /// Redrawn at the run's fresh-weight range and scale.
    Redrawn,
}

/// Everything a run needs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunConfig {
    /// Seed, environment, networks, PPO.
    pub config: Config,
    /// The method's name (`ours`, `finetune`, `ewc`, `si`).
    pub method: String,
    /// Every method's settings (`[method.ewc]`, `[method.si]`).
    pub method_settings: MethodSettings,
    /// The run's switches ([net.mask] with `[method]`'s changes).
    pub switches: Switches,
    pub eval: EvalConfig,
    pub run: RunSection,
    pub sequence: Sequence,
}

impl RunConfig {
    /// Reads and checks a run file; errors name the file and the key.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading run config {}", path.display()))?;
        Self::load_text(path, &text)
    }

    /// [`Self::load`] of `text`, read from (or standing for) the file `path`.
    pub fn load_text(path: &Path, text: &str) -> anyhow::Result<Self> {
        let mut cfg = Self::from_toml_str(text).with_context(|| format!("in run config {}", path.display()))?;
        // Relative paths inside the file are relative to the file's folder when they exist there.
        let base = path.parent().unwrap_or(Path::new("."));
        for p in [&mut cfg.run.reference, &mut cfg.run.base_policy].into_iter().flatten() {
            if p.is_relative() && !p.exists() && base.join(&*p).exists() {
                *p = base.join(&*p);
            }
        }
        Ok(cfg)
    }

    /// [`Self::load_text`] as a run that began before issue 60 read the file: where it leaves
    /// them open, E a count of 100 and the soft-score means at the optimiser's rate
    /// ([`crate::config::net::MaskConfig::as_before_issue_60`]), so that such a run resumed or
    /// continued trains its later tasks as it trained its first (docs/method.md, "The paper's
    /// experiments and ours").
    pub fn load_text_as_ran_before_issue_60(path: &Path, text: &str) -> anyhow::Result<Self> {
        let mut cfg = Self::load_text(path, text)?;
        let table: toml::Table = toml::from_str(text).with_context(|| format!("in run config {}", path.display()))?;
        let rate_set =
            table.get("net").and_then(|n| n.get("mask")).and_then(|m| m.get("score_learning_rate")).is_some();
        cfg.config.net.mask = cfg.config.net.mask.as_before_issue_60(rate_set);
        Ok(cfg)
    }

    /// Parses run-file text.
    pub fn from_toml_str(text: &str) -> anyhow::Result<Self> {
        let mut table: toml::Table = toml::from_str(text).map_err(|e| anyhow::anyhow!("{e}"))?;
        let mut take = |key: &str| table.remove(key);
        let method_value = take("method");
        let eval_value = take("eval");
        let run_value = take("run");
        let mut sequence_table = toml::Table::new();
        for key in ["iterations", "task"] {
            if let Some(v) = take(key) {
                sequence_table.insert(key.into(), v);
            }
        }
        let config: Config = toml::Value::Table(table).try_into().map_err(|e| anyhow::anyhow!("{e}"))?;
        config.validate()?;
        if !sequence_table.contains_key("task") {
            anyhow::bail!("the run has no [[task]] entries");
        }
        let sequence: Sequence =
            toml::Value::Table(sequence_table).try_into().map_err(|e| anyhow::anyhow!("in [[task]]: {e}"))?;
        sequence.validate()?;
        let (method, overrides, method_settings) = match method_value {
            None => ("ours".to_string(), SwitchOverrides::default(), MethodSettings::default()),
            Some(toml::Value::Table(mut t)) => {
                let name = match t.remove("name") {
                    None => "ours".to_string(),
                    Some(toml::Value::String(s)) => s,
                    Some(other) => anyhow::bail!("[method] name = {other}: expected a string"),
                };
                let mut settings = toml::Table::new();
                for key in ["ewc", "si", "rwalk", "er", "agem", "packnet", "piggyback"] {
                    if let Some(v) = t.remove(key) {
                        settings.insert(key.into(), v);
                    }
                }
                let settings: MethodSettings = toml::Value::Table(settings)
                    .try_into()
                    .map_err(|e| anyhow::anyhow!("in a [method.NAME] table: {e}"))?;
                settings.validate()?;
                let o: SwitchOverrides =
                    toml::Value::Table(t).try_into().map_err(|e| anyhow::anyhow!("in [method]: {e}"))?;
                (name, o, settings)
            }
            Some(other) => anyhow::bail!("method = {other}: expected a [method] table"),
        };
        let method_impl = crate::cl::method_by_name(&method, &method_settings)?;
        let kind = method_impl.network_kind();
        if config.net.kind != kind {
            anyhow::ensure!(
                config.net.kind.is_masked(),
                "[net] kind = \"dense\", but the method {method:?} trains masked networks (in a run file the \
                 method decides: finetune, ewc and si train dense ones)"
            );
        }
        let switches = Switches::from_mask_config(&config.net.mask).with(&overrides);
        let base_mask = switches.apply(&config.net.mask).context("in [method]")?;
        config.net.check_selects(&base_mask).context("in [method]")?;
        if kind == NetworkKind::Masked {
            check_task_masks(&config, &*method_impl, &base_mask, &switches, &sequence)?;
        }
        if method == "packnet" {
            check_packnet_budgets(&method_settings, &sequence)?;
        }
        let eval: EvalConfig = match eval_value {
            Some(v) => v.try_into().map_err(|e| anyhow::anyhow!("in [eval]: {e}"))?,
            None => EvalConfig::default(),
        };
        crate::config::ppo::check_env_count("[eval] episodes", eval.episodes)?;
        let run: RunSection = match run_value {
            Some(v) => v.try_into().map_err(|e| anyhow::anyhow!("in [run]: {e}"))?,
            None => RunSection::default(),
        };
        // Without a base policy nothing is learned before the sequence: every related task
        // must come earlier in it. With one, its tasks are checked once it is loaded.
        anyhow::ensure!(
            !(run.videos && run.learner == LearnerKind::Toy),
            "[run] videos = true needs the PPO learner: a [run] learner = \"toy\" run has no robot to film"
        );
        if run.base_policy.is_none() {
            anyhow::ensure!(
                run.base_vacant == BaseVacant::AsSaved,
                "[run] base_vacant = \"redrawn\" needs a base policy ([run] base_policy): without one every \
                 weight is drawn at [net.mask]'s range already"
            );
            sequence.validate_with(KnownBefore::Tasks(Vec::new()))?;
        }
        Ok(Self { config, method, method_settings, switches, eval, run, sequence })
    }

    /// The run file `text` with `[method] name` set to `name` (`quadcl run --method`): the
    /// text a run folder keeps as its `run.toml`, so `--resume` compares like with like.
    /// Comments do not survive; a header says where the file came from.
    pub fn text_with_method(text: &str, name: &str, source: &Path) -> anyhow::Result<String> {
        let mut table: toml::Table = toml::from_str(text).map_err(|e| anyhow::anyhow!("{}: {e}", source.display()))?;
        let method = table.entry("method").or_insert_with(|| toml::Value::Table(toml::Table::new()));
        let toml::Value::Table(method) = method else {
            anyhow::bail!("{}: method = {method}: expected a [method] table", source.display())
        };
        method.insert("name".into(), toml::Value::String(name.to_string()));
        let body = toml::to_string(&table)?;
        let text = format!("# {} with --method {name}\n{body}", source.display());
        Self::from_toml_str(&text).with_context(|| format!("{} with --method {name}", source.display()))?;
        Ok(text)
    }

    /// The same run with method `name` (`quadcl run --method`); an unknown name is an error.
    pub fn with_method(mut self, name: &str) -> anyhow::Result<Self> {
        crate::cl::method_by_name(name, &self.method_settings)?;
        self.method = name.to_string();
        Ok(self)
    }
}

/// Each task's mask settings as the method will make them when the task starts (the run's
/// switches with the task's `[task.switches]`), checked now: ranges, and that the capacity
/// selects something in every layer `[net]` sizes.
fn check_task_masks(
    config: &Config,
    method: &dyn ContinualMethod,
    base_mask: &MaskConfig,
    switches: &Switches,
    sequence: &Sequence,
) -> anyhow::Result<()> {
    for (i, task) in sequence.tasks.iter().enumerate() {
        let task_switches = switches.with(&task.switches);
        let mask = task_switches
            .apply(base_mask)
            .and_then(|_| method.task_mask_config(base_mask, &task_switches, sequence.iterations_of(i)))
            .map(|mask| mask.for_budget(sequence.iterations_of(i)))
            .and_then(|mask| config.net.check_selects(&mask));
        mask.with_context(|| format!("task {} ({}): in [task.switches]", i + 1, task.name))?;
    }
    Ok(())
}

/// PackNet prunes a task `retrain_iterations` before its end: a task no longer than that would
/// be pruned before it trained its fresh weights at all.
fn check_packnet_budgets(settings: &MethodSettings, sequence: &Sequence) -> anyhow::Result<()> {
    let retrain = settings.packnet.retrain_iterations;
    for (i, task) in sequence.tasks.iter().enumerate() {
        let n = sequence.iterations_of(i);
        anyhow::ensure!(
            retrain < n,
            "[method.packnet] retrain_iterations = {retrain}: task {} ({}) trains {n} iterations, so it would \
             be pruned before its first (give it more than {retrain}, or retrain_iterations = 0 for a tenth)",
            i + 1,
            task.name
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_method_reads_its_own_table_and_bad_values_name_the_key() {
        let text =
            "[method]\nname = \"ewc\"\n[method.ewc]\nlambda = 50.0\n[method.si]\nc = 0.5\n[[task]]\nname = \"none\"\n";
        let r = RunConfig::from_toml_str(text).unwrap();
        assert_eq!((r.method.as_str(), r.method_settings.ewc.lambda, r.method_settings.si.c), ("ewc", 50.0, 0.5));
        assert_eq!(r.method_settings.ewc.fisher_samples, crate::cl::EwcConfig::default().fisher_samples);
        for (table, key) in
            [("[method.ewc]\nlambda = -1.0", "lambda"), ("[method.si]\nxi = 0.0", "xi"), ("[method.si]\ncc = 1", "cc")]
        {
            let text = format!("[method]\nname = \"si\"\n{table}\n[[task]]\nname = \"none\"\n");
            let err = format!("{:#}", RunConfig::from_toml_str(&text).unwrap_err());
            assert!(err.contains(key), "{key}: {err}");
        }
        let r = RunConfig::from_toml_str(SMALL).unwrap().with_method("si").unwrap();
        assert_eq!(r.method, "si");
        assert!(RunConfig::from_toml_str(SMALL).unwrap().with_method("ewx").is_err());
    }

    const SMALL: &str = "seed = 4\niterations = 3\n[method]\nreinit = false\nlambda = \"free\"\n[run]\nlearner = \"toy\"\n[[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\n[task.switches]\nentropy = false\n";

    #[test]
    fn a_run_file_splits_into_config_method_and_sequence() {
        let r = RunConfig::from_toml_str(SMALL).unwrap();
        assert_eq!(r.config.seed, 4);
        assert_eq!(r.method, "ours");
        assert!(!r.switches.reinit_weights);
        assert_eq!(r.switches.lambda, crate::cl::LambdaMode::Free);
        assert_eq!(r.run.learner, LearnerKind::Toy);
        assert_eq!(r.sequence.tasks.len(), 2);
        assert_eq!(r.sequence.iterations_of(1), 3);
        assert_eq!(r.sequence.tasks[1].switches.entropy, Some(false));
    }

    #[test]
    fn unknown_keys_are_errors_naming_the_key() {
        for (text, key) in [
            ("sede = 1\n[[task]]\nname = \"none\"\n", "sede"),
            ("[method]\nrenit = true\n[[task]]\nname = \"none\"\n", "renit"),
            ("[eval]\nepisode = 3\n[[task]]\nname = \"none\"\n", "episode"),
            ("[[task]]\nname = \"none\"\nswitches = { capacty = 0.1 }\n", "capacty"),
        ] {
            let err = format!("{:#}", RunConfig::from_toml_str(text).unwrap_err());
            assert!(err.contains(key), "{key}: {err}");
        }
    }

    #[test]
    fn a_run_without_tasks_or_with_an_unknown_method_is_an_error() {
        assert!(format!("{:#}", RunConfig::from_toml_str("seed = 1\n").unwrap_err()).contains("[[task]]"));
        let err = format!(
            "{:#}",
            RunConfig::from_toml_str("[method]\nname = \"ewx\"\n[[task]]\nname = \"none\"\n").unwrap_err()
        );
        assert!(err.contains("ewx") && err.contains("ewc"), "{err}");
    }
}
