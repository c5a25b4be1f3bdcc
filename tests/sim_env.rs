//! The physics and the environment: standing still, perturbations reaching
//! exactly the legs they name, falling, and thread-count independence.

use quadcl::config::{CoriolisForces, EnvConfig};
use quadcl::sim::*;
use rand::{Rng, SeedableRng};

/// No randomisation, no pushes: the physics alone.
fn quiet_config() -> EnvConfig {
    EnvConfig { randomize: false, push_interval_s: 0.0, ..EnvConfig::default() }
}

fn robot() -> RobotModel {
    RobotModel::a1().unwrap()
}

#[test]
fn zero_action_stands_at_a_stable_trunk_height_for_ten_seconds() {
    let cfg = EnvConfig { episode_s: 30.0, ..quiet_config() };
    let mut env = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    let steps = (10.0 / cfg.policy_dt()).round() as usize;
    let mut heights = Vec::new();
    for k in 0..steps {
        let step = env.step(&[0.0; ACT_DIM]).unwrap();
        assert!(!step.terminated && !step.truncated, "ended at step {k}");
        assert!(env.observation().iter().chain(env.privileged_observation()).all(|v| v.is_finite()));
        heights.push(env.raw_state().base_pos[2]);
    }
    // After settling (2 s), the trunk stays within 1 cm, at a standing height.
    let settled = &heights[(2.0 / cfg.policy_dt()) as usize..];
    let (lo, hi) = settled.iter().fold((f32::MAX, f32::MIN), |(lo, hi), &h| (lo.min(h), hi.max(h)));
    assert!(hi - lo < 0.01, "trunk height wanders from {lo} to {hi}");
    assert!(lo > 0.22 && hi < 0.34, "standing height {lo}..{hi}");
    // Upright: projected gravity close to (0, 0, -1).
    assert!(env.observation()[5] < -0.99, "gravity {:?}", &env.observation()[3..6]);
    // On its four feet, nothing else touching.
    let contacts = &env.privileged_observation()[obs::PRIV_FOOT_CONTACTS..obs::PRIV_FOOT_CONTACTS + 4];
    assert_eq!(contacts, [1.0; 4]);
}

#[test]
fn coriolis_setting_reaches_the_physics_and_both_treatments_trot_alike() {
    // The same trot-like actions under explicit (default) and semi-implicit velocity-product
    // forces: different numbers (the setting reaches rapier), the same motion to a centimetre.
    let mut heights = Vec::new();
    for coriolis in [CoriolisForces::Explicit, CoriolisForces::Implicit] {
        let cfg = EnvConfig { coriolis, ..quiet_config() };
        let mut env = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
        let mut trace = Vec::new();
        for k in 0..100 {
            let phase = (k as f32 * cfg.policy_dt() * 2.0 * std::f32::consts::TAU).sin();
            let action: Vec<f32> = (0..ACT_DIM)
                .map(|j| {
                    if j % 3 == 0 {
                        0.0
                    } else if j / 3 == 0 || j / 3 == 3 {
                        phase
                    } else {
                        -phase
                    }
                })
                .collect();
            let step = env.step(&action).unwrap();
            assert!(!step.terminated, "{coriolis:?}: fell at step {k}");
            trace.push(env.raw_state().base_pos[2]);
        }
        heights.push(trace);
    }
    assert_ne!(heights[0], heights[1], "the setting changed nothing");
    let gap = heights[0].iter().zip(&heights[1]).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(gap < 0.01, "trunk heights part by {gap} m");
}

#[test]
fn commands_are_resampled_every_ten_seconds_within_their_ranges() {
    let cfg = quiet_config();
    let mut env = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    let per_resample = (cfg.command_resample_s / cfg.policy_dt()).round() as usize;
    let first = env.command();
    for k in 1..=per_resample {
        env.step(&[0.0; ACT_DIM]).unwrap();
        if k < per_resample {
            assert_eq!(env.command(), first, "changed at step {k}");
        }
    }
    let second = env.command();
    assert_ne!(second, first);
    for c in [first, second] {
        assert!((-1.0..=1.0).contains(&c[0]) && c[1] == 0.0 && c[2].abs() <= std::f32::consts::FRAC_PI_2, "{c:?}");
    }
    // The observation carries the scaled command.
    assert_eq!(env.observation()[6], second[0] * 2.0);
}

