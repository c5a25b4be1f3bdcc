#!/usr/bin/env python3
"""PPO in CleanRL's single-file style (ppo_continuous_action.py) on quadcl's
vector environment, with the recipe of quadcl's own dense learner
(`scenes/train-dense.toml`): PyTorch, a Gaussian policy with a
state-independent log-std starting at 0.5, an asymmetric critic on the
privileged observation, GAE with time-outs bootstrapped from V(s_t), step
rewards clipped at zero (legged_gym's `only_positive_rewards`), a clipped
value loss. The learning rate is CleanRL's, fixed at 3e-4;
`--desired-kl 0.01 --lr 1e-3` gives legged_gym's KL-adaptive rule instead (the
Rust learner's), which at this batch holds the rate near its 1e-5 floor and
learns about three times slower (docs/python.md has both runs).

It trains the walking base task (task "none") from scratch on
`quadcl.make_vec`, at the Rust learner's batch (128 envs x 24 steps), and
prints every `--log-every` iterations the env steps/s and the mean
`performance` of the episodes that ended (the normalised return
`metrics.json` reports).

    pip install ./python torch
    python3 examples/python/ppo_cleanrl.py [--iterations 1500] [--threads 2] [--seed 1] [--save actor.pt]

At the end it scores the policy with `quadcl.evaluate` (32 episodes, seed 0),
as `quadcl eval` scores the Rust learner's, and with `--save` writes the
actor as TorchScript.
"""

import argparse
import time

import numpy as np
import torch
import torch.nn as nn

import quadcl


def mlp(inp, out, out_std):
    """512-256-128 ELU, orthogonal initialisation, as quadcl's `[net]` default."""
    layers, width = [], inp
    for hidden in (512, 256, 128):
        layers += [layer(width, hidden, np.sqrt(2)), nn.ELU()]
        width = hidden
    return nn.Sequential(*layers, layer(width, out, out_std))


def layer(inp, out, std):
    lin = nn.Linear(inp, out)
    nn.init.orthogonal_(lin.weight, std)
    nn.init.zeros_(lin.bias)
    return lin


class Agent(nn.Module):
    def __init__(self, obs_dim, priv_dim, act_dim, init_std):
        super().__init__()
        self.actor = mlp(obs_dim, act_dim, 0.01)  # action means start near 0 (CleanRL's 0.01)
        self.critic = mlp(priv_dim, 1, 1.0)
        self.log_std = nn.Parameter(torch.full((act_dim,), float(np.log(init_std))))

    def value(self, priv):
        return self.critic(priv).squeeze(-1)

    def dist(self, obs):
        mean = self.actor(obs)
        return torch.distributions.Normal(mean, self.log_std.exp().expand_as(mean))


