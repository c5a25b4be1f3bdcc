//! Physics accuracy for `quadcl bench --only accuracy`: what the step's size costs in
//! exactness. One A1 env at the default step (0.01 s x 2) and at MuJoCo's reference step
//! (0.005 s x 4) is driven by the same actions from the same resets, for a fixed number of
//! control steps (the figures do not depend on `--seconds`, nor on the machine's load):
//!
//! - `stand`: zero actions (the default pose), and `trot`: `quadcl bench --only env`'s 2 Hz
//!   trot plus noise. Mean trunk height (m) and mean |joint position - PD target| (rad).
//! - `violent`: a fresh uniform action in [-4, 4] every control step (targets swing by up to
//!   1 rad and are clamped to the joint limits). The deepest foot sink below the ground (foot
//!   radius minus the foot centre's height, m) and the largest overshoot past a joint limit
//!   (rad), each the median over 25 runs of the run's maximum; the robot falls, and episodes
//!   restart when they end.
//!
//! Keys: `accuracy_{stand,trot}_{trunk_height_m,joint_err_rad}_{dt001x2,dt0005x4}` and
//! `accuracy_violent_{foot_sink_m,limit_overshoot_rad}_{dt001x2,dt0005x4}`, plus
//! `accuracy_control_steps` (per run and step).

use quadcl::config::EnvConfig;
use quadcl::sim::{LocomotionEnv, Perturbation, RobotModel, ACT_DIM, NUM_LEGS};
use rand::{Rng, SeedableRng};
use serde_json::json;

/// Control steps per scenario and step size: 20 s of simulated time.
const CONTROL_STEPS: usize = 1000;
/// Runs of the violent scenario (seeds 0..), each `CONTROL_STEPS` long.
const VIOLENT_SEEDS: u64 = 25;

/// What one scenario measured.
#[derive(Default)]
struct Figures {
    trunk_height_sum: f64,
    joint_err_sum: f64,
    samples: usize,
    foot_sink_max: f32,
    overshoot_max: f32,
}

/// Drives one env with `action(step)` and collects the figures after every control step.
fn drive(
    cfg: &EnvConfig,
    robot: &RobotModel,
    seed: u64,
    mut action: impl FnMut(usize) -> [f32; ACT_DIM],
) -> anyhow::Result<Figures> {
    let mut env = LocomotionEnv::new(cfg, robot, &Perturbation::none())?;
    env.reset(seed)?;
    let mut f = Figures::default();
    for k in 0..CONTROL_STEPS {
        let step = env.step(&action(k))?;
        let state = env.raw_state();
        let targets = env.targets();
        f.trunk_height_sum += state.base_pos[2] as f64;
        for (j, joint) in robot.joints.iter().enumerate() {
            f.joint_err_sum += (state.q[j] - targets[j]).abs() as f64 / ACT_DIM as f64;
            let past = (state.q[j] - joint.upper).max(joint.lower - state.q[j]);
            f.overshoot_max = f.overshoot_max.max(past);
        }
        for leg in 0..NUM_LEGS {
            f.foot_sink_max = f.foot_sink_max.max(robot.foot_radius[leg] - state.foot_pos[leg][2]);
        }
        f.samples += 1;
        if step.terminated || step.truncated {
            env.reset_episode()?;
        }
    }
    Ok(f)
}

/// Adds the accuracy figures to `report`.
pub fn measure(report: &mut serde_json::Map<String, serde_json::Value>) -> anyhow::Result<()> {
    let default = EnvConfig::default();
    let robot = RobotModel::for_config(&default)?;
    let reference = EnvConfig { physics_dt: 0.005, decimation: 4, ..default.clone() };
    for (label, cfg) in [("dt001x2", &default), ("dt0005x4", &reference)] {
        let trot = crate::bench::env::gait_actions(cfg.policy_dt());
        let stand = drive(cfg, &robot, 7, |_| [0.0; ACT_DIM])?;
        let trotting = drive(cfg, &robot, 7, |k| {
            let row = k % (trot.len() / ACT_DIM);
            std::array::from_fn(|j| trot[row * ACT_DIM + j])
        })?;
        // Violent actions make chaotic trajectories: a maximum over one run is noisy, so the
        // median over VIOLENT_SEEDS runs of each run's maximum.
        let mut sinks = Vec::new();
        let mut overshoots = Vec::new();
        for seed in 0..VIOLENT_SEEDS {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let f = drive(cfg, &robot, seed, |_| std::array::from_fn(|_| rng.gen_range(-4.0f32..4.0)))?;
            sinks.push(f.foot_sink_max.max(0.0));
            overshoots.push(f.overshoot_max.max(0.0));
        }
        for (name, f) in [("stand", &stand), ("trot", &trotting)] {
            let n = f.samples as f64;
            report.insert(format!("accuracy_{name}_trunk_height_m_{label}"), json!(round(f.trunk_height_sum / n, 4)));
            report.insert(format!("accuracy_{name}_joint_err_rad_{label}"), json!(round(f.joint_err_sum / n, 4)));
        }
        report.insert(format!("accuracy_violent_foot_sink_m_{label}"), json!(round(median(&mut sinks), 4)));
        report
            .insert(format!("accuracy_violent_limit_overshoot_rad_{label}"), json!(round(median(&mut overshoots), 4)));
    }
    report.insert("accuracy_control_steps".into(), json!(CONTROL_STEPS));
    Ok(())
}

fn median(values: &mut [f32]) -> f64 {
    values.sort_by(f32::total_cmp);
    values[values.len() / 2] as f64
}

fn round(x: f64, digits: i32) -> f64 {
    let scale = 10f64.powi(digits);
    (x * scale).round() / scale
}
