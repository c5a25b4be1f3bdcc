//! Settings of the simulated robot: physics step, PD control, commands,
//! episode limits, domain randomisation, task perturbation noise and the
//! reward weights of the paper's Table 1 (DESIGN.md, "The environment").
//!
//! Every field has a default; a TOML `[env]` table only names what it changes.

use super::bounds::{self, Interval, NON_NEGATIVE, POSITIVE, POSITIVE_UNIT};
use super::robot::RobotConfig;
use serde::{Deserialize, Serialize};

/// How the velocity-product forces enter a physics step (`env.coriolis`; rapier's
/// `Multibody::set_implicit_coriolis`, a patch of this project: vendor/rapier3d/PATCH.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CoriolisForces {
    /// Forces computed at the step's start; accelerations solved against the plain mass matrix.
    Explicit,
    /// Their velocity derivative times dt added to the accelerations' matrix (rapier's default).
    Implicit,
}

/// The simulated robot, its control, rewards and randomisation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EnvConfig {
    /// Robot description, relative to the crate root (or absolute).
    pub urdf: String,
    /// Physics step in seconds. Chosen by measurement (docs/simulator.md):
    /// with the PD law implicit in rapier's multibody dynamics, 0.01 s stands
    /// and moves like 0.005 s (height, tracking, falls) at twice the speed;
    /// 0.02 s lets feet sink up to 6 cm and changes how the robot falls. In (0, 0.1].
    pub physics_dt: f32,
    /// Physics steps per policy step (1 to 1000); policy rate = 1 / (physics_dt * decimation) = 50 Hz.
    pub decimation: usize,
    /// Constraint-solver iterations per physics step (rapier's `num_solver_iterations`).
    /// The PD motors do not go through the solver (implicit joint springs and
    /// damping), so one iteration (contacts and limits only) is enough; each
    /// extra one costs about as much as the rest of the step. 1 to 100.
    pub solver_iterations: usize,
    /// How the velocity-product forces (Coriolis, centrifugal, gyroscopic) enter a physics
    /// step: `explicit` (MuJoCo's implicitfast treats them so) solves the free accelerations
    /// against the plain mass matrix the contacts use anyway; `implicit` (rapier's own default)
    /// adds their velocity derivative times dt to a second, non-symmetric matrix factorised
    /// every step. Explicit is about 1.4x faster a physics step and walks the same to the
    /// second decimal (docs/simulator.md).
    pub coriolis: CoriolisForces,
    /// Proportional gain of the joint PD motors, N m / rad.
    pub kp: f32,
    /// Derivative gain of the joint PD motors, N m s / rad.
    pub kd: f32,
    /// Joint target = default pose + action_scale * action (> 0).
    pub action_scale: f32,
    /// Actions are clipped to [-clip_actions, clip_actions] before use (> 0).
    pub clip_actions: f32,
    /// Trunk height at reset, metres.
    pub start_height: f32,
    /// Default (standing) joint angles, rad, in the order hip, thigh, calf
    /// for the front-left leg; the other legs mirror it (right hips negated).
    pub default_hip_left: f32,
    /// Default hip angle of the right legs (FR, RR), rad.
    pub default_hip_right: f32,
    /// Default thigh angle of the front legs, rad.
    pub default_thigh_front: f32,
    /// Default thigh angle of the rear legs, rad.
    pub default_thigh_rear: f32,
    /// Default calf angle of every leg, rad.
    pub default_calf: f32,
    /// Episode length, seconds (time-out => truncated): at least one control step, at most 3600.
    pub episode_s: f32,
    /// Commands are resampled every this many seconds.
    pub command_resample_s: f32,
    /// Forward velocity command range, m/s (within [-10, 10], as every command range).
    pub cmd_vx: [f32; 2],
    /// Lateral velocity command range, m/s.
    pub cmd_vy: [f32; 2],
    /// Yaw rate command range, rad/s.
    pub cmd_wz: [f32; 2],
    /// Terminate when the trunk's up axis tilts more than this from vertical, rad, in (0, pi].
    pub max_tilt_rad: f32,
    /// Ground friction coefficient range (uniform), randomised per episode.
    pub friction_range: [f32; 2],
    /// Mass added to the trunk, kg (uniform), randomised per episode.
    pub added_mass_range: [f32; 2],
    /// Motor strength factor (gains and effort limits), randomised per episode.
    pub motor_strength_range: [f32; 2],
    /// Whether friction, added mass and motor strength are randomised at all.
    pub randomize: bool,
    /// A push (a change of the trunk's horizontal velocity) every this many seconds; 0 disables.
    pub push_interval_s: f32,
    /// Largest horizontal velocity change of a push, m/s (uniform per axis).
    pub push_max_vel: f32,
    /// Standard deviation of the Gaussian added to a `noise` leg's actions (action units).
    pub noise_std: f32,
    /// Soft joint limits: this fraction of each joint's range, centred, in (0, 1].
    pub soft_limit_fraction: f32,
    /// Tracking reward width sigma: exp(-err^2 / sigma).
    pub tracking_sigma: f32,
    /// Body height target, metres.
    pub height_target: f32,
    /// Feet clearance target height, metres.
    pub feet_height_target: f32,
    /// Named weights of the Table 1 reward terms (each also times the policy dt; finite).
    pub rewards: RewardWeights,
    /// Per-joint standing pose and gains, leg and foot names, by name pattern
    /// (`[env.robot]`, see [`RobotConfig`]); empty for the A1.
    #[serde(skip_serializing_if = "RobotConfig::is_empty")]
    pub robot: RobotConfig,
}

