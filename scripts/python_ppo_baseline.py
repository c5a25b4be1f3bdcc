#!/usr/bin/env python3
"""The lean Python stack of issue 15, to measure quadcl against it on the same machine in the same hour.

PyTorch (2 threads) + MuJoCo (`mujoco.rollout`, 2 threads): quadcl's own A1
(scenes/a1.urdf, a floating base added, a floor) at 0.005 s x 4 under PD
(position actuators, kp 20, kd 0.5, action scale 0.25 around quadcl's
default pose); 128 envs x 24 steps; actor and critic 512-256-128 ELU (the
critic also sees the base velocity), a state-independent log-std; PPO with GAE
(0.99, 0.95), 5 epochs x 4 minibatches, clip 0.2, value coefficient 1,
entropy 0.01, Adam 1e-3, gradient norm 1; no CENet, no masks. Rewards:
legged_gym's velocity tracking (exp, sigma 0.25), minus torques, joint
velocities and action rate; a fall (trunk below 0.18 m or tilted past 1 rad)
ends an episode, as does a 20 s time-out.

It is a throughput harness: it does the work a PPO iteration does (physics,
observations, rewards, resets, batched inference, the update) at the sizes
above, so its env steps/s can stand beside `quadcl bench --json --only ppo`
(`ppo_env_steps_per_s_dense` is quadcl's like-for-like config,
scenes/train-dense.toml). It is not tuned to learn to walk.

`--cenet` adds the full method's third network at quadcl's sizes, dense: the
CENet's encoder on the last 5 observations (225 -> 256 -> 128 -> 3 velocity +
16 latent means + 16 log-variances) and decoder (19 -> 128 -> 256 -> 45
next observation), ELU, trained on the base velocity, the next
observation and a beta-VAE KL; the actor reads the observation and the
rollout's context (64 inputs); 2 minibatches (scenes/train-base.toml's). That
is the arithmetic of `ppo_env_steps_per_s` (the full method) without its
masks, which cost quadcl about nothing (`quadcl bench --only nn`).

    pip install torch mujoco numpy
    python3 scripts/python_ppo_baseline.py [--iterations 12] [--threads 2] [--json]

Prints the mean over the iterations after the first 2 (warm-up): env steps/s
and the split per iteration (physics, inference, update, other), in ms.
"""

import argparse
import json
import math
import time

import mujoco
import numpy as np
from mujoco import rollout

from mujoco_a1 import DEFAULT_Q, KD, KP, a1_model as _a1_model

ACTION_SCALE, DT, DECIMATION = 0.25, 0.005, 4
EPISODE_STEPS = int(20.0 / (DT * DECIMATION))


def a1_model():
    return _a1_model(DT)


