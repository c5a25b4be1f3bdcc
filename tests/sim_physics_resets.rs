//! A physics blow-up costs one episode, not the run: the env whose state went
//! non-finite is reset and counted, the others step on untouched, and
//! training stops only when blow-ups exceed `ppo.max_physics_reset_rate`.

use quadcl::config::EnvConfig;
use quadcl::sim::{LocomotionEnv, Perturbation, PhysicsBlowUp, RobotModel, VecEnv, ACT_DIM, OBS_DIM};

fn cfg() -> EnvConfig {
    EnvConfig { push_interval_s: 0.0, ..EnvConfig::default() }
}

#[test]
fn a_state_gone_non_finite_is_a_physics_blow_up_naming_the_env() {
    let robot = RobotModel::a1().unwrap();
    let mut env = LocomotionEnv::new(&cfg(), &robot, &Perturbation::none()).unwrap();
    env.step(&[0.0; ACT_DIM]).unwrap();
    env.push([f32::INFINITY, 0.0]);
    let err = env.step(&[0.0; ACT_DIM]).unwrap_err();
    let blow_up = err.downcast_ref::<PhysicsBlowUp>().unwrap_or_else(|| panic!("not a blow-up: {err:#}"));
    assert!(blow_up.0.contains("env 0") && blow_up.0.contains("non-finite"), "{blow_up}");
    // Reset, the env is whole again.
    env.reset_episode().unwrap();
    assert!(env.observation().iter().all(|v| v.is_finite()));
    assert!(!env.step(&[0.0; ACT_DIM]).unwrap().terminated);
}

#[test]
fn a_blow_up_in_a_batch_resets_that_env_and_leaves_the_others_bit_identical() {
    let robot = RobotModel::a1().unwrap();
    let (n, seed) = (3, 11);
    let mut hit = VecEnv::new(&cfg(), &robot, &Perturbation::none(), n, seed).unwrap();
    let mut twin = VecEnv::new(&cfg(), &robot, &Perturbation::none(), n, seed).unwrap();
    let actions = vec![0.1; n * ACT_DIM];
    for _ in 0..3 {
        hit.step(&actions).unwrap();
        twin.step(&actions).unwrap();
    }
    hit.push(1, [f32::NAN, 0.0]).unwrap();
    let (a, b) = (hit.step(&actions).unwrap(), twin.step(&actions).unwrap());
    assert_eq!(a.physics_resets.len(), 1, "{:?}", a.physics_resets);
    assert_eq!(a.physics_resets[0].0, 1);
    assert!(a.physics_resets[0].1.contains("env 1") && a.physics_resets[0].1.contains("non-finite"));
    assert!(b.physics_resets.is_empty());
    assert!(a.terminated[1] && !a.truncated[1] && a.reward[1] == 0.0);
    assert!(a.finished.iter().all(|e| e.env != 1), "the cut-short episode is not reported as one");
    let row = |v: &[f32], i: usize| v[i * OBS_DIM..(i + 1) * OBS_DIM].to_vec();
    assert!(row(hit.observations(), 1).iter().all(|v| v.is_finite()));
    for i in [0, 2] {
        assert_eq!(a.reward[i].to_bits(), b.reward[i].to_bits(), "env {i}");
        assert_eq!(row(hit.observations(), i), row(twin.observations(), i), "env {i}");
    }
    // The batch steps on.
    for _ in 0..20 {
        let step = hit.step(&actions).unwrap();
        assert!(step.physics_resets.is_empty());
        assert!(hit.observations().iter().all(|v| v.is_finite()));
    }
    assert!(hit.push(3, [0.0; 2]).is_err(), "no env 3 in a batch of 3");
}

#[test]
fn training_stops_only_when_blow_ups_exceed_the_rate_and_the_error_says_so() {
    use quadcl::rl::check_physics_resets;
    let resets: Vec<(usize, String)> =
        (0..3).map(|i| (i, format!("env {i}: the physics produced a non-finite x"))).collect();
    check_physics_resets(&[], 3072, 0.0).unwrap();
    check_physics_resets(&resets, 3072, 0.01).unwrap();
    let err = format!("{:#}", check_physics_resets(&resets, 100, 0.01).unwrap_err());
    assert!(err.contains("3 of this iteration's 100 env steps") && err.contains("ppo.max_physics_reset_rate"), "{err}");
    assert!(err.contains("env 2: the physics produced"), "the last blow-up is named: {err}");
}
