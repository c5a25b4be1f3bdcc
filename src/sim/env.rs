//! `LocomotionEnv`: one robot, one world, one random stream. reset(seed) /
//! step(action) -> Step, legged_gym conventions (DESIGN.md, "The environment").
//!
//! A policy step: clip the action (ACT_DIM,), apply the task perturbation,
//! set PD targets = default + action_scale * action (clamped to the joint
//! range), run `decimation`
//! physics steps, then read the state, compute the Table 1 reward, check
//! termination (trunk contact or tilt) and time-out, resample the command
//! every `command_resample_s`, push every `push_interval_s`, and build the
//! observations. The env does not reset itself: the caller (or `VecEnv`)
//! calls [`LocomotionEnv::reset_episode`] once a step says it is done.

use super::env_setup::{build_sim, default_pose, first_non_finite, joint_gains, soft_limit, uniform};
use super::episode::{EpisodeStats, PhysicsBlowUp, Step};
use super::obs::{self, ObsInput, ACT_DIM, HISTORY_LEN, OBS_DIM, PRIV_OBS_DIM};
use super::observe::{StepInfo, StepObserver};
use super::physics::{PdGains, PhysicsParams, RawState, RobotSim, WorldShapes};
use super::reward::{self, RewardInput};
use super::robot::RobotModel;
use super::tasks::Perturbation;
use crate::config::EnvConfig;
use anyhow::{bail, Context};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::Arc;

mod replay;
pub use replay::{EpisodeReplay, Intervention};

/// How long a push shows in the privileged observation, seconds.
const PUSH_STATE_HOLD_S: f32 = 1.0;

/// One simulated quadruped with its task.
pub struct LocomotionEnv {
    cfg: Arc<EnvConfig>,
    robot: Arc<RobotModel>,
    task: Perturbation,
    /// Index of this env in its batch (for messages).
    env_index: usize,
    rng: ChaCha8Rng,
    sim: RobotSim,
    default_q: [f32; 12],
    /// PD stiffness and damping per leg joint (`env.robot.kp` / `kd`, else `env.kp` / `kd`).
    gains: PdGains,
    soft_lower: [f32; 12],
    soft_upper: [f32; 12],
    params: PhysicsParams,
    command: [f32; 3],
    episode_step: usize,
    total_steps: u64,
    push: [f32; 2],
    push_age_s: f32,
    state: RawState,
    last_action: [f32; 12],
    foot_contacts: [bool; 4],
    obs: [f32; OBS_DIM],
    priv_obs: [f32; PRIV_OBS_DIM],
    history: Vec<f32>,
    episode: EpisodeStats,
    /// Simulated seconds since the env was built.
    sim_time: f64,
    observer: Option<Box<dyn StepObserver>>,
    /// The random stream as the current episode began (for [`EpisodeReplay`]).
    episode_start_rng: crate::util::RngState,
    /// The current episode's actions and interventions, when a replay is kept.
    replay_log: Option<replay::EpisodeLog>,
}

impl LocomotionEnv {
    /// A new env, already reset with seed 0.
    pub fn new(cfg: &EnvConfig, robot: &RobotModel, task: &Perturbation) -> anyhow::Result<Self> {
        Self::with_shared_robot(cfg, Arc::new(robot.clone()), task, 0)
    }

    /// A new env sharing a robot description; `env_index` names it in errors.
    pub fn with_shared_robot(
        cfg: &EnvConfig,
        robot: Arc<RobotModel>,
        task: &Perturbation,
        env_index: usize,
    ) -> anyhow::Result<Self> {
        cfg.validate()?;
        let default_q = default_pose(cfg, &robot).with_context(|| format!("robot {}", robot.path.display()))?;
        let gains = joint_gains(cfg, &robot).with_context(|| format!("robot {}", robot.path.display()))?;
        let soft_lower = std::array::from_fn(|i| soft_limit(&robot, cfg, i).0);
        let soft_upper = std::array::from_fn(|i| soft_limit(&robot, cfg, i).1);
        let params = PhysicsParams { friction: 1.0, added_mass: 0.0, motor_strength: 1.0 };
        let sim = build_sim(cfg, &robot, params, &default_q, &gains)?;
        let mut env = Self {
            cfg: Arc::new(cfg.clone()),
            robot,
            task: task.clone(),
            env_index,
            rng: ChaCha8Rng::seed_from_u64(0),
            sim,
            default_q,
            gains,
            soft_lower,
            soft_upper,
            params,
            command: [0.0; 3],
            episode_step: 0,
            total_steps: 0,
            push: [0.0; 2],
            push_age_s: f32::INFINITY,
            state: RawState::default(),
            last_action: [0.0; 12],
            foot_contacts: [false; 4],
            obs: [0.0; OBS_DIM],
            priv_obs: [0.0; PRIV_OBS_DIM],
            history: vec![0.0; HISTORY_LEN * OBS_DIM],
            episode: EpisodeStats::default(),
            sim_time: 0.0,
            observer: None,
            episode_start_rng: crate::util::RngState::of(&ChaCha8Rng::seed_from_u64(0)),
            replay_log: None,
        };
        env.reset(0)?;
        Ok(env)
    }

