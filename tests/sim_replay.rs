//! An env's replay (`sim::EpisodeReplay`, what a training checkpoint keeps of
//! each env) restores it bit for bit in a fresh env: pushes and commands from
//! outside included, across the env's own resets and pushes; a replay that
//! does not fit the env is an error, not a silently different state.

use quadcl::config::EnvConfig;
use quadcl::sim::*;
use rand::{Rng, SeedableRng};

/// Randomised physics, frequent pushes of its own, short episodes: every draw of the stream matters.
fn busy_config() -> EnvConfig {
    EnvConfig { push_interval_s: 0.3, episode_s: 2.0, ..EnvConfig::default() }
}

fn robot() -> RobotModel {
    RobotModel::a1().unwrap()
}

fn random_actions(rng: &mut impl Rng, steps: usize) -> Vec<[f32; ACT_DIM]> {
    (0..steps).map(|_| std::array::from_fn(|_| rng.gen_range(-0.3..0.3))).collect()
}

/// Everything the env shows of its state, as bits.
fn fingerprint(env: &LocomotionEnv) -> Vec<u32> {
    let s = env.raw_state();
    let mut v: Vec<f32> = env.observation().to_vec();
    v.extend(env.privileged_observation());
    v.extend(env.obs_history());
    v.extend(s.q.iter().chain(&s.qd).chain(&s.base_pos).chain(&s.base_quat).chain(&s.base_lin_vel));
    v.extend(env.command());
    v.push(env.sim_time() as f32);
    v.iter().map(|x| x.to_bits()).collect()
}

/// Steps `env` with `actions`, resetting it when an episode ends (as `VecEnv` does).
fn run(env: &mut LocomotionEnv, actions: &[[f32; ACT_DIM]]) -> Vec<(u32, bool, bool)> {
    let mut out = Vec::new();
    for a in actions {
        let step = env.step(a).unwrap();
        out.push((step.reward.to_bits(), step.terminated, step.truncated));
        if step.terminated || step.truncated {
            env.reset_episode().unwrap();
        }
    }
    out
}

#[test]
fn a_restored_env_goes_on_bit_for_bit_with_outside_pushes_and_commands() {
    let cfg = busy_config();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let mut original = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    original.reset(77).unwrap();
    original.keep_replay().unwrap();
    // Past an episode end (2 s = 100 steps), with pushes and a command from outside in the episode.
    let before = random_actions(&mut rng, 130);
    run(&mut original, &before[..110]);
    original.push([0.4, -0.3]);
    run(&mut original, &before[110..120]);
    original.set_command([0.5, 0.0, 0.2]);
    run(&mut original, &before[120..]);
    let replay = original.replay().unwrap();
    assert!(replay.steps() > 0 && replay.steps() < 130, "the replay covers the current episode only");
    assert_eq!(replay.interventions.len(), 2, "{:?}", replay.interventions);

    let mut restored = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    restored.reset(1).unwrap();
    restored.restore(&replay).unwrap();
    assert_eq!(fingerprint(&restored), fingerprint(&original));
    let after = random_actions(&mut rng, 250);
    assert_eq!(run(&mut restored, &after), run(&mut original, &after), "rewards and episode ends");
    assert_eq!(fingerprint(&restored), fingerprint(&original));
    // The restored env keeps its replay: a second restore from it lands on the same state.
    let mut again = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    again.restore(&restored.replay().unwrap()).unwrap();
    assert_eq!(fingerprint(&again), fingerprint(&original));
}

#[test]
fn a_batch_restores_every_env_and_its_observation_buffers() {
    let cfg = busy_config();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
    let mut original = VecEnv::new(&cfg, &robot(), &Perturbation::none(), 5, 21).unwrap();
    original.keep_replays().unwrap();
    let flat = |steps: usize, rng: &mut rand_chacha::ChaCha8Rng| -> Vec<Vec<f32>> {
        (0..steps).map(|_| random_actions(rng, 5).concat()).collect()
    };
    for a in flat(60, &mut rng) {
        original.step(&a).unwrap();
    }
    let replays = original.replays().unwrap();
    let mut restored = VecEnv::new(&cfg, &robot(), &Perturbation::none(), 5, 999).unwrap();
    restored.restore(&replays).unwrap();
    assert_eq!(restored.observations(), original.observations());
    assert_eq!(restored.privileged_observations(), original.privileged_observations());
    assert_eq!(restored.obs_histories(), original.obs_histories());
    for a in flat(80, &mut rng) {
        let (x, y) = (original.step(&a).unwrap(), restored.step(&a).unwrap());
        assert_eq!((x.reward, x.terminated, x.truncated), (y.reward, y.terminated, y.truncated));
        assert_eq!(x.finished, y.finished);
    }
    assert_eq!(restored.observations(), original.observations());
    let err = format!("{:#}", restored.restore(&replays[..3]).unwrap_err());
    assert!(err.contains("3 env replays for a batch of 5"), "{err}");
}

#[test]
fn a_replay_that_does_not_fit_the_env_is_an_error() {
    let cfg = EnvConfig { push_interval_s: 0.0, ..busy_config() };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
    let mut original = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    original.keep_replay().unwrap();
    // Zero actions: the robot stands, so the episode runs to its time-out unless it is shorter.
    run(&mut original, &vec![[0.0; ACT_DIM]; 80]);
    let replay = original.replay().unwrap();
    assert_eq!(replay.steps(), 80);

    // An env whose episodes are shorter than the replay ends it early.
    let short = EnvConfig { episode_s: 1.0, ..cfg.clone() };
    let mut other = LocomotionEnv::new(&short, &robot(), &Perturbation::none()).unwrap();
    let err = format!("{:#}", other.restore(&replay).unwrap_err());
    assert!(err.contains("ended at step 50 of 80") && err.contains("another robot, task or configuration"), "{err}");

    // Actions that are not whole steps, and an intervention past the episode's end.
    let mut env = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    let mut broken = replay.clone();
    broken.actions.pop();
    assert!(format!("{:#}", env.restore(&broken).unwrap_err()).contains("not whole steps of 12"));
    let mut late = replay.clone();
    late.interventions.push((81, Intervention::Push([0.1, 0.0])));
    assert!(format!("{:#}", env.restore(&late).unwrap_err()).contains("after step 81 of a 80-step episode"));

    // No replay kept, or asked for mid-episode.
    let mut plain = LocomotionEnv::new(&cfg, &robot(), &Perturbation::none()).unwrap();
    assert!(format!("{:#}", plain.replay().unwrap_err()).contains("no replay kept"));
    plain.step(&random_actions(&mut rng, 1)[0]).unwrap();
    assert!(format!("{:#}", plain.keep_replay().unwrap_err()).contains("from an episode's start"));
}
