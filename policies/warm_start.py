"""Warm start: begin a PPO run from the networks of a trained run of another task (e.g. the confined
follower from the go1-flat walker), or of the same task (its networks as they are, e.g. to go on with new
rewards; through the layouts when its observations grew, e.g. by the randomisation's draws in the privileged
state).

The two tasks' observations differ, so the first layer is rebuilt input by input from the observations'
named layouts (`LeggedEnv.observation_layout`): an input both tasks have keeps its weights and its
normaliser statistics; a waypoint command component reads the weights of the velocity command it resembles
(a waypoint ahead is read as "walk that way"); a new input (e.g. height scans) starts with zero weights, so
the warm-started policy first acts exactly as the source policy did. Deeper layers and the action noise
are copied as they are, which needs the same hidden sizes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from legged.tasks import make
from policies.checkpoints import load_rsl_checkpoint
from policies.run_dir import RunDir, RunDirError

ALIASES = {"command/dx": "command/vx", "command/dy": "command/vy", "command/dyaw": "command/yaw_rate"}
"""Inputs of the target task that read the weights of a differently named input of the source task."""

ADAPT_SAMPLES = 1_000_000
"""Normaliser sample count after a warm start from another task: its statistics then follow the new observations
within the first few dozen iterations instead of staying the source's. From the same task the source's count stays
(a new input's statistics start at the first batch's)."""


def element_names(layout: list[tuple[str, int]]) -> list[str]:
    """One name per observation element: 'name' for a slice of size 1 (the layout spells the command out
    component by component), 'name[size]/i' for element i of a longer slice: a slice of another size (a height scan
    on another grid) is another input, not the same one read at other points."""
    out = []
    for name, size in layout:
        out.extend([name] if size == 1 else [f"{name}[{size}]/{i}" for i in range(size)])
    return out


def input_map(source: list[str], target: list[str]) -> np.ndarray:
    """For each target input, the index of the source input it takes its weights from, or -1."""
    where = {n: i for i, n in enumerate(source)}
    def find(name):
        key = name.removeprefix("state/")
        for candidate in (name, ALIASES.get(key), f"state/{ALIASES.get(key)}" if key in ALIASES else None):
            if candidate is not None and candidate in where:
                return where[candidate]
        return -1
    return np.array([find(n) for n in target])


def _rebuild(source: dict, target: dict, mapping: np.ndarray, fresh_mean: torch.Tensor,
             fresh_std: torch.Tensor, keep_count: bool = False) -> dict:
    """Target network state: first layer and normaliser rebuilt through `mapping`, the rest copied. The
    normaliser's sample count restarts at ADAPT_SAMPLES unless `keep_count` (the same task: the source's statistics stay
    settled; inputs it lacks take `fresh_mean` and `fresh_std`)."""
    out = dict(target)
    known = torch.as_tensor(mapping >= 0)
    src_idx = torch.as_tensor(np.maximum(mapping, 0))
    w = source["mlp.0.weight"][:, src_idx]
    out["mlp.0.weight"] = torch.where(known[None, :], w, torch.zeros_like(w))
    for key in ("_mean", "_var", "_std"):
        name = f"obs_normalizer.{key}"
        if name in source:
            fresh = {"_mean": fresh_mean, "_var": fresh_std ** 2, "_std": fresh_std}[key].reshape(1, -1)
            out[name] = torch.where(known[None, :], source[name][:, src_idx], fresh)
    if "obs_normalizer.count" in out:
        count = source["obs_normalizer.count"] if keep_count and "obs_normalizer.count" in source else ADAPT_SAMPLES
        out["obs_normalizer.count"] = torch.as_tensor(count, dtype=out["obs_normalizer.count"].dtype)
    for name, value in source.items():
        if name == "mlp.0.weight" or name.startswith("obs_normalizer"):
            continue
        if name not in out or out[name].shape != value.shape:
            raise RunDirError(f"cannot warm start: layer {name} has shape {tuple(value.shape)} in the source run and "
                              f"{tuple(out[name].shape) if name in out else 'none'} here; use the source run's "
                              "ppo.actor_hidden and ppo.critic_hidden")
        out[name] = value
    return out


def source_layout(run_path: Path) -> tuple[dict, Path, str]:
    """(observation layout, latest checkpoint, task) of a trained rsl run, without compiling its environment."""
    run = RunDir(Path(run_path))
    config = run.load_config()
    if config.backend != "rsl":
        raise RunDirError(f"cannot warm start from {run.path}: it was trained with the {config.backend} backend "
                          "(warm starts read rsl-rl checkpoints)")
    env = make(config.task, config.env)
    if not hasattr(env, "observation_layout"):
        raise RunDirError(f"cannot warm start from {run.path}: task {config.task} has no named observation layout")
    return env.observation_layout(), run.latest_checkpoint(), config.task


def same_task_start(alg, run_path: Path, task: str) -> str | None:
    """Load the latest actor and critic (normalisers and action noise included) of `run_path` into `alg` as they
    are, if that run trained `task` with rsl-rl on observations of the same sizes (a new run of the same task, e.g.
    with other rewards); None if it trained another task or other observations. Returns a summary."""
    run = RunDir(Path(run_path))
    config = run.load_config()
    if config.task != task or config.backend != "rsl":
        return None
    path = run.latest_checkpoint()
    saved = load_rsl_checkpoint(path)["alg"]
    nets = ((alg.actor, "actor_state_dict"), (alg.critic, "critic_state_dict"))
    differ = {name for net, key in nets for name, value in net.state_dict().items()
              if name in saved[key] and saved[key][name].shape != value.shape}
    if differ and differ <= {"mlp.0.weight"} | {n for n in differ if n.startswith("obs_normalizer.")}:
        return None  # only its observations changed (e.g. the randomisation grew the privileged state): by layout
    for net, key in nets:
        try:
            net.load_state_dict(saved[key])
        except RuntimeError as e:
            raise RunDirError(f"cannot warm start from {path}: its {key.split('_')[0]} does not fit this run's "
                              f"(use the source run's ppo.actor_hidden, ppo.critic_hidden and observations): "
                              f"{str(e).splitlines()[0]}") from None
    return f"warm start from {path}: the same task, every weight and normaliser statistic as they were"


def warm_start(alg, run_path: Path, env, obs, task: str = "") -> str:
    """Load `run_path`'s latest actor and critic into `alg` (rsl-rl PPO of `env`, training `task`): as they are
    if the source trained the same task, else through the observation layouts; `obs` is a first batch of
    observations (statistics of the new inputs). Returns a summary."""
    same = same_task_start(alg, run_path, task)
    if same is not None:
        return same
    if not hasattr(env, "observation_layout"):
        raise RunDirError(f"cannot warm start this task ({type(env).__name__}): it has no named observation layout")
    layout, path, source_task = source_layout(run_path)
    saved = load_rsl_checkpoint(path)["alg"]
    target_layout = env.observation_layout()
    report = []
    for net, group, key in ((alg.actor, "state", "actor_state_dict"), (alg.critic, "privileged_state", "critic_state_dict")):
        mapping = input_map(element_names(layout[group]), element_names(target_layout[group]))
        x = obs[group].float()
        # the same task: the source's statistics stay as settled as they were, the new inputs' start at this batch's
        # (restarting the count let the first iterations' observations, e.g. a curriculum's easiest level, pull the
        # settled ones away)
        keep = source_task == task
        net.load_state_dict(_rebuild(saved[key], net.state_dict(), mapping, x.mean(0), x.std(0).clamp_min(1e-2),
                                     keep))
        report.append(f"{group}: {int((mapping >= 0).sum())} of {len(mapping)} inputs from the source")
    return f"warm start from {path}: " + "; ".join(report)