    /// Reseeds the env's random stream and starts a new episode.
    pub fn reset(&mut self, seed: u64) -> anyhow::Result<()> {
        self.rng = ChaCha8Rng::seed_from_u64(seed);
        self.reset_episode()
    }

    /// Starts a new episode, drawing from the env's own random stream:
    /// domain randomisation, a fresh world at the default pose, a command.
    pub fn reset_episode(&mut self) -> anyhow::Result<()> {
        self.episode_start_rng = crate::util::RngState::of(&self.rng);
        if let Some(log) = &mut self.replay_log {
            log.actions.clear();
            log.interventions.clear();
        }
        let c = &self.cfg;
        self.params = if c.randomize {
            PhysicsParams {
                friction: uniform(&mut self.rng, c.friction_range),
                added_mass: uniform(&mut self.rng, c.added_mass_range),
                motor_strength: uniform(&mut self.rng, c.motor_strength_range),
            }
        } else {
            PhysicsParams { friction: 1.0, added_mass: 0.0, motor_strength: 1.0 }
        };
        self.sim = build_sim(c, &self.robot, self.params, &self.default_q, &self.gains)
            .with_context(|| format!("env {}: building the world", self.env_index))?;
        self.resample_command();
        self.episode_step = 0;
        self.push = [0.0; 2];
        self.push_age_s = f32::INFINITY;
        self.last_action = [0.0; 12];
        self.state = self.sim.state();
        self.foot_contacts = [false; 4];
        self.episode = EpisodeStats::default();
        self.write_observations();
        for k in 0..HISTORY_LEN {
            self.history[k * OBS_DIM..(k + 1) * OBS_DIM].copy_from_slice(&self.obs);
        }
        self.notify(None);
        Ok(())
    }

    /// Attaches `observer`: it hears every later episode start and control step.
    pub fn observe(&mut self, observer: Box<dyn StepObserver>) {
        self.observer = Some(observer);
    }

    /// Tells the observer the current state as an episode start (after attaching it mid-episode).
    pub fn announce(&mut self) {
        self.notify(None);
    }

    /// The robot description.
    pub fn robot(&self) -> &RobotModel {
        &self.robot
    }

    /// Detaches the observer (to [`StepObserver::finish`] it).
    pub fn take_observer(&mut self) -> Option<Box<dyn StepObserver>> {
        self.observer.take()
    }

    /// Simulated seconds since the env was built.
    pub fn sim_time(&self) -> f64 {
        self.sim_time
    }

    fn notify(&mut self, step: Option<(&Step, Option<[f32; 2]>)>) {
        let Some(mut o) = self.observer.take() else { return };
        let links = self.sim.link_poses();
        let info = StepInfo {
            env: self.env_index,
            sim_time: self.sim_time,
            episode_step: self.episode_step,
            state: &self.state,
            links: &links,
            command: self.command,
            targets: self.sim.targets(),
            torques: self.sim.last_torques(),
            reward: step.map(|(s, _)| (s.reward, &s.terms)),
            contacts: self.foot_contacts,
            push: step.and_then(|(_, p)| p),
            terminated: step.is_some_and(|(s, _)| s.terminated),
            truncated: step.is_some_and(|(s, _)| s.truncated),
        };
        match step {
            None => o.on_reset(&info),
            Some(_) => o.on_step(&info),
        }
        self.observer = Some(o);
    }

    /// Current policy observation (OBS_DIM,), layout in `sim::obs`.
    pub fn observation(&self) -> &[f32; OBS_DIM] {
        &self.obs
    }

    /// Current privileged observation (PRIV_OBS_DIM,).
    pub fn privileged_observation(&self) -> &[f32; PRIV_OBS_DIM] {
        &self.priv_obs
    }

    /// The last HISTORY_LEN observations, oldest first (HISTORY_LEN * OBS_DIM,).
    pub fn obs_history(&self) -> &[f32] {
        &self.history
    }