/// One step with the same action on every joint; returns (targets - default) / action_scale.
fn target_offsets(task: &str, action: f32, cfg: &EnvConfig) -> Vec<f32> {
    let mut env = LocomotionEnv::new(cfg, &robot(), &task.parse().unwrap()).unwrap();
    env.step(&[action; ACT_DIM]).unwrap();
    env.targets().iter().zip(env.default_pose()).map(|(t, d)| (t - d) / cfg.action_scale).collect()
}

fn leg_offsets(offsets: &[f32], leg: Leg) -> &[f32] {
    &offsets[3 * leg.index()..3 * leg.index() + 3]
}

#[test]
fn crash_holds_the_default_pose_of_exactly_the_named_leg() {
    let cfg = quiet_config();
    let offsets = target_offsets("crash:FR", 0.4, &cfg);
    for leg in Leg::ALL {
        let expected = if leg == Leg::FR { 0.0 } else { 0.4 };
        for &o in leg_offsets(&offsets, leg) {
            assert!((o - expected).abs() < 1e-6, "{leg:?}: {offsets:?}");
        }
    }
    // Physically: the crashed robot moves exactly like an unperturbed one whose
    // policy sends zero to that leg.
    let mut crashed = LocomotionEnv::new(&cfg, &robot(), &"crash:FR".parse().unwrap()).unwrap();
    let mut plain = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    for _ in 0..25 {
        let action: Vec<f32> = (0..ACT_DIM).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let mut zeroed = action.clone();
        zeroed[3..6].fill(0.0);
        crashed.step(&action).unwrap();
        plain.step(&zeroed).unwrap();
        assert_eq!(crashed.raw_state().q, plain.raw_state().q);
    }
}

#[test]
fn invert_mirrors_the_target_offset_of_exactly_the_named_legs() {
    let offsets = target_offsets("invert:RR+invert:FL", 0.4, &quiet_config());
    for leg in Leg::ALL {
        let expected = if matches!(leg, Leg::RR | Leg::FL) { -0.4 } else { 0.4 };
        for &o in leg_offsets(&offsets, leg) {
            assert!((o - expected).abs() < 1e-6, "{leg:?}: {offsets:?}");
        }
    }
}

#[test]
fn noise_has_the_configured_std_on_exactly_the_named_leg() {
    let cfg = EnvConfig { noise_std: 0.3, ..quiet_config() };
    let mut env = LocomotionEnv::new(&cfg, &robot(), &"noise:RL".parse().unwrap()).unwrap();
    let mut samples = Vec::new();
    for _ in 0..200 {
        env.step(&[0.1; ACT_DIM]).unwrap();
        let offsets: Vec<f32> =
            env.targets().iter().zip(env.default_pose()).map(|(t, d)| (t - d) / cfg.action_scale).collect();
        for leg in Leg::ALL {
            for &o in leg_offsets(&offsets, leg) {
                if leg == Leg::RL {
                    samples.push(o - 0.1);
                } else {
                    assert!((o - 0.1).abs() < 1e-6, "{leg:?} moved: {offsets:?}");
                }
            }
        }
    }
    let n = samples.len() as f32;
    let mean = samples.iter().sum::<f32>() / n;
    let std = (samples.iter().map(|s| (s - mean).powi(2)).sum::<f32>() / n).sqrt();
    assert!(mean.abs() < 0.05, "noise mean {mean}");
    assert!((std - 0.3).abs() < 0.03, "noise std {std}, configured 0.3");
}

#[test]
fn a_robot_pushed_over_terminates_as_fallen() {
    let cfg = quiet_config();
    let mut env = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    for _ in 0..25 {
        env.step(&[0.0; ACT_DIM]).unwrap();
    }
    env.push([0.0, 4.0]);
    let mut ended = None;
    for k in 0..100 {
        let step = env.step(&[0.0; ACT_DIM]).unwrap();
        if step.terminated || step.truncated {
            ended = Some((k, step));
            break;
        }
    }
    let (k, step) = ended.expect("a 4 m/s sideways push knocks the robot over within 2 s");
    assert!(step.terminated && !step.truncated, "at step {k}: {step:?}");
    let summary = step.finished.unwrap();
    assert!(summary.fell && summary.length_s < 2.0, "{summary:?}");
}

