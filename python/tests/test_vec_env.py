"""make_vec as a Gymnasium vector environment: shapes, determinism, auto-reset,
threads, and registration."""

import gymnasium
import numpy as np

import quadcl

W = quadcl.HISTORY_LEN * quadcl.OBS_DIM


def rollout(envs, steps, seed):
    obs, _ = envs.reset(seed=seed)
    frames, rewards = [obs], []
    rng = np.random.default_rng(0)
    for _ in range(steps):
        obs, r, _, _, _ = envs.step(rng.uniform(-1, 1, (envs.num_envs, quadcl.ACT_DIM)).astype(np.float32))
        frames.append(obs)
        rewards.append(r)
    return np.stack(frames), np.stack(rewards)


def test_reset_and_step_give_the_documented_arrays():
    envs = quadcl.make_vec(task="crash:FL", num_envs=8, seed=3)
    assert isinstance(envs, gymnasium.vector.VectorEnv)
    assert envs.metadata["autoreset_mode"] == gymnasium.vector.AutoresetMode.SAME_STEP
    obs, infos = envs.reset(seed=3)
    assert obs.shape == (8, W) and obs.dtype == np.float32
    assert infos["privileged_obs"].shape == (8, quadcl.PRIV_OBS_DIM)
    assert envs.single_observation_space.contains(obs[0])
    obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample() * 0.1)
    assert obs.shape == (8, W) and rewards.shape == (8,) and rewards.dtype == np.float32
    assert terminated.dtype == np.bool_ and truncated.dtype == np.bool_
    assert np.isfinite(obs).all() and np.isfinite(rewards).all()
    # The history shifts by one frame each step: the old newest frames are now second newest.
    assert envs.task == "crash:FL"


def test_the_same_seed_gives_the_same_numbers_and_another_seed_others():
    a = rollout(quadcl.make_vec(num_envs=4, seed=5), 40, seed=5)
    b = rollout(quadcl.make_vec(num_envs=4, seed=5), 40, seed=5)
    c = rollout(quadcl.make_vec(num_envs=4, seed=5), 40, seed=6)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[0], c[0])


def test_without_a_seed_the_envs_draw_one():
    envs = quadcl.make_vec(num_envs=2, seed=None)
    obs, _ = envs.reset()
    assert np.isfinite(envs.step(np.zeros((2, quadcl.ACT_DIM), np.float32))[0]).all()


def test_one_thread_and_every_core_give_the_same_numbers():
    one = rollout(quadcl.make_vec(num_envs=6, seed=2, num_threads=1), 30, seed=2)
    many = rollout(quadcl.make_vec(num_envs=6, seed=2, num_threads=2), 30, seed=2)
    assert np.array_equal(one[0], many[0]) and np.array_equal(one[1], many[1])


def test_an_ending_row_returns_the_next_episodes_first_observation_and_keeps_its_last_in_final_obs():
    envs = quadcl.make_vec(task="crash:FL", num_envs=8, seed=1)
    obs, _ = envs.reset(seed=1)
    rng = np.random.default_rng(1)
    for _ in range(400):
        before = obs
        # Violent actions: the robot falls within a few seconds.
        obs, _, terminated, truncated, infos = envs.step(rng.uniform(-10, 10, (8, quadcl.ACT_DIM)).astype(np.float32))
        done = terminated | truncated
        if done.any():
            break
    assert done.any(), "no env ended in 400 steps of violent actions"
    assert np.array_equal(infos["_final_obs"], done)
    final = infos["final_obs"][done]
    # The history it ended with continues the one before the step...
    assert np.array_equal(final[:, : W - quadcl.OBS_DIM], before[done][:, quadcl.OBS_DIM :])
    # ...while the returned row is a new episode's: every frame the same first observation.
    fresh = obs[done].reshape(-1, quadcl.HISTORY_LEN, quadcl.OBS_DIM)
    assert np.array_equal(fresh, np.repeat(fresh[:, -1:], quadcl.HISTORY_LEN, axis=1))
    assert np.array_equal(infos["_episode"], done)
    assert (infos["episode"]["l"][done] > 0).all()
    assert infos["episode"]["fell"][terminated].all()


def test_gymnasium_makes_the_registered_environments():
    env = gymnasium.make("quadcl/Quadruped-v0", task="invert:RL")
    obs, _ = env.reset(seed=0)
    assert obs.shape == (W,)
    envs = gymnasium.make_vec("quadcl/Quadruped-v0", num_envs=3, vectorization_mode="vector_entry_point", task="noise:FR")
    obs, _ = envs.reset(seed=0)
    assert obs.shape == (3, W) and envs.unwrapped.task == "noise:FR"


def test_every_shipped_robot_steps():
    for robot in quadcl.SHIPPED_ROBOTS:
        envs = quadcl.make_vec(robot=robot, num_envs=2, seed=0)
        obs, _ = envs.reset(seed=0)
        obs, *_ = envs.step(np.zeros((2, quadcl.ACT_DIM), np.float32))
        assert np.isfinite(obs).all(), robot


def test_single_environment_passes_gymnasiums_env_checker_without_a_warning():
    import warnings

    from gymnasium.utils.env_checker import check_env

    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        check_env(quadcl.QuadrupedEnv(task="crash:FL"), skip_render_check=True)
    # Only Gymnasium's recommendations on the spaces' bounds remain: actions are the
    # simulator's own, clipped at +-clip_actions (10), and observations have no bound.
    others = [str(w.message) for w in seen if "recommend using a symmetric" not in str(w.message)
              and "observation space maximum value is infinity" not in str(w.message)
              and "observation space minimum value is -infinity" not in str(w.message)]
    assert not others, f"check_env warned: {others}"
