//! Watching a policy: [`RobotViewer`] runs a policy directory's deterministic
//! policy on one environment of a task, one control step at a time, and hands
//! back what a drawing needs ([`RobotFrame`]: the robot's world pose, the
//! command, the trunk's velocity, the time). The environment is the one
//! `record_gait` uses (nominal physics, no pushes); a fall or the end of an
//! episode starts the next episode, so a viewer runs for as long as it is stepped.

use super::acting::ActingWeights;
use super::agent::Agent;
use super::policy_dir::load_for_task;
use crate::config::EnvConfig;
use crate::sim::obs::rotate_into_frame;
use crate::sim::{LocomotionEnv, Perturbation, RobotModel, RobotPose};
use anyhow::Context;
use std::path::Path;

/// What one control step shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotFrame {
    /// The robot after the step (after a fall: where it fell; the next step starts a new episode).
    pub pose: RobotPose,
    /// The command the policy followed in this step (vx m/s, vy m/s, wz rad/s, trunk frame).
    pub command: [f32; 3],
    /// The trunk's velocity in its own frame: forward vx, lateral vy (m/s), yaw rate wz (rad/s).
    pub base_velocity: [f32; 3],
    /// Simulated seconds since the viewer started (control steps times the policy step).
    pub sim_time: f32,
    /// Simulated seconds since this episode started.
    pub episode_time: f32,
    /// Episodes started before this one (falls and time-outs so far).
    pub episode: u64,
    /// Whether this step ended in a fall (trunk contact or tilt).
    pub fell: bool,
}

/// A policy walking one robot, a control step per [`RobotViewer::step`].
pub struct RobotViewer {
    agent: Agent,
    /// The agent's acting weights, made once: the viewer owns the agent and never trains it.
    weights: ActingWeights,
    env: LocomotionEnv,
    /// The command held through every episode; `None`: the env's own random commands.
    held: Option<[f32; 3]>,
    dt: f32,
    steps: u64,
    episode_steps: u64,
    episode: u64,
}

impl RobotViewer {
    /// Loads the policy directory `policy_dir` for `task` (`none`, `crash:FL`, ...) as `quadcl eval`
    /// and `quadcl gait` do ([`load_for_task`]: a policy directory or a training run's
    /// `checkpoint/`), and builds one environment of `task` from the policy's env config, reset
    /// with `seed`. `command`: the (vx, vy, wz) held throughout, or `None` for the env's own
    /// commands, resampled every `command_resample_s`.
    pub fn new(policy_dir: &Path, task: &str, seed: u64, command: Option<[f32; 3]>) -> anyhow::Result<Self> {
        let task: Perturbation = task.parse()?;
        let loaded = load_for_task(policy_dir, &task.to_string())?;
        let env_cfg = &loaded.info.config.env;
        let robot =
            RobotModel::for_config(env_cfg).with_context(|| format!("the robot of policy {}", policy_dir.display()))?;
        Self::with_agent(loaded.agent, env_cfg, &robot, &task, seed, command)
    }

    /// A viewer of an agent already in memory, on one environment of `task` built from
    /// `env_cfg` with nominal physics and no pushes (as `record_gait`).
    pub fn with_agent(
        agent: Agent,
        env_cfg: &EnvConfig,
        robot: &RobotModel,
        task: &Perturbation,
        seed: u64,
        command: Option<[f32; 3]>,
    ) -> anyhow::Result<Self> {
        let cfg = EnvConfig { randomize: false, push_interval_s: 0.0, ..env_cfg.clone() };
        let mut env = LocomotionEnv::new(&cfg, robot, task)?;
        env.reset(seed)?;
        let weights = agent.acting_weights()?;
        let mut viewer =
            Self { agent, weights, env, held: command, dt: cfg.policy_dt(), steps: 0, episode_steps: 0, episode: 0 };
        viewer.hold_command();
        Ok(viewer)
    }

    /// Holds `command` (vx m/s, vy m/s, wz rad/s) from the next step on, or with `None` goes
    /// back to the env's own random commands (from the next resample).
    pub fn set_command(&mut self, command: Option<[f32; 3]>) {
        self.held = command;
        self.hold_command();
    }

    /// The held command, if one is held.
    pub fn held_command(&self) -> Option<[f32; 3]> {
        self.held
    }

    /// The command the next step follows.
    pub fn command(&self) -> [f32; 3] {
        self.env.command()
    }

    /// The task the robot runs on.
    pub fn task(&self) -> &Perturbation {
        self.env.task()
    }

    /// Attaches a step observer (a recorder) to the viewer's env; it hears the current state
    /// as the start of the episode, then every step.
    pub fn observe(&mut self, observer: Box<dyn crate::sim::StepObserver>) {
        self.env.observe(observer);
        self.env.announce();
    }

    /// Detaches the observer, to finish it.
    pub fn take_observer(&mut self) -> Option<Box<dyn crate::sim::StepObserver>> {
        self.env.take_observer()
    }

    /// The viewer's env (its robot, its task).
    pub fn env(&self) -> &crate::sim::LocomotionEnv {
        &self.env
    }

