"""A run file's task sequence from Python: the tasks in training order with
their budgets, each a factory of its environments, so a continual method
written in Python trains on the same sequence as ``quadcl run``."""

from dataclasses import dataclass

from . import _native
from .vector import QuadrupedVectorEnv


@dataclass(frozen=True)
class SequenceTask:
    """One step of a sequence: its position, task name and PPO iteration budget."""

    index: int
    name: str
    iterations: int
    env_toml: str
    seed: int

    def make_vec(self, num_envs=128, seed=None, num_threads=None):
        """This task's environments with the run file's ``[env]`` settings (seed: the run's)."""
        seed = self.seed if seed is None else seed
        return QuadrupedVectorEnv(task=self.name, num_envs=num_envs, seed=seed, num_threads=num_threads, env_toml=self.env_toml)


class Sequence:
    """The task sequence of a run file: ``for task in quadcl.Sequence("scenes/sequence-a1.toml")``."""

    def __init__(self, path):
        self.path = str(path)
        env_toml, self.seed, tasks, self.method = _native.sequence_of(self.path)
        self.env_toml = env_toml
        self.tasks = [SequenceTask(i, name, iterations, env_toml, self.seed) for i, (name, iterations) in enumerate(tasks)]

    def __len__(self):
        return len(self.tasks)

    def __iter__(self):
        return iter(self.tasks)

    def __getitem__(self, i):
        return self.tasks[i]

    def __repr__(self):
        steps = ", ".join(f"{t.name} ({t.iterations})" for t in self.tasks)
        return f"Sequence({self.path!r}: {steps})"
