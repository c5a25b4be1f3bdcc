#!/usr/bin/env python3
"""PPO in CleanRL's single-file style (ppo_continuous_action.py) on quadcl's
vector environment: PyTorch, a Gaussian policy with a state-independent
log-std, GAE, clipped surrogate, value clipping off, advantage normalisation.

It trains the walking base task (task "none") from scratch on
`quadcl.make_vec`, at the Rust learner's batch (128 envs x 24 steps), and
prints per iteration the env steps/s and the mean `performance` of the
episodes that ended (the normalised return `metrics.json` reports).

    pip install ./python torch
    python3 examples/python/ppo_cleanrl.py [--iterations 500] [--threads 2] [--seed 1]

At the end it scores the policy with `quadcl.evaluate` (32 episodes, seed 0),
as `quadcl eval` scores the Rust learner's.
"""

import argparse
import time

import numpy as np
import torch
import torch.nn as nn

import quadcl


def layer(inp, out, std=np.sqrt(2)):
    lin = nn.Linear(inp, out)
    nn.init.orthogonal_(lin.weight, std)
    nn.init.zeros_(lin.bias)
    return lin


class Agent(nn.Module):
    def __init__(self, obs_dim, act_dim):
        super().__init__()
        self.critic = nn.Sequential(layer(obs_dim, 512), nn.ELU(), layer(512, 256), nn.ELU(), layer(256, 128), nn.ELU(), layer(128, 1, 1.0))
        self.actor = nn.Sequential(layer(obs_dim, 512), nn.ELU(), layer(512, 256), nn.ELU(), layer(256, 128), nn.ELU(), layer(128, act_dim, 0.01))
        self.log_std = nn.Parameter(torch.full((act_dim,), np.log(0.5)))

    def value(self, x):
        return self.critic(x).squeeze(-1)

    def act(self, x, action=None):
        mean = self.actor(x)
        dist = torch.distributions.Normal(mean, self.log_std.exp().expand_as(mean))
        if action is None:
            action = dist.sample()
        return action, dist.log_prob(action).sum(-1), dist.entropy().sum(-1), self.value(x)


class Normalizer:
    """Running mean and variance of the observations (as the Rust learner normalises them)."""

    def __init__(self, dim):
        self.mean, self.var, self.count = np.zeros(dim), np.ones(dim), 1e-4

    def update(self, x):
        m, v, n = x.mean(0), x.var(0), len(x)
        delta, total = m - self.mean, self.count + n
        self.mean = self.mean + delta * n / total
        self.var = (self.var * self.count + v * n + delta**2 * self.count * n / total) / total
        self.count = total

    def __call__(self, x):
        return np.clip((x - self.mean) / np.sqrt(self.var + 1e-8), -5, 5).astype(np.float32)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--iterations", type=int, default=500)
    p.add_argument("--envs", type=int, default=128)
    p.add_argument("--steps", type=int, default=24)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--epochs", type=int, default=5)
    p.add_argument("--minibatches", type=int, default=4)
    a = p.parse_args()
    torch.manual_seed(a.seed)
    torch.set_num_threads(a.threads)
    envs = quadcl.make_vec(task="none", num_envs=a.envs, seed=a.seed, num_threads=a.threads)
    obs_dim, act_dim = envs.single_observation_space.shape[0], envs.single_action_space.shape[0]
    agent = Agent(obs_dim, act_dim)
    opt = torch.optim.Adam(agent.parameters(), lr=a.lr, eps=1e-5)
    norm = Normalizer(obs_dim)
    n, t = a.envs, a.steps
    obs_buf = np.zeros((t, n, obs_dim), np.float32)
    act_buf, logp_buf = torch.zeros((t, n, act_dim)), torch.zeros((t, n))
    rew_buf, done_buf, val_buf = np.zeros((t, n), np.float32), np.zeros((t, n), np.float32), torch.zeros((t, n))
    raw, _ = envs.reset(seed=a.seed)
    performance, start = [], time.perf_counter()
    for it in range(1, a.iterations + 1):
        tick = time.perf_counter()
        for k in range(t):
            norm.update(raw)
            x = norm(raw)
            with torch.no_grad():
                action, logp, _, value = agent.act(torch.from_numpy(x))
            raw, reward, terminated, truncated, infos = envs.step(action.numpy())
            obs_buf[k], act_buf[k], logp_buf[k], val_buf[k] = x, action, logp, value
            rew_buf[k] = reward
            done_buf[k] = terminated  # a time-out bootstraps below
            if truncated.any():
                # Bootstrap time-outs from the value of the observation they ended with.
                with torch.no_grad():
                    final = torch.from_numpy(norm(infos["final_obs"][truncated]))
                    rew_buf[k][truncated] += 0.99 * agent.value(final).numpy()
                done_buf[k][truncated] = 1.0
            if "episode" in infos:
                performance.extend(infos["episode"]["performance"][infos["_episode"]].tolist())
        with torch.no_grad():
            next_value = agent.value(torch.from_numpy(norm(raw)))
        adv, last = torch.zeros((t, n)), torch.zeros(n)
        for k in reversed(range(t)):
            not_done = 1.0 - torch.from_numpy(done_buf[k])
            nv = next_value if k == t - 1 else val_buf[k + 1]
            delta = torch.from_numpy(rew_buf[k]) + 0.99 * nv * not_done - val_buf[k]
            last = delta + 0.99 * 0.95 * not_done * last
            adv[k] = last
        ret = adv + val_buf
        b_obs, b_act = torch.from_numpy(obs_buf.reshape(t * n, -1)), act_buf.reshape(t * n, -1)
        b_logp, b_adv, b_ret = logp_buf.reshape(-1), adv.reshape(-1), ret.reshape(-1)
        size = t * n // a.minibatches
        for _ in range(a.epochs):
            for mb in torch.randperm(t * n).split(size):
                _, logp, entropy, value = agent.act(b_obs[mb], b_act[mb])
                ratio = (logp - b_logp[mb]).exp()
                adv_mb = (b_adv[mb] - b_adv[mb].mean()) / (b_adv[mb].std() + 1e-8)
                pg = torch.max(-adv_mb * ratio, -adv_mb * ratio.clamp(0.8, 1.2)).mean()
                loss = pg + 0.5 * ((value - b_ret[mb]) ** 2).mean() - 0.01 * entropy.mean()
                opt.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(agent.parameters(), 1.0)
                opt.step()
        sps = t * n / (time.perf_counter() - tick)
        recent = np.mean(performance[-64:]) if performance else float("nan")
        print(f"iteration {it:4d}  {sps:7.0f} env steps/s  performance {recent:.3f}  "
              f"({len(performance)} episodes, {time.perf_counter() - start:.0f} s)", flush=True)

    def policy(x):
        with torch.no_grad():
            return agent.actor(torch.from_numpy(norm(x))).numpy()

    report = quadcl.evaluate(policy, "none", episodes=32, seed=0)
    print("evaluation:", {k: round(v, 3) if isinstance(v, float) else v for k, v in report.items()})


if __name__ == "__main__":
    main()