    /// The raw physical state after the last step (world frame).
    pub fn raw_state(&self) -> &RawState {
        &self.state
    }

    /// The current command (vx, vy, wz).
    pub fn command(&self) -> [f32; 3] {
        self.command
    }

    /// Sets the command until the next resample (for evaluation and tests). The
    /// observation and the newest history entry (every entry, right after a reset) show it.
    pub fn set_command(&mut self, command: [f32; 3]) {
        self.log_intervention(Intervention::Command(command));
        self.command = command;
        self.write_observations();
        let first = if self.episode_step == 0 { 0 } else { HISTORY_LEN - 1 };
        for k in first..HISTORY_LEN {
            self.history[k * OBS_DIM..(k + 1) * OBS_DIM].copy_from_slice(&self.obs);
        }
    }

    /// The robot's and the ground's colliders as the last step left them, for pictures
    /// (the simulator's [`WorldShapes`]).
    pub fn collider_shapes(&self) -> WorldShapes {
        self.sim.collider_shapes()
    }

    /// Where the trunk, the leg joints and the feet are now, for drawing the robot (`sim::pose`).
    pub fn pose(&self) -> super::pose::RobotPose {
        super::pose::robot_pose(&self.robot, &self.state, &self.sim.joint_positions(), self.foot_contacts)
    }

    /// This episode's physical parameters.
    pub fn physics_params(&self) -> PhysicsParams {
        self.params
    }

    /// The default joint pose, rad.
    pub fn default_pose(&self) -> &[f32; 12] {
        &self.default_q
    }

    /// The PD targets of the last step, rad.
    pub fn targets(&self) -> &[f32; 12] {
        self.sim.targets()
    }

    /// The PD torques (clamped to the effort limits) at the start of the last physics step, N m.
    pub fn torques(&self) -> &[f32; 12] {
        self.sim.last_torques()
    }

    /// The task perturbation.
    pub fn task(&self) -> &Perturbation {
        &self.task
    }

    /// Changes the task perturbation (takes effect at the next step).
    pub fn set_task(&mut self, task: &Perturbation) {
        self.task = task.clone();
    }

    /// Adds a horizontal velocity change to the trunk now (a push).
    pub fn push(&mut self, dv: [f32; 2]) {
        self.log_intervention(Intervention::Push(dv));
        self.apply_push(dv);
    }

    /// A push, from outside ([`Self::push`]) or from the episode's own schedule.
    fn apply_push(&mut self, dv: [f32; 2]) {
        self.sim.push(dv);
        self.push = dv;
        self.push_age_s = 0.0;
    }