    /// The policy's masks per layer as the task it acts with sees them (what a recording shows;
    /// empty for a dense network).
    pub fn mask_views(&self) -> Vec<crate::nn::LayerView> {
        crate::nn::mask_views(&self.agent.masked_networks(), self.agent.task())
    }

    /// Episodes finished so far.
    pub fn episodes(&self) -> u64 {
        self.episode
    }

    /// Seconds per control step.
    pub fn policy_dt(&self) -> f32 {
        self.dt
    }

    /// The current state as a frame, without stepping (what to draw before the first step).
    pub fn frame(&self) -> RobotFrame {
        self.frame_now(false)
    }

    /// One control step with the policy's deterministic action. After a fall or a time-out the
    /// returned frame still shows the end of the episode, and the env starts the next episode
    /// (from its own random stream, so the run is deterministic given the seed).
    pub fn step(&mut self) -> anyhow::Result<RobotFrame> {
        // The command of this step (the env may resample it at the step's end).
        let command = self.env.command();
        let actions =
            self.agent.act_deterministic_with(&self.weights, self.env.observation(), self.env.obs_history())?;
        let step = self.env.step(&actions)?;
        self.steps += 1;
        self.episode_steps += 1;
        let frame = RobotFrame { command, ..self.frame_now(step.terminated) };
        if step.terminated || step.truncated {
            self.env.reset_episode()?;
            self.episode += 1;
            self.episode_steps = 0;
        }
        self.hold_command();
        Ok(frame)
    }

    fn hold_command(&mut self) {
        if let Some(command) = self.held.filter(|c| *c != self.env.command()) {
            self.env.set_command(command);
        }
    }

    fn frame_now(&self, fell: bool) -> RobotFrame {
        let s = self.env.raw_state();
        let lin = rotate_into_frame(s.base_quat, s.base_lin_vel);
        let ang = rotate_into_frame(s.base_quat, s.base_ang_vel);
        RobotFrame {
            pose: self.env.pose(),
            command: self.env.command(),
            base_velocity: [lin[0], lin[1], ang[2]],
            sim_time: self.steps as f32 * self.dt,
            episode_time: self.episode_steps as f32 * self.dt,
            episode: self.episode,
            fell,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base_policy() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("policies/base-a1-flat")
    }

    #[test]
    fn the_base_policy_walks_the_held_command_for_fifty_steps_without_falling() {
        let command = [0.5, 0.0, 0.0];
        let mut viewer = RobotViewer::new(&base_policy(), "none", 0, Some(command)).unwrap();
        let dt = viewer.policy_dt();
        assert!((dt - 0.02).abs() < 1e-6, "policy dt {dt}");
        let start = viewer.frame();
        assert_eq!((start.sim_time, start.command, start.fell), (0.0, command, false));
        let mut frames = Vec::new();
        for _ in 0..50 {
            frames.push(viewer.step().unwrap());
        }
        let last = frames.last().unwrap();
        assert_eq!(last.sim_time, 50.0 * dt);
        assert_eq!((last.episode, last.episode_time), (0, 50.0 * dt));
        assert!(frames.iter().all(|f| !f.fell && f.command == command), "a fall or a changed command");
        let height = last.pose.trunk_center[2];
        assert!(height > 0.2 && height < 0.4 && last.pose.trunk_rotation[2][2] > 0.9, "{:?}", last.pose);
        // It walks forward: over the last 0.5 s the trunk moves at some of the commanded 0.5 m/s.
        let vx: f32 = frames[25..].iter().map(|f| f.base_velocity[0]).sum::<f32>() / 25.0;
        assert!(vx > 0.2 && vx < 0.8, "mean forward velocity {vx} m/s");
        assert!(last.pose.trunk_center[0] > start.pose.trunk_center[0] + 0.1, "{:?}", last.pose);
        // A trot lifts feet: some frame has a foot in the air, and every frame has one on the ground.
        assert!(frames.iter().any(|f| f.pose.legs.iter().any(|l| !l.contact)));
        assert!(frames[10..].iter().all(|f| f.pose.legs.iter().any(|l| l.contact)));
    }

    #[test]
    fn a_changed_command_is_followed_and_a_fall_starts_a_new_episode() {
        let mut viewer = RobotViewer::new(&base_policy(), "none", 3, None).unwrap();
        assert_eq!(viewer.held_command(), None);
        viewer.set_command(Some([0.0, 0.0, 0.5]));
        assert_eq!(viewer.command(), [0.0, 0.0, 0.5]);
        assert_eq!(viewer.step().unwrap().command, [0.0, 0.0, 0.5]);
        // Knock the robot over: it falls within a second, and the viewer goes on in a new episode.
        viewer.env.push([6.0, 6.0]);
        let frames: Vec<RobotFrame> = (0..100).map(|_| viewer.step().unwrap()).collect();
        let fall = frames.iter().position(|f| f.fell).expect("a 8.5 m/s push topples the robot");
        let after = &frames[fall + 1];
        assert_eq!((after.episode, after.episode_time), (1, viewer.policy_dt()));
        assert!((after.sim_time - (fall + 3) as f32 * viewer.policy_dt()).abs() < 1e-5);
        assert!(after.pose.trunk_center[2] > 0.3, "the new episode starts at the start height: {:?}", after.pose);
    }
}
