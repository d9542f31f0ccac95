"""`legged export RUN --onnx`: the deterministic actor as ONNX, checked against the framework's own output."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import torch

from legged.files import atomic_path
from policies.policy_io import Policy, load_policy

PARITY_ATOL = 1e-4
"""Largest action difference allowed between the ONNX model and the framework policy."""


class BraxActor(torch.nn.Module):
    """Brax PPO's deterministic policy in torch: normalise, MLP (swish), tanh of the mean."""

    def __init__(self, normalizer, policy_params, num_actions: int):
        super().__init__()
        self.register_buffer("mean", torch.as_tensor(np.asarray(normalizer.mean["state"]), dtype=torch.float32))
        self.register_buffer("std", torch.as_tensor(np.asarray(normalizer.std["state"]), dtype=torch.float32))
        layers = policy_params["params"]
        self.linears = torch.nn.ModuleList()
        for k in range(sum(name.startswith("hidden_") for name in layers)):
            w, b = np.asarray(layers[f"hidden_{k}"]["kernel"]), np.asarray(layers[f"hidden_{k}"]["bias"])
            linear = torch.nn.Linear(w.shape[0], w.shape[1])
            linear.weight.data = torch.as_tensor(w.T.copy())
            linear.bias.data = torch.as_tensor(b.copy())
            self.linears.append(linear)
        self.num_actions = num_actions

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        x = (obs - self.mean) / self.std
        for k, linear in enumerate(self.linears):
            x = linear(x)
            if k < len(self.linears) - 1:
                x = x * torch.sigmoid(x)  # swish, Brax's default activation
        return torch.tanh(x[..., : self.num_actions])


def actor_module(policy: Policy) -> torch.nn.Module:
    """The policy as a torch module mapping actor observations to actions."""
    if policy.backend == "rsl":
        return policy.torch_module
    return BraxActor(*policy.brax_params, policy.num_actions).eval()


def export_onnx(policy: Policy, path: str | Path, samples: int = 64, seed: int = 0) -> dict:
    """Write the ONNX model and compare it with the policy on random observations; returns the check. The
    model is written to a temporary file and checked there: `path` is replaced only by a model that passed."""
    import onnxruntime

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    module = actor_module(policy)
    # one ONNX input per observation group the actor reads: `obs` (the state), then e.g. `history` or `camera`
    names = ["obs" if g == "state" else g for g in policy.inputs]
    shape = lambda g: (policy.obs_sizes[g],) if isinstance(policy.obs_sizes[g], int) else tuple(policy.obs_sizes[g])
    dummy = tuple(torch.zeros(1, *shape(g)) for g in policy.inputs)
    recurrent = getattr(module, "is_recurrent", False)  # memory in, memory out (policies.memory_models)
    inputs, outputs = names + (["memory"] if recurrent else []), ["actions"] + (["memory_out"] if recurrent else [])
    if recurrent:
        dummy = dummy + (module.initial_memory(1),)
    axes = {n: {0: "batch"} for n in names} | {"actions": {0: "batch"}} | \
        ({"memory": {1: "batch"}, "memory_out": {1: "batch"}} if recurrent else {})
    rng = np.random.default_rng(seed)
    draw = lambda g: (rng.random((samples, *shape(g)), dtype=np.float32) if len(shape(g)) > 1 else
                      rng.normal(size=(samples, *shape(g))).astype(np.float32))  # images in [0, 1]
    with atomic_path(path) as tmp:  # replaced only when the block ends without an error, else removed
        with warnings.catch_warnings():  # the GRU's batch warning: its initial memory is an input, as it asks
            warnings.filterwarnings("ignore", message="Exporting a model to ONNX with a batch_size other than 1")
            torch.onnx.export(module, dummy, str(tmp), input_names=inputs, output_names=outputs, dynamic_axes=axes,
                              opset_version=18, dynamo=False)
        session = onnxruntime.InferenceSession(str(tmp), providers=["CPUExecutionProvider"])
        policy.reset()
        memory, gap, largest = (module.initial_memory(samples).numpy() if recurrent else None), 0.0, 0.0
        for _ in range(3 if recurrent else 1):  # a model with memory: three steps, its memory carried
            groups = {g: draw(g) for g in policy.inputs}
            feeds = {n: groups[g] for n, g in zip(names, policy.inputs)} | ({"memory": memory} if recurrent else {})
            result = session.run(outputs, feeds)
            memory = result[-1] if recurrent else None
            gap = max(gap, float(np.abs(result[0] - policy.act(groups)).max()))
            largest = max(largest, float(np.abs(result[0]).max()))
        policy.reset()
        if not gap <= PARITY_ATOL:
            raise ValueError(f"ONNX export of {policy.checkpoint} differs from the policy by {gap:.2e} "
                             f"(allowed {PARITY_ATOL:.0e}); {path} was left as it was")
        if policy.action_bound is not None and largest > policy.action_bound + 1e-6:
            raise ValueError(f"ONNX export of {policy.checkpoint} returns actions up to {largest:.3g}, outside its "
                             f"+-{policy.action_bound:g}; {path} was left as it was")
    return {"onnx": str(path), "checkpoint": str(policy.checkpoint), "backend": policy.backend,
            "obs_size": policy.obs_size, "inputs": inputs, "outputs": outputs, "num_actions": policy.num_actions,
            "max_abs_diff": gap, "samples": samples, "action_bound": policy.action_bound, "max_abs_action": largest}


def export_run(run_dir: str, checkpoint: str | None = None, out: str | Path | None = None) -> dict:
    """Export the policy of `run_dir` (its `checkpoint`, default its newest) with `export_onnx` to `out` (default
    RUN_DIR/policy.onnx); returns the check. A piloted vision student deploys as two networks, it estimates and
    the pilot steers: the pilot is exported beside it (<out>_pilot.onnx) and its check reported as `pilot`."""
    policy, config = load_policy(run_dir, checkpoint)
    out = Path(out or f"{run_dir}/policy.onnx")
    report = export_onnx(policy, out)
    if config.soccer.pilot:
        pilot, _ = load_policy(config.soccer.pilot)
        report["pilot"] = dict(export_onnx(pilot, out.with_name(f"{out.stem}_pilot.onnx")), run=config.soccer.pilot)
    return report