    /// One policy step with `action` (ACT_DIM,).
    pub fn step(&mut self, action: &[f32]) -> anyhow::Result<Step> {
        let cfg = Arc::clone(&self.cfg);
        let c = &*cfg;
        if action.len() != ACT_DIM {
            bail!("env {}: action has {} values, expected {ACT_DIM}", self.env_index, action.len());
        }
        if let Some(i) = action.iter().position(|a| !a.is_finite()) {
            bail!("env {}: action[{i}] is {} at step {}", self.env_index, action[i], self.total_steps);
        }
        self.log_action(action);
        let clip = c.clip_actions;
        let policy_action: [f32; 12] = std::array::from_fn(|i| action[i].clamp(-clip, clip));
        let mut applied = policy_action;
        self.task.apply(&mut applied, c.noise_std, &mut self.rng);
        // Targets stay inside the joint range, so the PD spring never pulls a joint
        // into its limit (rapier's limits only push back once violated).
        let targets: [f32; 12] = std::array::from_fn(|i| {
            let joint = &self.robot.joints[i];
            (self.default_q[i] + c.action_scale * applied[i]).clamp(joint.lower, joint.upper)
        });
        self.sim.set_targets(&targets);

        let prev = self.state;
        for substep in 0..c.decimation {
            self.sim.step().with_context(|| {
                format!(
                    "env {}: physics step {substep} of policy step {} (episode step {}, task {})",
                    self.env_index,
                    self.total_steps + 1,
                    self.episode_step + 1,
                    self.task
                )
            })?;
        }
        let state = self.sim.state();
        self.check_finite(&state)?;
        self.state = state;
        self.total_steps += 1;
        self.episode_step += 1;
        let dt = c.policy_dt();
        self.sim_time += f64::from(dt);
        let pushed = (self.push_age_s == 0.0).then_some(self.push);

        let (trunk_contact, limb, feet) = self.sim.contacts();
        self.foot_contacts = feet;
        let gravity = obs::rotate_into_frame(state.base_quat, [0.0, 0.0, -1.0]);
        let lin_vel = obs::rotate_into_frame(state.base_quat, state.base_lin_vel);
        let ang_vel = obs::rotate_into_frame(state.base_quat, state.base_ang_vel);
        let input = RewardInput {
            base_lin_vel: lin_vel,
            base_ang_vel: ang_vel,
            projected_gravity: gravity,
            command: self.command,
            q: state.q,
            soft_lower: self.soft_lower,
            soft_upper: self.soft_upper,
            torques: *self.sim.last_torques(),
            qdd: std::array::from_fn(|i| (state.qd[i] - prev.qd[i]) / dt),
            base_height: state.base_pos[2],
            foot_height: std::array::from_fn(|f| state.foot_pos[f][2] - self.robot.foot_radius[f]),
            foot_speed_xy: std::array::from_fn(|f| {
                let dx = state.foot_pos[f][0] - prev.foot_pos[f][0];
                let dy = state.foot_pos[f][1] - prev.foot_pos[f][1];
                (dx * dx + dy * dy).sqrt() / dt
            }),
            limb_contacts: limb.iter().sum(),
            action: policy_action,
            last_action: self.last_action,
        };
        let terms = reward::compute(&input, c);
        let step_reward = terms.total();
        self.episode.add(&terms, lin_vel, ang_vel, self.command);

        let tilted = gravity[2] > -c.max_tilt_rad.cos();
        let terminated = trunk_contact || tilted;
        let episode_steps = (c.episode_s / dt).round() as usize;
        let truncated = !terminated && self.episode_step >= episode_steps;
        self.last_action = policy_action;

        // Commands and pushes for the next step.
        let resample_steps = ((c.command_resample_s / dt).round() as usize).max(1);
        if self.episode_step % resample_steps == 0 {
            self.resample_command();
        }
        self.push_age_s += dt;
        if self.push_age_s > PUSH_STATE_HOLD_S {
            self.push = [0.0; 2];
        }
        if c.push_interval_s > 0.0 {
            let push_steps = ((c.push_interval_s / dt).round() as usize).max(1);
            if self.episode_step % push_steps == 0 {
                let m = c.push_max_vel;
                let dv = [self.rng.gen_range(-m..=m), self.rng.gen_range(-m..=m)];
                self.apply_push(dv);
            }
        }

        self.write_observations();
        self.history.copy_within(OBS_DIM.., 0);
        self.history[(HISTORY_LEN - 1) * OBS_DIM..].copy_from_slice(&self.obs);

        let finished =
            (terminated || truncated).then(|| self.episode.summary(self.env_index, self.episode_step, dt, terminated));
        let step = Step { reward: step_reward, terms, terminated, truncated, finished };
        self.notify(Some((&step, pushed)));
        Ok(step)
    }

    fn resample_command(&mut self) {
        let c = &self.cfg;
        self.command =
            [uniform(&mut self.rng, c.cmd_vx), uniform(&mut self.rng, c.cmd_vy), uniform(&mut self.rng, c.cmd_wz)];
    }

    fn write_observations(&mut self) {
        let s = &self.state;
        let input = ObsInput {
            base_ang_vel: obs::rotate_into_frame(s.base_quat, s.base_ang_vel),
            projected_gravity: obs::rotate_into_frame(s.base_quat, [0.0, 0.0, -1.0]),
            command: self.command,
            q_minus_default: std::array::from_fn(|i| s.q[i] - self.default_q[i]),
            qd: s.qd,
            last_action: self.last_action,
            base_lin_vel: obs::rotate_into_frame(s.base_quat, s.base_lin_vel),
            foot_contacts: self.foot_contacts,
            friction: self.params.friction,
            added_mass: self.params.added_mass,
            motor_strength: self.params.motor_strength,
            push: self.push,
        };
        obs::write_obs(&input, &mut self.obs);
        obs::write_priv_obs(&input, &self.obs, &mut self.priv_obs);
    }

    fn check_finite(&self, s: &RawState) -> anyhow::Result<()> {
        match first_non_finite(s) {
            Some((name, i, v)) => Err(anyhow::Error::new(PhysicsBlowUp(format!(
                "env {}: the physics produced a non-finite {name} (component {i} = {v}) at step {} (episode step {}, task {})",
                self.env_index,
                self.total_steps + 1,
                self.episode_step + 1,
                self.task
            )))),
            None => Ok(()),
        }
    }
}