#[test]
fn an_episode_times_out_as_truncated_not_terminated() {
    let cfg = EnvConfig { episode_s: 0.5, ..quiet_config() };
    let mut env = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    let steps = (0.5 / cfg.policy_dt()).round() as usize;
    for k in 1..=steps {
        let step = env.step(&[0.0; ACT_DIM]).unwrap();
        assert_eq!(step.truncated, k == steps, "step {k}");
        assert!(!step.terminated);
    }
}

#[test]
fn a_non_finite_action_is_an_error_naming_the_env_and_step() {
    let mut env = LocomotionEnv::new(&quiet_config(), &robot(), &Perturbation::none()).unwrap();
    let mut action = [0.0; ACT_DIM];
    action[4] = f32::NAN;
    let err = format!("{:#}", env.step(&action).unwrap_err());
    assert!(err.contains("env 0") && err.contains("action[4]") && err.contains("step 0"), "{err}");
}

fn run_batch(threads: usize, on_calling_thread: bool) -> (Vec<u32>, Vec<u32>, usize) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        // Short episodes so auto-resets (and their randomisation) happen too.
        let cfg = EnvConfig { episode_s: 0.4, push_interval_s: 0.2, ..EnvConfig::default() };
        let task: Perturbation = "noise:FL+invert:RR".parse().unwrap();
        let mut envs = VecEnv::new(&cfg, &robot(), &task, 4, 42).unwrap();
        envs.set_on_calling_thread(on_calling_thread);
        envs.reset(43).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let mut rewards = Vec::new();
        let mut finished = 0;
        for _ in 0..30 {
            let actions: Vec<f32> = (0..4 * ACT_DIM).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let step = envs.step(&actions).unwrap();
            rewards.extend(step.reward.iter().map(|r| r.to_bits()));
            finished += step.finished.len();
        }
        let obs = envs.observations().iter().chain(envs.privileged_observations()).chain(envs.obs_histories());
        (rewards, obs.map(|v| v.to_bits()).collect(), finished)
    })
}

/// Two runs of `run_batch` that must give the same numbers, episodes having ended in them.
fn assert_same_batch_runs(a: (Vec<u32>, Vec<u32>, usize), b: (Vec<u32>, Vec<u32>, usize)) {
    let ((r1, o1, f1), (r2, o2, f2)) = (a, b);
    assert!(f1 >= 4, "episodes should have ended and auto-reset ({f1})");
    assert_eq!(f1, f2);
    assert_eq!(r1, r2, "rewards differ");
    assert_eq!(o1, o2, "observations differ");
}

#[test]
fn same_seed_is_bit_identical_with_one_and_two_threads() {
    assert_same_batch_runs(run_batch(1, false), run_batch(2, false));
}

#[test]
fn a_batch_on_the_calling_thread_gives_the_pools_numbers() {
    assert_same_batch_runs(run_batch(2, false), run_batch(2, true));
}

#[test]
fn different_envs_in_a_batch_get_different_randomisation() {
    let envs = VecEnv::new(&EnvConfig::default(), &robot(), &Perturbation::none(), 3, 1).unwrap();
    let p: Vec<_> = envs.envs().iter().map(|e| e.physics_params()).collect();
    assert!(p[0].friction != p[1].friction && p[1].friction != p[2].friction, "{p:?}");
    for q in &p {
        assert!((0.5..1.25).contains(&q.friction), "{q:?}");
        assert!((-1.0..1.0).contains(&q.added_mass), "{q:?}");
        assert!((0.9..1.1).contains(&q.motor_strength), "{q:?}");
    }
    // The critic sees them.
    let row = &envs.privileged_observations()[obs::PRIV_PHYSICS..obs::PRIV_PHYSICS + 3];
    assert_eq!(row, [p[0].friction, p[0].added_mass, p[0].motor_strength]);
}

