#!/usr/bin/env python3
"""Loads a safetensors policy written by `quadcl export --format safetensors`
into a PyTorch module and prints it: `encoder` and `actor` are nn.Sequential
MLPs whose keys the file holds as they are (`actor.0.weight`, ...), the
observation normaliser and the action transform are buffers. With a reference
file (`quadcl export --reference`) it also compares its actions with quadcl's.

    python3 scripts/load_exported.py crash_FL.safetensors [--check]
    (pip install torch safetensors)

From your own code:

    from load_exported import QuadclPolicy
    policy = QuadclPolicy.from_file("crash_FL.safetensors")
    actions, joint_targets = policy(obs_history)   # (N, H * 45) -> (N, 12), (N, 12)
"""
import json
import sys

import torch
from safetensors import safe_open
from safetensors.torch import load_file
from torch import nn


def mlp(sizes, activation):
    layers = []
    for i in range(len(sizes) - 1):
        layers.append(nn.Linear(sizes[i], sizes[i + 1]))
        if i < len(sizes) - 2:
            layers.append(getattr(nn, activation)())
    return nn.Sequential(*layers)


class QuadclPolicy(nn.Module):
    def __init__(self, meta):
        super().__init__()
        self.meta = meta
        self.obs_dim, self.history_len = meta["obs_dim"], meta["history_len"]
        self.actor = mlp(meta["actor_sizes"], meta["actor_activation"])
        self.encoder = mlp(meta["encoder_sizes"], meta["encoder_activation"]) if "encoder_sizes" in meta else None
        self.normalize = meta["obs_normalization"]["inside_model"]
        if self.normalize:
            self.register_buffer("obs_normalizer_mean", torch.zeros(self.obs_dim))
            self.register_buffer("obs_normalizer_scale", torch.ones(self.obs_dim))
        for name in ("default_joint_pos", "joint_lower", "joint_upper"):
            self.register_buffer(name, torch.zeros(12))

    @classmethod
    def from_file(cls, path):
        with safe_open(path, framework="pt") as f:
            meta = {k: json.loads(v) if k != "format" else v for k, v in f.metadata().items()}
        policy = cls(meta)
        state = {k.replace("obs_normalizer.", "obs_normalizer_"): v for k, v in load_file(path).items()}
        policy.load_state_dict(state, strict=True)
        return policy.eval()

    @torch.no_grad()
    def forward(self, obs_history):
        h = obs_history
        if self.normalize:
            clip = self.meta["obs_clip"]
            mean = self.obs_normalizer_mean.repeat(self.history_len)
            scale = self.obs_normalizer_scale.repeat(self.history_len)
            h = torch.clamp((h - mean) * scale, -clip, clip)
        x = h[:, -self.obs_dim:]
        if self.encoder is not None:
            x = torch.cat([x, self.encoder(h)[:, : self.meta["context_dim"]]], dim=1)
        clip = self.meta["clip_actions"]
        actions = torch.clamp(self.actor(x), -clip, clip)
        targets = self.default_joint_pos + self.meta["action_scale"] * actions
        return actions, torch.minimum(torch.maximum(targets, self.joint_lower), self.joint_upper)


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    path = sys.argv[1]
    policy = QuadclPolicy.from_file(path)
    print(policy)
    print(f"task {policy.meta['task']}, joints {policy.meta['joint_names']}")
    if "--check" in sys.argv[2:]:
        reference = load_file(f"{path}.reference.safetensors")
        actions, targets = policy(reference["obs_history"])
        diff = max(float((actions - reference["actions"]).abs().max()),
                   float((targets - reference["joint_targets"]).abs().max()))
        print(f"max |diff| from quadcl's actions and joint targets: {diff:.2e}")
        sys.exit(0 if diff <= 1e-5 else 1)


if __name__ == "__main__":
    main()