def quat_rotate_inverse(q, v):
    """v (n, 3) into the frame of unit quaternions q (n, 4), w first."""
    w, u = q[:, :1], -q[:, 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


class Envs:
    def __init__(self, n, threads, seed):
        self.model = a1_model()
        self.n = n
        self.data = [mujoco.MjData(self.model) for _ in range(threads)]  # one per rollout thread
        self.runner = rollout.Rollout(nthread=threads)
        self.nstate = mujoco.mj_stateSize(self.model, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        self.rng = np.random.default_rng(seed)
        self.state = np.zeros((n, self.nstate))
        self.steps = np.zeros(n, dtype=np.int64)
        self.command = np.zeros((n, 3))
        self.last_action = np.zeros((n, 12))
        d = self.data[0]
        mujoco.mj_resetData(self.model, d)
        d.qpos[7:] = DEFAULT_Q
        mujoco.mj_forward(self.model, d)
        self.reset_state = np.empty(self.nstate)
        mujoco.mj_getState(self.model, d, self.reset_state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        self.reset(np.ones(n, dtype=bool))

    def reset(self, which):
        k = int(which.sum())
        self.state[which] = self.reset_state
        self.steps[which] = 0
        self.last_action[which] = 0.0
        self.command[which] = np.stack([self.rng.uniform(-1, 1, k), np.zeros(k), self.rng.uniform(-1.57, 1.57, k)], 1)

    def observe(self):
        # FULLPHYSICS state: time, qpos (19), qvel (18), act, ...
        qpos, qvel = self.state[:, 1:20], self.state[:, 20:38]
        quat = qpos[:, 3:7]
        lin = quat_rotate_inverse(quat, qvel[:, 0:3])
        ang = quat_rotate_inverse(quat, qvel[:, 3:6])
        gravity = quat_rotate_inverse(quat, np.tile([0.0, 0.0, -1.0], (self.n, 1)))
        obs = np.concatenate(
            [ang * 0.25, gravity, self.command * [2.0, 2.0, 0.25], qpos[:, 7:] - DEFAULT_Q, qvel[:, 6:] * 0.05, self.last_action],
            axis=1,
        )
        return obs.astype(np.float32), np.concatenate([obs, lin * 2.0], axis=1).astype(np.float32), lin, ang, gravity, qpos, qvel

    def step(self, actions):
        targets = DEFAULT_Q + ACTION_SCALE * np.clip(actions, -10, 10)
        control = np.repeat(targets[:, None, :], DECIMATION, axis=1)
        states, _ = self.runner.rollout(self.model, self.data, self.state, control, nstep=DECIMATION)
        self.state = states[:, -1, :]
        obs, priv, lin, ang, gravity, qpos, qvel = self.observe()
        torques = KP * (targets - qpos[:, 7:]) - KD * qvel[:, 6:]
        reward = (
            np.exp(-np.sum((self.command[:, :2] - lin[:, :2]) ** 2, 1) / 0.25)
            + 0.5 * np.exp(-((self.command[:, 2] - ang[:, 2]) ** 2) / 0.25)
            - 1e-5 * np.sum(torques**2, 1)
            - 1e-4 * np.sum(qvel[:, 6:] ** 2, 1)
            - 0.01 * np.sum((actions - self.last_action) ** 2, 1)
        ) * (DT * DECIMATION)
        self.last_action = actions
        self.steps += 1
        fell = (qpos[:, 2] < 0.18) | (gravity[:, 2] > -math.cos(1.0))
        timeout = self.steps >= EPISODE_STEPS
        done = fell | timeout
        if done.any():
            self.reset(done)
            obs, priv = self.observe()[:2]
        return obs, priv, reward.astype(np.float32), fell, timeout & ~fell


def mlp(inp, out, hidden=(512, 256, 128)):
    import torch

    layers, width = [], inp
    for h in hidden:
        layers += [torch.nn.Linear(width, h), torch.nn.ELU()]
        width = h
    return torch.nn.Sequential(*layers, torch.nn.Linear(width, out))


def main():
    # Imported here, not at the top: python_vs_mujoco.py uses Envs alone, without PyTorch.
    import torch

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--iterations", type=int, default=12)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--envs", type=int, default=128)
    p.add_argument("--steps", type=int, default=24)
    p.add_argument("--cenet", action="store_true", help="the full method's networks, without masks")
    p.add_argument("--minibatches", type=int, help="default 4, or 2 with --cenet")
    p.add_argument("--json", action="store_true")
    a = p.parse_args()
    minibatches = a.minibatches or (2 if a.cenet else 4)
    torch.set_num_threads(a.threads)
    torch.manual_seed(0)
    envs = Envs(a.envs, a.threads, 0)
    obs, priv = envs.observe()[:2]
    history_len, latent = 5, 16
    context = 3 + latent  # the velocity estimate and the latent means
    actor, critic = mlp(obs.shape[1] + (context if a.cenet else 0), 12), mlp(priv.shape[1], 1)
    log_std = torch.nn.Parameter(torch.zeros(12))
    params = list(actor.parameters()) + list(critic.parameters()) + [log_std]
    if a.cenet:
        encoder = mlp(history_len * obs.shape[1], context + latent, (256, 128))
        decoder = mlp(context, obs.shape[1], (128, 256))
        params += list(encoder.parameters()) + list(decoder.parameters())
        history = np.zeros((a.envs, history_len, obs.shape[1]), dtype=np.float32)
        history[:, -1] = obs
    opt = torch.optim.Adam(params, lr=1e-3)
    n, T = a.envs, a.steps
    rows = []
    # Rows the update draws minibatches from, then the per-step columns GAE reads.
    sampled = ("obs", "priv", "act", "logp") + (("hist", "ctx", "next", "vel") if a.cenet else ())
    keys = sampled[:4] + ("val", "rew", "term", "trunc") + sampled[4:]
    for it in range(a.iterations):
        t0 = time.perf_counter()
        physics = inference = 0.0
        buf = {k: [] for k in keys}
        for _ in range(T):
            t = time.perf_counter()
            with torch.no_grad():
                o, pv = torch.from_numpy(obs), torch.from_numpy(priv)
                if a.cenet:
                    h = torch.from_numpy(history.reshape(n, -1).copy())
                    est = encoder(h)
                    ctx = est[:, :context]
                    mean = actor(torch.cat([o, ctx], 1))
                else:
                    mean = actor(o)
                value = critic(pv).squeeze(1)
                dist = torch.distributions.Normal(mean, log_std.exp())
                act = dist.sample()
                logp = dist.log_prob(act).sum(1)
            inference += time.perf_counter() - t
            t = time.perf_counter()
            obs2, priv2, rew, term, trunc = envs.step(act.numpy().astype(np.float64))
            physics += time.perf_counter() - t
            for k, v in zip(buf, (o, pv, act, logp, value, rew, term, trunc)):
                buf[k].append(torch.as_tensor(v))
            if a.cenet:
                # The next observation before a reset would be the target; the batch's is close
                # enough for a throughput harness. A reset env's history restarts.
                buf["hist"].append(h)
                buf["ctx"].append(ctx)
                buf["next"].append(torch.from_numpy(obs2))
                buf["vel"].append(pv[:, -3:] * 0.5)  # the base velocity: the privileged part
                history = np.roll(history, -1, axis=1)
                history[:, -1] = obs2
                history[term | trunc, :-1] = 0.0
            obs, priv = obs2, priv2
        t = time.perf_counter()
        with torch.no_grad():
            last = critic(torch.from_numpy(priv)).squeeze(1)
        inference += time.perf_counter() - t
        rew, val = torch.stack(buf["rew"]), torch.stack(buf["val"])
        term, trunc = torch.stack(buf["term"]).float(), torch.stack(buf["trunc"]).float()
        rew = rew + 0.99 * trunc * val  # time-out bootstrap (legged_gym)
        adv, gae = torch.zeros(T, n), torch.zeros(n)
        for s in reversed(range(T)):
            nxt = last if s == T - 1 else val[s + 1]
            delta = rew[s] + 0.99 * nxt * (1 - term[s]) - val[s]
            gae = delta + 0.99 * 0.95 * (1 - term[s]) * gae
            adv[s] = gae
        ret = (adv + val).reshape(-1)
        adv = adv.reshape(-1)
        flat = {k: torch.stack(buf[k]).reshape(T * n, -1).squeeze(-1) for k in sampled}
        t = time.perf_counter()
        for _ in range(5):
            for idx in torch.randperm(T * n).chunk(minibatches):
                o = flat["obs"][idx]
                mean = actor(torch.cat([o, flat["ctx"][idx]], 1) if a.cenet else o)
                dist = torch.distributions.Normal(mean, log_std.exp())
                logp = dist.log_prob(flat["act"][idx]).sum(1)
                ratio = (logp - flat["logp"][idx]).exp()
                a_ = adv[idx]
                a_ = (a_ - a_.mean()) / (a_.std() + 1e-8)
                pg = -torch.min(ratio * a_, ratio.clamp(0.8, 1.2) * a_).mean()
                v = critic(flat["priv"][idx]).squeeze(1)
                loss = pg + ((v - ret[idx]) ** 2).mean() - 0.01 * dist.entropy().sum(1).mean()
                if a.cenet:
                    est = encoder(flat["hist"][idx])
                    vel, mu, logvar = est[:, :3], est[:, 3:context], est[:, context:]
                    z = mu + torch.randn_like(mu) * (0.5 * logvar).exp()
                    rec = decoder(torch.cat([vel, z], 1))
                    kl = -0.5 * (1 + logvar - mu**2 - logvar.exp()).sum(1).mean()
                    cenet = ((vel - flat["vel"][idx]) ** 2).mean() + ((rec - flat["next"][idx]) ** 2).mean() + kl
                    loss = loss + cenet
                opt.zero_grad()
                loss.backward()
                torch.nn.utils.clip_grad_norm_(params, 1.0)
                opt.step()
        update = time.perf_counter() - t
        total = time.perf_counter() - t0
        rows.append((total, physics, inference, update))
        if not a.json:
            print(f"iteration {it + 1}: {T * n / total:.0f} env steps/s, physics {physics * 1e3:.0f} ms, "
                  f"inference {inference * 1e3:.0f} ms, update {update * 1e3:.0f} ms, reward {rew.mean():.4f}")
    m = np.mean(rows[2:], axis=0) if len(rows) > 2 else np.mean(rows, axis=0)
    out = {
        "py_env_steps_per_s": T * n / m[0],
        "py_iteration_ms": m[0] * 1e3,
        "py_physics_ms": m[1] * 1e3,
        "py_inference_ms": m[2] * 1e3,
        "py_update_ms": m[3] * 1e3,
        "py_other_ms": (m[0] - m[1] - m[2] - m[3]) * 1e3,
        "threads": a.threads,
        "cenet": a.cenet,
        "minibatches": minibatches,
        "torch": torch.__version__,
        "mujoco": mujoco.__version__,
        "measured_iterations": max(len(rows) - 2, 1),
    }
    print(json.dumps(out, indent=None if a.json else 2))


if __name__ == "__main__":
    main()