#[test]
fn joint_limits_and_effort_limits_from_the_urdf_hold() {
    let cfg = quiet_config();
    let robot = robot();
    let mut env = LocomotionEnv::new(&cfg, &robot, &Perturbation::none()).unwrap();
    // Drive every calf far past its upper limit (-0.916 rad) and every thigh far back.
    let mut action = [0.0; ACT_DIM];
    for leg in 0..4 {
        action[3 * leg + 1] = -cfg.clip_actions;
        action[3 * leg + 2] = cfg.clip_actions;
    }
    let mut saturated = false;
    for k in 0..50 {
        if k == 25 {
            // Then swing the thighs from their lower limit to far forward: a
            // 4 rad error asks for about 87 N m, more than the 55 N m effort limit.
            for leg in 0..4 {
                action[3 * leg + 1] = cfg.clip_actions;
            }
        }
        env.step(&action).unwrap();
        // Limits push back once violated, held at the end. At impacts (one solver
        // iteration) a joint slams a few hundredths of a radian past its limit, and
        // the largest single impact is a chaotic maximum: 0.075 rad here with
        // semi-implicit Coriolis forces, 0.115 rad with explicit ones (the default),
        // while the median over 25 violent runs is 0.04-0.06 rad in both
        // (`quadcl bench --only accuracy`).
        let tolerance = if k < 49 { 0.15 } else { 0.03 };
        for (i, joint) in robot.joints.iter().enumerate() {
            let q = env.raw_state().q[i];
            assert!(
                q >= joint.lower - tolerance && q <= joint.upper + tolerance,
                "step {k}: {} at {q}, limits {}..{}",
                joint.name,
                joint.lower,
                joint.upper
            );
            let tau = env.torques()[i];
            assert!(tau.abs() <= joint.effort + 1e-4, "{} torque {tau} above effort {}", joint.name, joint.effort);
            saturated |= (tau.abs() - joint.effort).abs() < 1e-4;
        }
    }
    assert!(saturated, "the thigh swing should saturate some motor");
}

#[test]
fn non_finite_physics_is_an_error_naming_the_env_step_and_quantity() {
    let mut env = LocomotionEnv::new(&quiet_config(), &robot(), &Perturbation::none()).unwrap();
    env.step(&[0.0; ACT_DIM]).unwrap();
    env.push([f32::NAN, 0.0]);
    let err = format!("{:#}", env.step(&[0.0; ACT_DIM]).unwrap_err());
    assert!(err.contains("env 0") && err.contains("step 2"), "{err}");
    assert!(err.contains("non-finite") || err.contains("rapier failed"), "{err}");
}

#[test]
fn a_meaningless_config_is_an_error_not_a_panic() {
    let cfg = EnvConfig { kd: f32::INFINITY, ..quiet_config() };
    let err = format!("{:#}", LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).err().unwrap());
    assert!(err.contains("env.kd"), "{err}");
}

#[test]
fn observations_carry_the_documented_quantities_and_scales_and_the_history_the_last_five() {
    let cfg = quiet_config();
    let mut env = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let mut seen = vec![env.observation().to_vec()];
    for _ in 0..7 {
        let action: Vec<f32> = (0..ACT_DIM).map(|_| rng.gen_range(-1.5..1.5)).collect();
        env.step(&action).unwrap();
        seen.push(env.observation().to_vec());
        let (o, p, s) = (env.observation(), env.privileged_observation(), *env.raw_state());
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * (1.0 + b.abs());
        let ang = obs::rotate_into_frame(s.base_quat, s.base_ang_vel);
        let lin = obs::rotate_into_frame(s.base_quat, s.base_lin_vel);
        let g = obs::rotate_into_frame(s.base_quat, [0.0, 0.0, -1.0]);
        let c = env.command();
        for k in 0..3 {
            assert!(close(o[k], 0.25 * ang[k]) && close(o[3 + k], g[k]), "angular velocity / gravity {k}");
            assert!(close(o[6 + k], [2.0, 2.0, 0.25][k] * c[k]), "command {k}");
            assert!(close(p[obs::PRIV_BASE_LIN_VEL + k], 2.0 * lin[k]), "linear velocity {k}");
        }
        for j in 0..12 {
            assert!(close(o[9 + j], s.q[j] - env.default_pose()[j]), "joint position {j}");
            assert!(close(o[21 + j], 0.05 * s.qd[j]), "joint velocity {j}");
            assert!(close(o[33 + j], action[j]), "previous action {j}");
        }
        assert!(close(g.iter().map(|v| v * v).sum::<f32>(), 1.0), "gravity is a unit vector");
    }
    // The history holds the last five observations, oldest first.
    let want: Vec<f32> = seen[seen.len() - HISTORY_LEN..].concat();
    assert_eq!(env.obs_history(), &want[..]);
}

