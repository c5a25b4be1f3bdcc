"""Pictures from Python: ``render_mode="rgb_array"`` on the single and the vector
environment (frames drawn on the CPU by quadcl's renderer), Gymnasium's own tools over
them (its env checker's render check, ``RecordVideo``), Stable-Baselines3's standard
helper unchanged, and the loose ends found on the way: a closed environment says so,
and a policy says which learned task's network acts."""

import shutil
import subprocess

import gymnasium
import numpy as np
import pytest

import quadcl

SHIPPED = "policies/sequence-a1-adapter/checkpoints/step-03-crash_FR"


def test_an_rgb_array_environment_renders_the_robot_as_height_width_3_bytes():
    env = quadcl.QuadrupedEnv(task="crash:FL", render_mode="rgb_array", width=160, height=120)
    env.reset(seed=1)
    frame = env.render()
    assert frame.shape == (120, 160, 3) and frame.dtype == np.uint8
    # Sky above, something darker (the robot, the ground's grid) below: not a blank picture.
    assert frame[0].mean() > 150 and frame.std() > 10
    for _ in range(10):
        env.step(np.zeros(quadcl.ACT_DIM, np.float32))
    assert not np.array_equal(env.render(), frame), "the picture follows the robot"
    assert env.metadata["render_fps"] == 50


def test_render_modes_other_than_rgb_array_are_refused_naming_the_supported_ones():
    assert quadcl.QuadrupedEnv().render() is None
    for mode in ("human", "ansi", "depth_array"):
        with pytest.raises(ValueError, match="rgb_array"):
            quadcl.QuadrupedEnv(render_mode=mode)
        with pytest.raises(ValueError, match="rgb_array"):
            quadcl.make_vec(num_envs=2, render_mode=mode)
    with pytest.raises(ValueError, match="width"):
        quadcl.QuadrupedEnv(render_mode="rgb_array", width=0)


def test_a_vector_environment_renders_a_frame_per_environment():
    envs = gymnasium.make_vec("quadcl/Quadruped-v0", num_envs=3, vectorization_mode="vector_entry_point",
                              render_mode="rgb_array", width=64, height=48)
    envs.reset(seed=0)
    frames = envs.render()
    assert len(frames) == 3 and all(f.shape == (48, 64, 3) and f.dtype == np.uint8 for f in frames)
    assert quadcl.make_vec(num_envs=2).render() is None


def test_one_thread_and_every_core_draw_the_same_pictures():
    one = quadcl.make_vec(num_envs=2, num_threads=1, render_mode="rgb_array", width=64, height=48)
    every = quadcl.make_vec(num_envs=2, render_mode="rgb_array", width=64, height=48)
    one.reset(seed=3)
    every.reset(seed=3)
    for a, b in zip(one.render(), every.render()):
        assert np.array_equal(a, b)


def test_gymnasiums_env_checker_passes_the_render_check():
    from gymnasium.utils.env_checker import check_env

    # Made by gymnasium.make, so the checker also tries the other render modes the metadata lists.
    check_env(gymnasium.make("quadcl/Quadruped-v0", render_mode="rgb_array", width=64, height=48).unwrapped)


def test_a_closed_environment_says_it_is_closed():
    env = quadcl.QuadrupedEnv(render_mode="rgb_array")
    env.reset(seed=0)
    env.close()
    for call in (lambda: env.step(np.zeros(quadcl.ACT_DIM, np.float32)), lambda: env.reset(seed=0), env.render):
        with pytest.raises(RuntimeError, match="closed"):
            call()
    envs = quadcl.make_vec(num_envs=2)
    envs.reset(seed=0)
    envs.close()
    with pytest.raises(RuntimeError, match="closed"):
        envs.step(np.zeros((2, quadcl.ACT_DIM), np.float32))


def test_a_policy_says_which_learned_tasks_network_acts(root):
    learned = quadcl.load_policy(root / SHIPPED, "crash:FL")
    assert learned.task == "crash:FL" and learned.recalls == "crash:FL"
    # invert:RR was never learned: the last learned task's network acts, and the policy says so.
    zero_shot = quadcl.load_policy(root / SHIPPED, "invert:RR")
    assert zero_shot.task == "invert:RR" and zero_shot.recalls == zero_shot.tasks[-1] == "crash:FR"
    assert "recalls='crash:FR'" in repr(zero_shot)


@pytest.mark.skipif(shutil.which("ffprobe") is None, reason="ffprobe (ffmpeg) reads the video back")
def test_gymnasiums_record_video_writes_an_mp4_of_the_expected_frames_and_size(tmp_path):
    pytest.importorskip("moviepy")
    from gymnasium.wrappers import RecordVideo

    env = RecordVideo(gymnasium.make("quadcl/Quadruped-v0", render_mode="rgb_array", width=160, height=120),
                      str(tmp_path), episode_trigger=lambda e: True, disable_logger=True)
    env.reset(seed=0)
    for _ in range(40):
        env.step(np.zeros(quadcl.ACT_DIM, np.float32))
    env.close()
    videos = sorted(tmp_path.glob("*.mp4"))
    assert videos, "RecordVideo wrote no video"
    probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                            "stream=width,height,nb_read_frames", "-of", "csv=p=0", str(videos[0])],
                           capture_output=True, text=True, check=True).stdout.strip()
    width, height, frames = (int(v) for v in probe.split(","))
    # The reset's frame and one per step.
    assert (width, height) == (160, 120) and frames == 41, probe


def test_stable_baselines3s_make_vec_env_trains_ppo_with_no_extra_argument():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    envs = make_vec_env("quadcl/Quadruped-v0", n_envs=4, seed=0)
    model = PPO("MlpPolicy", envs, n_steps=256, batch_size=256, n_epochs=1, seed=0, device="cpu")
    model.learn(total_timesteps=2048)
    assert model.num_timesteps >= 2048
    frames = envs.get_images()
    assert len(frames) == 4 and frames[0].ndim == 3 and frames[0].dtype == np.uint8
