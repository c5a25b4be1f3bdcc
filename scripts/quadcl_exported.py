"""Loads a policy written by `quadcl export` and runs it with no quadcl code:
an ONNX model in ONNX Runtime, or a safetensors file with NumPy (the same
layers PyTorch's nn.Sequential would run; scripts/load_exported.py builds that
module). Imported by scripts/check_export.py and scripts/policy_server.py.

    policy = load("crash_FL.onnx")          # or .safetensors
    out = policy(obs_history)                # (N, H * 45) float32, oldest frame first
    out["actions"], out["joint_targets"]     # (N, 12) each
    policy.metadata["joint_names"]           # the contract, values decoded from JSON
"""
import json

import numpy as np


class Exported:
    def __init__(self, path, metadata, run):
        self.path = str(path)
        self.metadata = {k: _decode(v) for k, v in metadata.items()}
        self._run = run

    def __call__(self, obs_history):
        return self._run(np.ascontiguousarray(obs_history, dtype=np.float32))


def _decode(value):
    try:
        return json.loads(value)
    except (TypeError, ValueError):
        return value


def load(path):
    path = str(path)
    if path.endswith(".onnx"):
        return _load_onnx(path)
    if path.endswith(".safetensors"):
        return _load_safetensors(path)
    raise ValueError(f"{path}: not an .onnx or .safetensors file")


def _load_onnx(path):
    import onnxruntime as ort

    session = ort.InferenceSession(path, providers=["CPUExecutionProvider"])
    metadata = session.get_modelmeta().custom_metadata_map

    def run(history):
        actions, targets = session.run(["actions", "joint_targets"], {"obs_history": history})
        return {"actions": actions, "joint_targets": targets}

    return Exported(path, metadata, run)


def _activation(name):
    return {
        "ELU": lambda x: np.where(x > 0, x, np.expm1(np.minimum(x, 0))),
        "ReLU": lambda x: np.maximum(x, 0),
        "Tanh": np.tanh,
        "Identity": lambda x: x,
    }[name]


def _mlp(tensors, prefix, sizes, activation):
    layers = len(sizes) - 1

    def run(x):
        for i in range(layers):
            x = x @ tensors[f"{prefix}.{2 * i}.weight"].T + tensors[f"{prefix}.{2 * i}.bias"]
            if i < layers - 1:
                x = activation(x)
        return x.astype(np.float32)

    return run


def _load_safetensors(path):
    from safetensors import safe_open
    from safetensors.numpy import load_file

    tensors = load_file(path)
    with safe_open(path, framework="np") as f:
        metadata = f.metadata()
    meta = {k: _decode(v) for k, v in metadata.items()}
    obs_dim, history_len = meta["obs_dim"], meta["history_len"]
    actor = _mlp(tensors, "actor", meta["actor_sizes"], _activation(meta["actor_activation"]))
    encoder = None
    if "encoder_sizes" in meta:
        encoder = _mlp(tensors, "encoder", meta["encoder_sizes"], _activation(meta["encoder_activation"]))
    clip_actions = np.float32(meta["clip_actions"])

    def run(history):
        h = history
        if "obs_normalizer.mean" in tensors:
            mean = np.tile(tensors["obs_normalizer.mean"], history_len)
            scale = np.tile(tensors["obs_normalizer.scale"], history_len)
            clip = np.float32(meta["obs_clip"])
            h = np.clip((h - mean) * scale, -clip, clip)
        x = h[:, -obs_dim:]
        if encoder is not None:
            x = np.concatenate([x, encoder(h)[:, : meta["context_dim"]]], axis=1)
        actions = np.clip(actor(x), -clip_actions, clip_actions)
        targets = tensors["default_joint_pos"] + np.float32(meta["action_scale"]) * actions
        targets = np.minimum(np.maximum(targets, tensors["joint_lower"]), tensors["joint_upper"])
        return {"actions": actions, "joint_targets": targets.astype(np.float32)}

    return Exported(path, metadata, run)