#[test]
fn a_set_command_shows_in_the_newest_history_entry_too() {
    let mut env = LocomotionEnv::new(&quiet_config(), &robot(), &Perturbation::none()).unwrap();
    // Right after a reset the history is five copies of the first observation, with the new command.
    env.set_command([0.5, 0.0, 0.2]);
    for k in 0..HISTORY_LEN {
        assert_eq!(&env.obs_history()[k * OBS_DIM..(k + 1) * OBS_DIM], env.observation(), "entry {k} after reset");
    }
    for _ in 0..3 {
        env.step(&[0.0; ACT_DIM]).unwrap();
    }
    let older = env.obs_history()[..(HISTORY_LEN - 1) * OBS_DIM].to_vec();
    env.set_command([-0.5, 0.0, 0.0]);
    assert_eq!(&env.obs_history()[(HISTORY_LEN - 1) * OBS_DIM..], env.observation());
    assert_eq!(&env.obs_history()[..(HISTORY_LEN - 1) * OBS_DIM], &older[..], "older entries are what was observed");
}

#[test]
fn config_values_that_would_panic_later_are_errors_naming_the_key() {
    let cases = [
        ("push_max_vel", EnvConfig { push_max_vel: -1.0, push_interval_s: 0.02, ..EnvConfig::default() }),
        ("friction_range", EnvConfig { friction_range: [0.5, f32::INFINITY], ..EnvConfig::default() }),
        ("tracking_sigma", EnvConfig { tracking_sigma: 0.0, ..EnvConfig::default() }),
        ("soft_limit_fraction", EnvConfig { soft_limit_fraction: f32::NAN, ..EnvConfig::default() }),
        ("push_interval_s", EnvConfig { push_interval_s: f32::NAN, ..EnvConfig::default() }),
        ("added_mass", EnvConfig { added_mass_range: [-10.0, -10.0], ..EnvConfig::default() }),
    ];
    for (key, cfg) in cases {
        let result =
            LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).and_then(|mut env| env.step(&[0.0; ACT_DIM]));
        let err = format!("{:#}", result.err().unwrap_or_else(|| panic!("{key}: accepted")));
        assert!(err.contains(key), "{key}: {err}");
    }
}

/// The collision term's value in a step (0 when no thigh or calf touches).
fn collision_term(step: &Step) -> f32 {
    let k = reward::TERM_NAMES.iter().position(|&n| n == "collision").expect("a collision term");
    step.terms.values[k]
}

/// Regression: rapier's `has_any_active_contact` also counts speculative
/// contacts (within the prediction distance, zero impulse), so the rear calves'
/// lower ends hovering ~2 cm above the ground counted as thigh/calf collisions
/// about 2.4 times a step under small random actions (from step 240 of this
/// sequence on). 300 steps: under these actions the rear legs slowly fold into
/// a crouch (rear knees near -2 rad) in which, from about step 310, the rear
/// calves do press on the ground for real.
#[test]
fn small_random_actions_while_standing_touch_the_ground_only_with_feet() {
    let cfg = quiet_config();
    let mut env = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let normal = rand_distr::Normal::new(0.0f32, 0.3).unwrap();
    for k in 0..300 {
        let a: Vec<f32> = (0..ACT_DIM).map(|_| rng.sample(normal)).collect();
        let step = env.step(&a).unwrap();
        assert_eq!(collision_term(&step), 0.0, "step {k}: a thigh or calf counted as touching while standing");
        assert!(!step.terminated, "step {k}: fell under small random actions");
    }

    // Knocked onto its side (tilt termination off, so only a trunk contact
    // ends the episode), the robot's legs or trunk do touch the ground.
    let cfg = EnvConfig { max_tilt_rad: 3.0, ..quiet_config() };
    let mut env = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    for _ in 0..25 {
        env.step(&[0.0; ACT_DIM]).unwrap();
    }
    env.push([0.0, 4.0]);
    let mut limb_touched = false;
    let mut trunk_touched = false;
    for _ in 0..150 {
        let step = env.step(&[0.0; ACT_DIM]).unwrap();
        limb_touched |= collision_term(&step) < 0.0;
        if step.terminated {
            trunk_touched = true;
            break;
        }
    }
    assert!(limb_touched || trunk_touched, "a robot knocked onto its side registers no thigh/calf or trunk contact");
}
