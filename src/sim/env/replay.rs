//! An env's exact state, as a replay of its current episode: the random
//! stream as the episode began and what the env was given since (actions,
//! pushes and commands from outside). A reset builds a fresh world from the
//! stream alone, and rapier is deterministic, so re-running the episode's
//! steps in another process lands on the same state bit for bit, contact
//! caches and solver warm starts included, without serialising rapier.
//!
//! The replay runs under the env's own task and configuration: a task changed
//! in mid-episode (`set_task`, which only sequences do, between tasks) is not
//! part of it.
//!
//! Kept only when asked ([`LocomotionEnv::keep_replay`]: training that
//! checkpoints); it costs ACT_DIM f32 per control step of the current episode
//! (48 KB for a 20 s episode at 50 Hz), cleared at each reset (its capacity kept).

use super::LocomotionEnv;
use crate::sim::obs::ACT_DIM;
use crate::util::RngState;
use anyhow::{bail, ensure};

/// What the env was given from outside, between two steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Intervention {
    /// [`LocomotionEnv::push`] with this velocity change (world x, y, m/s).
    Push([f32; 2]),
    /// [`LocomotionEnv::set_command`] with this command.
    Command([f32; 3]),
}

/// Everything that restores an env exactly (see the module header).
#[derive(Debug, Clone, PartialEq)]
pub struct EpisodeReplay {
    /// The env's random stream at the start of its current episode, before the episode's draws.
    pub start_rng: RngState,
    /// (steps, ACT_DIM): the actions of the episode's steps, in order.
    pub actions: Vec<f32>,
    /// Interventions, each after this many steps of the episode, in order.
    pub interventions: Vec<(usize, Intervention)>,
    /// Control steps since the env was built (across episodes).
    pub total_steps: u64,
    /// Simulated seconds since the env was built.
    pub sim_time: f64,
}

impl EpisodeReplay {
    /// Control steps of the current episode.
    pub fn steps(&self) -> usize {
        self.actions.len() / ACT_DIM
    }
}

/// The part of the replay an env keeps while it steps.
#[derive(Debug, Clone, Default)]
pub(super) struct EpisodeLog {
    pub actions: Vec<f32>,
    pub interventions: Vec<(usize, Intervention)>,
}

impl LocomotionEnv {
    /// From now on keep what [`Self::replay`] needs. Must be called before the episode's first step.
    pub fn keep_replay(&mut self) -> anyhow::Result<()> {
        ensure!(
            self.episode_step == 0,
            "env {}: a replay must be kept from an episode's start (it is at step {})",
            self.env_index,
            self.episode_step
        );
        self.replay_log = Some(EpisodeLog::default());
        Ok(())
    }

    /// The env's exact state as a replay of its current episode.
    pub fn replay(&self) -> anyhow::Result<EpisodeReplay> {
        let Some(log) = &self.replay_log else {
            bail!("env {}: no replay kept (keep_replay was not called)", self.env_index)
        };
        Ok(EpisodeReplay {
            start_rng: self.episode_start_rng,
            actions: log.actions.clone(),
            interventions: log.interventions.clone(),
            total_steps: self.total_steps,
            sim_time: self.sim_time,
        })
    }

    /// Puts the env in the state `replay` describes: a reset from its stream, then its steps
    /// again (no observer hears them). Keeps the replay from then on. Errors if the episode
    /// ends early: the replay then belongs to another robot, task or configuration.
    pub fn restore(&mut self, replay: &EpisodeReplay) -> anyhow::Result<()> {
        ensure!(
            replay.actions.len() % ACT_DIM == 0,
            "env {}: a replay of {} action values is not whole steps of {ACT_DIM}",
            self.env_index,
            replay.actions.len()
        );
        let observer = self.observer.take();
        let result = self.replay_steps(replay);
        self.observer = observer;
        result
    }

    fn replay_steps(&mut self, replay: &EpisodeReplay) -> anyhow::Result<()> {
        self.rng = replay.start_rng.rng();
        self.reset_episode()?;
        self.replay_log = Some(EpisodeLog::default());
        let steps = replay.steps();
        let mut interventions = replay.interventions.iter().peekable();
        for s in 0..=steps {
            while let Some((_, what)) = interventions.next_if(|(at, _)| *at == s) {
                match *what {
                    Intervention::Push(dv) => self.push(dv),
                    Intervention::Command(c) => self.set_command(c),
                }
            }
            if s == steps {
                break;
            }
            let step = self.step(&replay.actions[s * ACT_DIM..(s + 1) * ACT_DIM])?;
            ensure!(
                !(step.terminated || step.truncated),
                "env {}: the replayed episode ended at step {} of {steps}: the checkpoint was made with another robot, task or configuration",
                self.env_index,
                s + 1
            );
        }
        if let Some((at, _)) = interventions.next() {
            bail!("env {}: an intervention after step {at} of a {steps}-step episode", self.env_index);
        }
        self.total_steps = replay.total_steps;
        self.sim_time = replay.sim_time;
        Ok(())
    }

    /// Notes an action or an intervention in the replay log, when one is kept.
    pub(super) fn log_action(&mut self, action: &[f32]) {
        if let Some(log) = &mut self.replay_log {
            log.actions.extend_from_slice(action);
        }
    }

    pub(super) fn log_intervention(&mut self, what: Intervention) {
        let at = self.episode_step;
        if let Some(log) = &mut self.replay_log {
            log.interventions.push((at, what));
        }
    }
}