/// Weights of the paper's Table 1 reward terms. A term's reward is
/// weight * value * policy dt.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RewardWeights {
    /// exp(-|v_xy - v_xy_cmd|^2 / sigma)
    pub lin_vel_tracking: f32,
    /// exp(-(w_z - w_z_cmd)^2 / sigma)
    pub ang_vel_tracking: f32,
    /// v_z^2
    pub lin_vel_z: f32,
    /// |w_xy|^2
    pub ang_vel_xy: f32,
    /// |g_xy|^2 (projected gravity)
    pub orientation: f32,
    /// sum of distances outside the soft joint limits
    pub joint_limits: f32,
    /// |tau|^2
    pub torques: f32,
    /// |qdd|^2
    pub joint_acc: f32,
    /// (h - h_target)^2
    pub body_height: f32,
    /// sum over feet of (p_z - p_target)^2 * |v_foot_xy|
    pub feet_clearance: f32,
    /// count of thigh/calf contacts with the ground
    pub collision: f32,
    /// |a_(t-1) - a_t|^2
    pub action_rate: f32,
}

impl Default for RewardWeights {
    fn default() -> Self {
        Self {
            lin_vel_tracking: 1.0,
            ang_vel_tracking: 0.5,
            lin_vel_z: -2.0,
            ang_vel_xy: -0.05,
            orientation: -5.0,
            joint_limits: -10.0,
            torques: -2e-4,
            joint_acc: -2.5e-7,
            body_height: -30.0,
            feet_clearance: -1.0,
            collision: -1.0,
            action_rate: -0.01,
        }
    }
}

impl Default for EnvConfig {
    fn default() -> Self {
        Self {
            urdf: "scenes/a1.urdf".into(),
            physics_dt: 0.01,
            decimation: 2,
            solver_iterations: 1,
            coriolis: CoriolisForces::Explicit,
            kp: 20.0,
            kd: 0.5,
            action_scale: 0.25,
            clip_actions: 10.0,
            start_height: 0.42,
            default_hip_left: 0.1,
            default_hip_right: -0.1,
            default_thigh_front: 0.8,
            default_thigh_rear: 1.0,
            default_calf: -1.5,
            episode_s: 20.0,
            command_resample_s: 10.0,
            cmd_vx: [-1.0, 1.0],
            cmd_vy: [0.0, 0.0],
            cmd_wz: [-std::f32::consts::FRAC_PI_2, std::f32::consts::FRAC_PI_2],
            max_tilt_rad: 1.0,
            friction_range: [0.5, 1.25],
            added_mass_range: [-1.0, 1.0],
            motor_strength_range: [0.9, 1.1],
            randomize: true,
            push_interval_s: 15.0,
            push_max_vel: 1.0,
            noise_std: 0.5,
            soft_limit_fraction: 0.9,
            tracking_sigma: 0.25,
            height_target: 0.30,
            feet_height_target: 0.08,
            rewards: RewardWeights::default(),
            robot: RobotConfig::default(),
        }
    }
}

/// The largest physics step, seconds: 0.02 s already lets the A1's feet sink
/// up to 6 cm (docs/simulator.md).
pub const MAX_PHYSICS_DT: f32 = 0.1;
/// The most physics steps per policy step.
pub const MAX_DECIMATION: usize = 1000;
/// The most constraint-solver iterations per physics step (each costs about a step).
pub const MAX_SOLVER_ITERATIONS: usize = 100;
/// The longest episode, seconds (an hour; the shipped runs use 20 s).
pub const MAX_EPISODE_S: f32 = 3600.0;
/// The largest command, m/s or rad/s, sampled (`env.cmd_*`) or held (`--vx`,
/// `--vy`, `--wz`): the A1 runs at about 3.5 m/s.
pub const MAX_COMMAND: f32 = 10.0;

/// Checks a commanded velocity or yaw rate (`what` names the key or option).
pub fn check_command(what: &str, value: f32) -> anyhow::Result<()> {
    bounds::check(what, value, Interval::Closed((-MAX_COMMAND).into(), MAX_COMMAND.into()))
}