class Normalizer:
    """Running mean and variance (Chan et al.), clipped at +-5, as the Rust learner's."""

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
    p.add_argument("--iterations", type=int, default=1500)
    p.add_argument("--envs", type=int, default=128)
    p.add_argument("--steps", type=int, default=24)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--lr", type=float, default=3e-4, help="the rate (the initial one with --desired-kl)")
    p.add_argument("--desired-kl", type=float, default=0.0, help="adapt the rate to this KL (legged_gym); 0: fixed")
    p.add_argument("--epochs", type=int, default=5)
    p.add_argument("--minibatches", type=int, default=4)
    p.add_argument("--init-std", type=float, default=0.5)
    p.add_argument("--log-every", type=int, default=10)
    p.add_argument("--save", help="write the trained actor (with its normaliser) as TorchScript here")
    a = p.parse_args()
    gamma, lam, clip = 0.99, 0.95, 0.2
    torch.manual_seed(a.seed)
    torch.set_num_threads(a.threads)
    envs = quadcl.make_vec(task="none", num_envs=a.envs, seed=a.seed, num_threads=a.threads)
    # The actor reads the current observation (the last 45 of the 225 history
    # columns), as quadcl's dense learner without its context estimator does.
    obs_dim, priv_dim, act_dim = quadcl.OBS_DIM, quadcl.PRIV_OBS_DIM, quadcl.ACT_DIM
    agent = Agent(obs_dim, priv_dim, act_dim, a.init_std)
    lr = a.lr
    opt = torch.optim.Adam(agent.parameters(), lr=lr, eps=1e-5)  # as quadcl's MaskedAdam and CleanRL
    norm, priv_norm = Normalizer(obs_dim), Normalizer(priv_dim)
    n, t = a.envs, a.steps
    obs_buf, priv_buf = np.zeros((t, n, obs_dim), np.float32), np.zeros((t, n, priv_dim), np.float32)
    act_buf, logp_buf, val_buf = torch.zeros((t, n, act_dim)), torch.zeros((t, n)), torch.zeros((t, n))
    mean_buf = torch.zeros((t, n, act_dim))  # the rollout policy's means, for the KL of the adaptive rate
    rew_buf, term_buf, trunc_buf = np.zeros((t, n), np.float32), np.zeros((t, n), bool), np.zeros((t, n), bool)
    history, infos = envs.reset(seed=a.seed)
    raw, raw_priv = history[:, -obs_dim:], infos["privileged_obs"]
    performance, start = [], time.perf_counter()
    for it in range(1, a.iterations + 1):
        tick = time.perf_counter()
        for k in range(t):
            norm.update(raw)
            priv_norm.update(raw_priv)
            x, xp = norm(raw), priv_norm(raw_priv)
            with torch.no_grad():
                dist = agent.dist(torch.from_numpy(x))
                action = dist.sample()
                logp = dist.log_prob(action).sum(-1)
                value = agent.value(torch.from_numpy(xp))
            history, reward, terminated, truncated, infos = envs.step(action.numpy())
            obs_buf[k], priv_buf[k], act_buf[k], logp_buf[k], val_buf[k] = x, xp, action, logp, value
            mean_buf[k] = dist.mean
            rew_buf[k], term_buf[k], trunc_buf[k] = np.maximum(reward, 0.0), terminated, truncated
            raw, raw_priv = history[:, -obs_dim:], infos["privileged_obs"]
            if "episode" in infos:
                performance.extend(infos["episode"]["performance"][infos["_episode"]].tolist())
        # GAE as the Rust learner's (`rl/rollout.rs`): a time-out that is not a
        # fall is bootstrapped from V(s_t); any ended row cuts the trace.
        with torch.no_grad():
            next_value = agent.value(torch.from_numpy(priv_norm(raw_priv)))
        rewards = torch.from_numpy(rew_buf) + gamma * val_buf * torch.from_numpy(trunc_buf & ~term_buf)
        not_done = 1.0 - torch.from_numpy(term_buf | trunc_buf).float()
        adv, last = torch.zeros((t, n)), torch.zeros(n)
        for k in reversed(range(t)):
            nv = next_value if k == t - 1 else val_buf[k + 1]
            delta = rewards[k] + gamma * nv * not_done[k] - val_buf[k]
            last = delta + gamma * lam * not_done[k] * last
            adv[k] = last
        ret = adv + val_buf
        b_obs, b_priv = torch.from_numpy(obs_buf.reshape(t * n, -1)), torch.from_numpy(priv_buf.reshape(t * n, -1))
        b_act, b_logp = act_buf.reshape(t * n, -1), logp_buf.reshape(-1)
        b_adv, b_ret, b_val = adv.reshape(-1), ret.reshape(-1), val_buf.reshape(-1)
        # The rollout's policy: its means as recorded, its std state-independent (one per action).
        old_mean = mean_buf.reshape(t * n, -1)
        old_std = agent.log_std.detach().exp().expand_as(old_mean)
        size = -(-t * n // a.minibatches)
        for _ in range(a.epochs):
            for mb in torch.randperm(t * n).split(size):
                dist = agent.dist(b_obs[mb])
                # legged_gym's adaptive rate: the KL between the rollout's policy and this one.
                with torch.no_grad():
                    s0, s1 = old_std[mb], dist.stddev
                    kl = (torch.log(s1 / s0) + (s0**2 + (old_mean[mb] - dist.mean) ** 2) / (2 * s1**2) - 0.5).sum(-1).mean()
                if a.desired_kl > 0 and kl > 2 * a.desired_kl:
                    lr = max(lr / 1.5, 1e-5)
                elif a.desired_kl > 0 and kl < a.desired_kl / 2:
                    lr = min(lr * 1.5, 1e-2)
                for group in opt.param_groups:
                    group["lr"] = lr
                ratio = (dist.log_prob(b_act[mb]).sum(-1) - b_logp[mb]).exp()
                adv_mb = (b_adv[mb] - b_adv[mb].mean()) / (b_adv[mb].std() + 1e-8)
                pg = torch.max(-adv_mb * ratio, -adv_mb * ratio.clamp(1 - clip, 1 + clip)).mean()
                value = agent.value(b_priv[mb])
                clipped = b_val[mb] + (value - b_val[mb]).clamp(-clip, clip)
                v_loss = torch.max((value - b_ret[mb]) ** 2, (clipped - b_ret[mb]) ** 2).mean()
                loss = pg + 1.0 * v_loss - 0.01 * dist.entropy().sum(-1).mean()
                opt.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(agent.parameters(), 1.0)
                opt.step()
        if it % a.log_every == 0 or it == a.iterations:
            sps = t * n / (time.perf_counter() - tick)
            recent = np.mean(performance[-128:]) if performance else float("nan")
            print(f"iteration {it:5d}  {sps:6.0f} env steps/s  performance {recent:.3f}  lr {lr:.1e}  "
                  f"std {agent.log_std.exp().mean().item():.2f}  ({len(performance)} episodes, "
                  f"{time.perf_counter() - start:.0f} s)", flush=True)
    wall = time.perf_counter() - start

    def policy(history):
        with torch.no_grad():
            return agent.actor(torch.from_numpy(norm(history[:, -obs_dim:]))).numpy()

    report = quadcl.evaluate(policy, "none", episodes=32, seed=0)
    print(f"trained {a.iterations} iterations ({a.iterations * t * n} env steps) in {wall:.0f} s, "
          f"{a.iterations * t * n / wall:.0f} env steps/s")
    print("evaluation:", {k: round(v, 3) if isinstance(v, float) else v for k, v in report.items()})
    if a.save:
        torch.jit.script(NormalisedActor(agent.actor, norm)).save(a.save)
        print("actor saved to", a.save)


class NormalisedActor(nn.Module):
    """The actor with its frozen normaliser: history (N, 225) -> action means (N, 12)."""

    def __init__(self, actor, norm):
        super().__init__()
        self.actor = actor
        self.register_buffer("mean", torch.tensor(norm.mean, dtype=torch.float32))
        self.register_buffer("scale", torch.tensor(np.sqrt(norm.var + 1e-8), dtype=torch.float32))

    def forward(self, history: torch.Tensor) -> torch.Tensor:
        x = ((history[:, -45:] - self.mean) / self.scale).clamp(-5.0, 5.0)
        return self.actor(x)


if __name__ == "__main__":
    main()
