//! Environment throughput for `quadcl bench`: control (policy) steps per
//! second of the default A1 env, one env on one thread and a batch of 64 on
//! all rayon threads. Actions are a trotting-like sine on thighs and calves
//! plus noise (walking-like contacts, not a robot standing still); episodes
//! reset as they end, and the resets are part of the time.
//!
//! Keys: `env_control_steps_per_s_1t`, `env_control_steps_per_s_all`,
//! `env_batch`, `threads`, `physics_dt`, `decimation`, `solver_iterations`,
//! `coriolis`, `env_physics_steps_per_s_1t`, `env_control_steps_per_s_1t_dt0005_x4`
//! (one env at MuJoCo's reference step 0.005 s x 4, to compare like with like) and
//! `env_control_steps_per_s_1t_implicit_coriolis` (one env with `env.coriolis = "implicit"`).

use quadcl::config::{CoriolisForces, EnvConfig};
use quadcl::sim::{LocomotionEnv, Perturbation, RobotModel, VecEnv, ACT_DIM};
use rand::{Rng, SeedableRng};
use serde_json::json;
use std::time::Instant;

/// Envs in the all-threads batch.
const BATCH: usize = 64;
/// Distinct action rows cycled through (precomputed so drawing them costs nothing).
const ACTION_ROWS: usize = 256;

/// Walking-like actions: (ACTION_ROWS, ACT_DIM), 2 Hz trot at 50 Hz plus noise.
pub(crate) fn gait_actions(policy_dt: f32) -> Vec<f32> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let mut out = Vec::with_capacity(ACTION_ROWS * ACT_DIM);
    for k in 0..ACTION_ROWS {
        let phase = k as f32 * policy_dt * 2.0 * std::f32::consts::TAU;
        for j in 0..ACT_DIM {
            let leg = j / 3;
            let diagonal = if leg == 0 || leg == 3 { 1.0 } else { -1.0 };
            let swing = if j % 3 == 0 { 0.0 } else { diagonal * phase.sin() };
            out.push(swing + 0.3 * rng.gen_range(-1.0f32..1.0));
        }
    }
    out
}

/// Control steps per second of one env on this thread for `seconds`.
fn one_env_rate(cfg: &EnvConfig, robot: &RobotModel, actions: &[f32], seconds: f64) -> anyhow::Result<f64> {
    let mut env = LocomotionEnv::new(cfg, robot, &Perturbation::none())?;
    let start = Instant::now();
    let mut steps = 0usize;
    while start.elapsed().as_secs_f64() < seconds {
        for _ in 0..50 {
            let row = steps % ACTION_ROWS;
            let step = env.step(&actions[row * ACT_DIM..(row + 1) * ACT_DIM])?;
            if step.terminated || step.truncated {
                env.reset_episode()?;
            }
            steps += 1;
        }
    }
    Ok(steps as f64 / start.elapsed().as_secs_f64())
}

/// Control steps per second (envs x steps) of a batch of `n` envs for `seconds`, each env
/// on its own row of the gait actions (env i at row step + 7 i).
fn batch_rate(
    cfg: &EnvConfig,
    robot: &RobotModel,
    task: &Perturbation,
    actions: &[f32],
    n: usize,
    seconds: f64,
) -> anyhow::Result<f64> {
    let mut batch = VecEnv::new(cfg, robot, task, n, 1)?;
    let mut batch_actions = vec![0.0f32; n * ACT_DIM];
    let start = Instant::now();
    let mut batch_steps = 0usize;
    while start.elapsed().as_secs_f64() < seconds {
        for (i, row) in batch_actions.chunks_mut(ACT_DIM).enumerate() {
            let r = (batch_steps + 7 * i) % ACTION_ROWS;
            row.copy_from_slice(&actions[r * ACT_DIM..(r + 1) * ACT_DIM]);
        }
        batch.step(&batch_actions)?;
        batch_steps += 1;
    }
    Ok((batch_steps * n) as f64 / start.elapsed().as_secs_f64())
}

/// Adds the environment figures to `report`.
pub fn measure(seconds: f64, report: &mut serde_json::Map<String, serde_json::Value>) -> anyhow::Result<()> {
    let cfg = EnvConfig::default();
    let robot = RobotModel::for_config(&cfg)?;
    let task = Perturbation::none();
    let actions = gait_actions(cfg.policy_dt());

    let one = one_env_rate(&cfg, &robot, &actions, seconds)?;
    // The same at MuJoCo's reference setting (0.005 s x 4), for the ratio in docs/simulator.md.
    let reference = EnvConfig { physics_dt: 0.005, decimation: 4, ..cfg.clone() };
    let one_reference = one_env_rate(&reference, &robot, &actions, seconds)?;
    // The same with semi-implicit velocity-product forces (rapier's default), for the patch's figures.
    let implicit = EnvConfig { coriolis: CoriolisForces::Implicit, ..cfg.clone() };
    let one_implicit = one_env_rate(&implicit, &robot, &actions, seconds)?;

    // A batch on all threads.
    let all = batch_rate(&cfg, &robot, &task, &actions, BATCH, seconds)?;
    // The Python package's reference (issue 40): 128 envs, the batch the learner steps, on one thread.
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let batch128_1t = one_thread.install(|| batch_rate(&cfg, &robot, &task, &actions, 128, seconds))?;

    report.insert("env_control_steps_per_s_1t".into(), json!(one.round()));
    report.insert("env_control_steps_per_s_all".into(), json!(all.round()));
    report.insert("env_physics_steps_per_s_1t".into(), json!((one * cfg.decimation as f64).round()));
    report.insert("env_control_steps_per_s_1t_dt0005_x4".into(), json!(one_reference.round()));
    report.insert("env_control_steps_per_s_1t_implicit_coriolis".into(), json!(one_implicit.round()));
    report.insert("env_batch".into(), json!(BATCH));
    report.insert("env_control_steps_per_s_batch128_1t".into(), json!(batch128_1t.round()));
    report.insert("threads".into(), json!(rayon::current_num_threads()));
    report.insert("physics_dt".into(), json!((cfg.physics_dt as f64 * 1e6).round() / 1e6));
    report.insert("decimation".into(), json!(cfg.decimation));
    report.insert("solver_iterations".into(), json!(cfg.solver_iterations));
    report.insert("coriolis".into(), json!(cfg.coriolis));
    Ok(())
}
