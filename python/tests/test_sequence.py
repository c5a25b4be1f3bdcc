"""quadcl.Sequence is the run file's sequence as `quadcl run` trains it."""

import tomllib

import numpy as np

import quadcl


def test_a_run_files_sequence_has_its_tasks_budgets_and_settings(root):
    path = root / "scenes/sequence-a1.toml"
    text = tomllib.loads(path.read_text())
    seq = quadcl.Sequence(path)
    assert [t.name for t in seq] == [quadcl.task_name(t["name"]) for t in text["task"]]
    assert [t.iterations for t in seq] == [t.get("iterations", text.get("iterations", 300)) for t in text["task"]]
    assert seq.seed == text.get("seed", 1) and len(seq) == len(text["task"])
    first = seq[0].make_vec(num_envs=2)
    assert first.task == seq[0].name
    obs, _ = first.reset(seed=0)
    # The run file's [env] is the environments' (its robot and control settings).
    same = quadcl.make_vec(task=seq[0].name, num_envs=2, seed=0, config=path)
    assert np.array_equal(obs, same.reset(seed=0)[0])
