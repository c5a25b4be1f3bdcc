//! Task sequences: which perturbed-leg tasks a run trains, in which order,
//! with which budget and which related tasks (METHOD.md 2.5, 2.6), read from
//! a TOML file under `scenes/`.
//!
//! ```toml
//! [[task]]
//! name = "crash:FL"          # the perturbation syntax of sim::tasks
//! iterations = 200           # PPO iterations for this task (optional)
//! [[task]]
//! name = "invert:RR+noise:FR"
//! related = ["invert:RR", "noise:FR"]  # forward transfer (METHOD.md 2.6)
//! init = "related"           # related | random | scratch
//! [task.switches]            # ablation switches for this task only (cl::ours)
//! reinit_weights = false
//! ```
//!
//! A task name may come back later in the sequence: it is then a repeat, trained on
//! its private parameters only (METHOD.md 2.5).

use super::ours::SwitchOverrides;
use crate::config::bounds;
use crate::config::ppo::MAX_ITERATIONS;
use crate::sim::Perturbation;
use serde::{Deserialize, Serialize};
use std::str::FromStr;

/// How a new task's soft scores start (METHOD.md 2.6).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TransferInit {
    /// A bonus on the elements the named related tasks select.
    #[default]
    Related,
    /// The same bonus on as many other learned tasks, drawn at random.
    Random,
    /// No bonus.
    Scratch,
}

/// One entry of a sequence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskSpec {
    /// The perturbation, e.g. `invert:RR+noise:FR`; `none` is the base task.
    pub name: String,
    /// PPO iterations for this task; the sequence default when absent.
    #[serde(default)]
    pub iterations: Option<usize>,
    /// Earlier tasks whose masks seed this task's soft scores.
    #[serde(default)]
    pub related: Vec<String>,
    /// How the soft scores start.
    #[serde(default)]
    pub init: TransferInit,
    /// Switches of the method changed for this task only (unset ones keep the run's).
    #[serde(default)]
    pub switches: SwitchOverrides,
}

/// A whole sequence, as written in TOML.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sequence {
    /// PPO iterations of a task that names none.
    #[serde(default = "default_iterations")]
    pub iterations: usize,
    /// The tasks in training order.
    #[serde(rename = "task")]
    pub tasks: Vec<TaskSpec>,
}

fn default_iterations() -> usize {
    300
}

/// What the learner knows before a sequence starts, for checking related-task names.
#[derive(Debug, Clone)]
pub enum KnownBefore {
    /// Not known yet (a base policy is still to be loaded): names outside the sequence pass.
    Pending,
    /// Exactly these tasks (empty: none).
    Tasks(Vec<String>),
}

impl Sequence {
    /// Checks every name and reference; the error names the entry (1-based)
    /// and what is wrong. Related tasks that are not earlier in the sequence are
    /// left for [`Sequence::validate_with`] once the tasks learned before it are known.
    pub fn validate(&self) -> anyhow::Result<()> {
        self.validate_with(KnownBefore::Pending)
    }