impl RewardWeights {
    /// Every weight with its key.
    pub fn named(&self) -> [(&'static str, f32); 12] {
        [
            ("lin_vel_tracking", self.lin_vel_tracking),
            ("ang_vel_tracking", self.ang_vel_tracking),
            ("lin_vel_z", self.lin_vel_z),
            ("ang_vel_xy", self.ang_vel_xy),
            ("orientation", self.orientation),
            ("joint_limits", self.joint_limits),
            ("torques", self.torques),
            ("joint_acc", self.joint_acc),
            ("body_height", self.body_height),
            ("feet_clearance", self.feet_clearance),
            ("collision", self.collision),
            ("action_rate", self.action_rate),
        ]
    }
}

impl EnvConfig {
    /// Seconds per policy step (physics_dt * decimation).
    pub fn policy_dt(&self) -> f32 {
        self.physics_dt * self.decimation as f32
    }

    /// Control steps an evaluation runs at most: an episode's length (`episode_s`) in
    /// policy steps, plus a margin of 10 (an env that has not ended by then is an error).
    pub fn evaluation_step_bound(&self) -> usize {
        (f64::from(self.episode_s) / f64::from(self.policy_dt())).ceil() as usize + 10
    }

    /// Checks the values that would make the simulation meaningless; errors name the key.
    pub fn validate(&self) -> anyhow::Result<()> {
        let key = |name: &str| format!("env.{name}");
        bounds::check("env.physics_dt", self.physics_dt, Interval::OpenClosed(0.0, MAX_PHYSICS_DT.into()))?;
        bounds::check_count("env.decimation", self.decimation, 1, MAX_DECIMATION)?;
        bounds::check_count("env.solver_iterations", self.solver_iterations, 1, MAX_SOLVER_ITERATIONS)?;
        bounds::check("env.episode_s", self.episode_s, Interval::OpenClosed(0.0, MAX_EPISODE_S.into()))?;
        anyhow::ensure!(
            self.episode_s >= self.policy_dt(),
            "env.episode_s = {} is shorter than one control step (env.physics_dt * env.decimation = {} s)",
            self.episode_s,
            self.policy_dt()
        );
        let command = Interval::Closed((-MAX_COMMAND).into(), MAX_COMMAND.into());
        for (name, r, interval) in [
            ("cmd_vx", self.cmd_vx, command),
            ("cmd_vy", self.cmd_vy, command),
            ("cmd_wz", self.cmd_wz, command),
            ("friction_range", self.friction_range, NON_NEGATIVE),
            ("added_mass_range", self.added_mass_range, Interval::Finite),
            // A factor on the motors' gains: 0 or less leaves the legs limp.
            ("motor_strength_range", self.motor_strength_range, POSITIVE),
        ] {
            bounds::check_range(&key(name), r, interval)?;
        }
        for (name, v, interval) in [
            ("kp", self.kp, POSITIVE),
            ("kd", self.kd, NON_NEGATIVE),
            // 0 makes every action the default pose: nothing a policy does moves the robot.
            ("action_scale", self.action_scale, POSITIVE),
            ("clip_actions", self.clip_actions, POSITIVE),
            ("start_height", self.start_height, POSITIVE),
            ("command_resample_s", self.command_resample_s, NON_NEGATIVE),
            ("max_tilt_rad", self.max_tilt_rad, Interval::OpenClosed(0.0, std::f64::consts::PI)),
            ("push_interval_s", self.push_interval_s, NON_NEGATIVE),
            ("push_max_vel", self.push_max_vel, NON_NEGATIVE),
            ("noise_std", self.noise_std, NON_NEGATIVE),
            ("soft_limit_fraction", self.soft_limit_fraction, POSITIVE_UNIT),
            ("tracking_sigma", self.tracking_sigma, POSITIVE),
            ("height_target", self.height_target, POSITIVE),
            ("feet_height_target", self.feet_height_target, NON_NEGATIVE),
            ("default_hip_left", self.default_hip_left, Interval::Finite),
            ("default_hip_right", self.default_hip_right, Interval::Finite),
            ("default_thigh_front", self.default_thigh_front, Interval::Finite),
            ("default_thigh_rear", self.default_thigh_rear, Interval::Finite),
            ("default_calf", self.default_calf, Interval::Finite),
        ] {
            bounds::check(&key(name), v, interval)?;
        }
        for (name, w) in self.rewards.named() {
            bounds::check(&key(&format!("rewards.{name}")), w, Interval::Finite)?;
        }
        self.robot.validate()?;
        if !self.robot.default_pose.is_empty() {
            let d = Self::default();
            let legacy = [
                ("default_hip_left", self.default_hip_left, d.default_hip_left),
                ("default_hip_right", self.default_hip_right, d.default_hip_right),
                ("default_thigh_front", self.default_thigh_front, d.default_thigh_front),
                ("default_thigh_rear", self.default_thigh_rear, d.default_thigh_rear),
                ("default_calf", self.default_calf, d.default_calf),
            ];
            if let Some((name, _, _)) = legacy.iter().find(|(_, v, default)| v != default) {
                anyhow::bail!("env.{name} and env.robot.default_pose both set the standing pose; keep one");
            }
        }
        Ok(())
    }
}
