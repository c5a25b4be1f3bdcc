"""Bad input from Python is a Python exception with a clear message, raised
before anything steps, never an abort of the interpreter."""

import numpy as np
import pytest

import quadcl
from quadcl import _native


def fresh():
    envs = quadcl.make_vec(num_envs=2, seed=4)
    envs.reset(seed=4)
    return envs


def test_a_wrong_action_shape_is_a_value_error_naming_both_shapes():
    with pytest.raises(ValueError, match=r"\(2, 11\).*\(2, 12\)"):
        fresh().step(np.zeros((2, 11), np.float32))
    # The native layer checks too, for callers that skip the wrapper.
    envs = fresh()
    with pytest.raises(ValueError, match=r"\(2, 12\)"):
        envs._native.step(np.zeros((3, 12), np.float32))


def test_a_non_float_action_dtype_is_a_type_error():
    with pytest.raises(TypeError, match="int64"):
        fresh().step(np.zeros((2, 12), np.int64))


def test_a_nan_action_is_refused_and_nothing_steps():
    envs, twin = fresh(), fresh()
    bad = np.zeros((2, 12), np.float32)
    bad[1, 7] = np.nan
    with pytest.raises(ValueError, match=r"finite.*\[1, 7\]"):
        envs.step(bad)
    with pytest.raises(ValueError, match="env 1"):
        envs._native.step(bad)
    good = np.full((2, 12), 0.3, np.float32)
    assert np.array_equal(envs.step(good)[0], twin.step(good)[0]), "the refused steps changed the envs"


def test_unknown_robot_task_and_config_are_errors_naming_them(tmp_path):
    with pytest.raises(ValueError, match="spot.*a1"):
        quadcl.make_vec(robot="spot")
    with pytest.raises(ValueError, match="crash:XX"):
        quadcl.make_vec(task="crash:XX")
    with pytest.raises(OSError, match="nowhere.toml"):
        quadcl.make_vec(config=tmp_path / "nowhere.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[env]\nkp = -3.0\n")
    with pytest.raises(ValueError, match=r"bad.toml.*kp"):
        quadcl.make_vec(config=bad)
    with pytest.raises(ValueError, match="not both"):
        quadcl.make_vec(robot="a1", config=bad)
    with pytest.raises(ValueError, match="num_threads"):
        quadcl.make_vec(num_threads=0)
    with pytest.raises(ValueError, match="seed"):
        quadcl.make_vec(seed=-1)
    with pytest.raises(ValueError, match="num_envs|env count"):
        quadcl.make_vec(num_envs=0)


def test_a_bad_policy_path_and_bad_observations_are_errors(tmp_path, root):
    with pytest.raises(OSError, match="no-policy"):
        quadcl.load_policy(tmp_path / "no-policy", "none")
    policy = quadcl.load_policy(root / "policies/base-a1-flat", "none")
    with pytest.raises(ValueError, match=r"\(3, 10\)"):
        policy(np.zeros((3, 10), np.float32))
    with pytest.raises(TypeError, match="callable"):
        quadcl.evaluate(42, "none", episodes=2)
    with pytest.raises(ValueError, match="shape"):
        quadcl.evaluate(lambda obs: np.zeros((len(obs), 3), np.float32), "none", episodes=2)
    with pytest.raises(ValueError, match="raised.*boom"):
        quadcl.evaluate(lambda obs: (_ for _ in ()).throw(RuntimeError("boom")), "none", episodes=2)


def test_a_rust_panic_surfaces_as_a_runtime_error():
    with pytest.raises(RuntimeError, match="panicked.*on purpose"):
        _native._panic_for_test("on purpose")
    # The interpreter lives on and the module still works.
    assert quadcl.task_name(" crash:FL ") == "crash:FL"