    /// [`Sequence::validate`] given what is learned before the sequence starts: a related task
    /// must be trained earlier in the sequence or be one of `known`'s tasks.
    pub fn validate_with(&self, known: KnownBefore) -> anyhow::Result<()> {
        anyhow::ensure!(!self.tasks.is_empty(), "the sequence has no [[task]] entries");
        bounds::check_count("iterations", self.iterations, 0, MAX_ITERATIONS)?;
        for (i, task) in self.tasks.iter().enumerate() {
            let at = || format!("task {} ({})", i + 1, task.name);
            Perturbation::from_str(&task.name).map_err(|e| anyhow::anyhow!("{}: {e}", at()))?;
            // A task of 0 iterations trains nothing and reports results as if it had.
            let (key, n) = match task.iterations {
                Some(n) => ("iterations", n),
                None => ("iterations (the run's default, which it takes)", self.iterations),
            };
            bounds::check_count(key, n, 1, MAX_ITERATIONS).map_err(|e| anyhow::anyhow!("{}: {e}", at()))?;
            if task.init == TransferInit::Random && task.related.is_empty() {
                anyhow::bail!("{}: init = \"random\" draws as many tasks as `related` names, and it names none", at());
            }
            for related in &task.related {
                let earlier = self.tasks[..i].iter().any(|t| &t.name == related);
                let known_before = match &known {
                    KnownBefore::Pending => true,
                    KnownBefore::Tasks(tasks) => tasks.contains(related),
                };
                anyhow::ensure!(
                    earlier || known_before,
                    "{}: related task {related:?} is not trained earlier in the sequence{}",
                    at(),
                    match &known {
                        KnownBefore::Tasks(t) if !t.is_empty() => format!(" nor by the base policy (which has {t:?})"),
                        _ => " and the run has no base policy ([run] base_policy)".to_string(),
                    }
                );
            }
        }
        let total: usize = (0..self.tasks.len()).map(|i| self.iterations_of(i)).sum();
        anyhow::ensure!(
            total <= MAX_ITERATIONS,
            "the sequence trains {total} iterations in all: at most {MAX_ITERATIONS} (the curves keep a row per iteration)"
        );
        Ok(())
    }

    /// The distinct task names in order of first appearance (the columns of
    /// the evaluation matrix and the learner's task ids).
    pub fn distinct_tasks(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for t in &self.tasks {
            if !names.contains(&t.name) {
                names.push(t.name.clone());
            }
        }
        names
    }

    /// The iteration budget of entry `i`.
    pub fn iterations_of(&self, i: usize) -> usize {
        self.tasks[i].iterations.unwrap_or(self.iterations)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> anyhow::Result<Sequence> {
        let seq: Sequence = toml::from_str(text)?;
        seq.validate_with(KnownBefore::Tasks(Vec::new()))?;
        Ok(seq)
    }

    #[test]
    fn repeats_keep_one_column_per_distinct_task() {
        let seq = parse(
            "iterations = 5\n[[task]]\nname = \"crash:FL\"\n[[task]]\nname = \"invert:RR\"\niterations = 7\n[[task]]\nname = \"crash:FL\"\n",
        )
        .unwrap();
        assert_eq!(seq.distinct_tasks(), vec!["crash:FL", "invert:RR"]);
        assert_eq!(seq.iterations_of(0), 5);
        assert_eq!(seq.iterations_of(1), 7);
    }

    #[test]
    fn an_unknown_task_name_is_an_error_naming_the_entry() {
        let err = format!("{:#}", parse("[[task]]\nname = \"none\"\n[[task]]\nname = \"wobble:FL\"\n").unwrap_err());
        assert!(err.contains("task 2") && err.contains("wobble"), "{err}");
    }

    #[test]
    fn a_related_task_must_come_earlier() {
        let err = format!(
            "{:#}",
            parse(
                "[[task]]\nname = \"invert:RR+noise:FR\"\nrelated = [\"invert:RR\"]\n[[task]]\nname = \"invert:RR\"\n"
            )
            .unwrap_err()
        );
        assert!(err.contains("not trained earlier"), "{err}");
    }

    #[test]
    fn a_related_task_may_be_one_learned_before_the_sequence() {
        let seq: Sequence = toml::from_str("[[task]]\nname = \"crash:FL\"\nrelated = [\"none\"]\n").unwrap();
        // Before the base policy is read the name cannot be checked; once it is, it must be there.
        seq.validate().unwrap();
        seq.validate_with(KnownBefore::Tasks(vec!["none".into()])).unwrap();
        let err = format!("{:#}", seq.validate_with(KnownBefore::Tasks(vec!["invert:RR".into()])).unwrap_err());
        assert!(err.contains("task 1 (crash:FL)") && err.contains("\"none\"") && err.contains("base policy"), "{err}");
        let err = format!("{:#}", seq.validate_with(KnownBefore::Tasks(Vec::new())).unwrap_err());
        assert!(err.contains("no base policy"), "{err}");
    }
}
