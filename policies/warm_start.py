"""Warm start: begin a PPO run from the networks of a trained run of another task (e.g. the confined
follower from the go1-flat walker), or of the same task (a fine-tune: its networks as they are, e.g. to go on with
new rewards, through the layouts when its observations grew, e.g. by the randomisation's draws in the privileged
state; its optimiser and curriculum levels too, so that it goes on as a resumed run would).

The two tasks' observations differ, so the first layer is rebuilt input by input from the observations'
named layouts (`LeggedEnv.observation_layout`): an input both tasks have keeps its weights and its
normaliser statistics; a waypoint command component reads the weights of the velocity command it resembles
(a waypoint ahead is read as "walk that way"); a new input (e.g. height scans) starts with zero weights, so
the warm-started policy first acts exactly as the source policy did. Deeper layers and the action noise
are copied as they are, which needs the same hidden sizes.
"""

from __future__ import annotations

from functools import cached_property
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
(a new input's statistics are measured over a rollout, WARM_UP_STEPS)."""

OPTIMISER_NOTE = {"moments": "its optimiser's moments and learning rate",
                  "rate": "a new optimiser at the learning rate the source had reached (a slimmed run keeps only that)",
                  "new": "a new optimiser (the source's is missing or does not fit)"}
"""How the note of a warm start from the same task names the optimiser it starts with (continue_optimiser)."""

WARM_UP_STEPS = 100
"""Steps of every environment that a warm start from the same task rolls out, its policy acting, to measure the
statistics of inputs the source did not have. The normaliser keeps the source's sample count (tens of millions), so
those statistics are never revised in training: taken from the first batch (every episode at its start) they were
five times too narrow for the rest of an episode (a waypoint preview's std 0.035 m against 0.17 m over a rollout),
and the fine-tune fell."""


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


def continue_optimiser(alg, saved: dict, columns: dict | None = None, rate: float | None = None) -> str:
    """Load the source's optimiser state (`saved`: its checkpoint's "alg") into `alg`'s, so that a fine-tune of the same
    task updates as a resumed run would: Adam's moments, and with the adaptive schedule the learning rate it had
    reached (a fixed schedule keeps this run's). `columns` maps a first-layer weight (by id) rebuilt by layout to its
    source column per column (-1: a new input, whose moments start at zero). A new optimiser's first update, at the
    configured rate (1e-3 against the 5e-5 the source had settled at), threw a trained follower off: training falls
    went from 20% to 50-75%. Returns the OPTIMISER_NOTE key: "moments"; "rate" when the source kept only the rate
    it had reached (`rate`, a slimmed checkpoint's `learning_rate`) and the schedule is adaptive: the new optimiser
    starts there; "new", the optimiser left as it was, when the source has neither or its state does not fit."""
    source = saved.get("optimizer_state_dict")
    params = [p for group in alg.optimizer.param_groups for p in group["params"]]
    if source is None or [len(g["params"]) for g in source["param_groups"]] != [
            len(g["params"]) for g in alg.optimizer.param_groups]:
        if source is not None or rate is None or getattr(alg, "schedule", None) != "adaptive":
            return "new"
        alg.learning_rate = float(rate)
        for group in alg.optimizer.param_groups:
            group["lr"] = float(rate)
        return "rate"
    columns = columns or {}
    state = {"param_groups": source["param_groups"], "state": {}}
    for i, entry in source["state"].items():
        entry, mapping = dict(entry), columns.get(id(params[i]))
        for key in ("exp_avg", "exp_avg_sq"):
            if mapping is not None and key in entry:
                known, src = torch.as_tensor(mapping >= 0), torch.as_tensor(np.maximum(mapping, 0))
                entry[key] = torch.where(known[None, :], entry[key][:, src], torch.zeros(()))
            if key in entry and entry[key].shape != params[i].shape:
                return "new"
        state["state"][i] = entry
    configured = alg.learning_rate
    alg.optimizer.load_state_dict(state)
    if getattr(alg, "schedule", None) == "adaptive":
        alg.learning_rate = alg.optimizer.param_groups[0]["lr"]
    else:
        for group in alg.optimizer.param_groups:
            group["lr"] = configured
    return "moments"


def _first_weight(net) -> torch.nn.Parameter:
    """A network's first-layer weight (the one a warm start rebuilds by layout)."""
    return dict(net.named_parameters())["mlp.0.weight"]


class SourceRun:
    """The trained run a warm start reads: its config and latest checkpoint, each read once however many parts of
    the start (levels, networks, optimiser) need them."""

    def __init__(self, path: Path | str):
        self.run = RunDir(Path(path))
        self.config = self.run.load_config()

    @cached_property
    def checkpoint(self) -> Path:
        """The latest checkpoint's path (looked up when first needed: a run of another backend fails on that first)."""
        return self.run.latest_checkpoint()

    @cached_property
    def payload(self) -> dict:
        """The latest checkpoint's contents (networks, optimiser, curriculum levels)."""
        return load_rsl_checkpoint(self.checkpoint)

    def trained(self, task: str) -> bool:
        """Whether this run trained `task` with rsl-rl (a fine-tune: its optimiser and levels go on)."""
        return self.config.task == task and self.config.backend == "rsl"

    def layout(self) -> dict:
        """The observation layout of the task this run trained, without compiling its environment."""
        if self.config.backend != "rsl":
            raise RunDirError(f"cannot warm start from {self.run.path}: it was trained with the {self.config.backend} "
                              "backend (warm starts read rsl-rl checkpoints)")
        env = make(self.config.task, self.config.env)
        if not hasattr(env, "observation_layout"):
            raise RunDirError(f"cannot warm start from {self.run.path}: task {self.config.task} has no named "
                              "observation layout")
        return env.observation_layout()


def _source(run: SourceRun | Path | str) -> SourceRun:
    """`run` as a SourceRun (read now when given as a path)."""
    return run if isinstance(run, SourceRun) else SourceRun(run)


def source_levels(source: SourceRun | Path, task: str, num_envs: int) -> torch.Tensor | None:
    """The curriculum level of each of `num_envs` environments for a warm start of `task` from `source`: its latest
    checkpoint's levels (repeated or cut to `num_envs`) if it trained the same task with a curriculum, else None. A
    fine-tune then goes on where its source stood instead of relearning the easiest levels, whose worlds its critic
    had stopped valuing (restarted at level 0 with a new optimiser, a 21M-step follower fell in 50-75% of its
    training episodes)."""
    source = _source(source)
    if not source.trained(task):  # another task's, or not one warm_start reads
        return None
    levels = source.payload.get("curriculum_levels")
    return None if levels is None else torch.as_tensor(np.resize(levels.numpy(), num_envs))


def same_task_start(alg, source: SourceRun, task: str) -> str | None:
    """Load the latest actor and critic (normalisers and action noise included) of `source` into `alg` as they
    are, if that run trained `task` with rsl-rl on observations of the same sizes (a new run of the same task, e.g.
    with other rewards); None if it trained another task or other observations. Returns a summary."""
    if not source.trained(task):
        return None
    path, saved = source.checkpoint, source.payload["alg"]
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
    optimiser = OPTIMISER_NOTE[continue_optimiser(alg, saved, rate=source.payload.get("learning_rate"))]
    return f"warm start from {path}: the same task, every weight and normaliser statistic as they were; {optimiser}"


def rollout_statistics(venv, actor, hooks, steps: int = WARM_UP_STEPS) -> dict:
    """{group: (mean, std)} of each observation group over `steps` steps of every environment of `venv` (an rsl-rl
    vector environment), `actor` acting with sampled actions as in training, `hooks` (policies.training_hooks)
    called as in a rollout. Nothing is learned, no normaliser moves, the episodes that end are not reported."""
    obs = venv.get_observations()
    sums = {k: [torch.zeros(obs[k].shape[1:], dtype=torch.float64) for _ in range(2)] for k in obs.keys()}
    count = 0
    hooks.before_rollout(venv)
    with torch.inference_mode():
        for step in range(steps + 1):
            for k, (total, squares) in sums.items():
                x = obs[k].double()
                total += x.sum(0)
                squares += (x * x).sum(0)
            count += obs[next(iter(sums))].shape[0]
            if step < steps:
                obs, _, dones, _ = venv.step(actor(obs, stochastic_output=True))
                actor.reset(dones)  # a recurrent actor forgets the episodes that ended (as in training)
                hooks.after_step(dones)
    venv.episode_stats.means()  # the warm-up's episodes are not the first iteration's
    out = {}
    for k, (total, squares) in sums.items():
        mean = total / count
        var = (squares / count - mean * mean).clamp_min(0.0) * count / max(count - 1, 1)
        out[k] = (mean.float(), var.sqrt().float())
    return out


def warm_start(alg, source: SourceRun | Path, env, obs, task: str = "", observe=None) -> str:
    """Load `source`'s latest actor and critic into `alg` (rsl-rl PPO of `env`, training `task`): as they are
    if the source trained the same task, else through the observation layouts; `obs` is a first batch of
    observations (statistics of the new inputs). `observe(alg)`, when given, returns {group: (mean, std)} over a
    rollout of the warm-started policy (rollout_statistics): a warm start from the same task takes its new inputs'
    statistics from it. Returns a summary."""
    source = _source(source)
    same = same_task_start(alg, source, task)
    if same is not None:
        return same
    if not hasattr(env, "observation_layout"):
        raise RunDirError(f"cannot warm start this task ({type(env).__name__}): it has no named observation layout")
    layout, path, saved = source.layout(), source.checkpoint, source.payload["alg"]
    target_layout = env.observation_layout()
    nets = ((alg.actor, "state", "actor_state_dict"), (alg.critic, "privileged_state", "critic_state_dict"))
    maps = {group: input_map(element_names(layout[group]), element_names(target_layout[group])) for _, group, _ in nets}
    # the same task: the source's statistics stay as settled as they were (restarting the count let the first
    # iterations' observations, e.g. a curriculum's easiest level, pull the settled ones away)
    keep = source.config.task == task

    def load(stats: dict) -> None:
        for net, group, key in nets:
            mean, std = stats[group]
            net.load_state_dict(_rebuild(saved[key], net.state_dict(), maps[group], mean, std.clamp_min(1e-2), keep))

    load({group: (obs[group].float().mean(0), obs[group].float().std(0)) for group in maps})
    report = [f"{group}: {int((m >= 0).sum())} of {len(m)} inputs from the source" for group, m in maps.items()]
    if keep and observe is not None and any((m < 0).any() for m in maps.values()):
        load(observe(alg))  # the new inputs have zero weights: the rollout is the source policy's
        report.append("the new inputs' statistics measured over a rollout")
    if keep:  # another task's optimiser state means nothing here
        columns = {id(_first_weight(net)): maps[group] for net, group, _ in nets}
        report.append(OPTIMISER_NOTE[continue_optimiser(alg, saved, columns, source.payload.get("learning_rate"))])
    return f"warm start from {path}: " + "; ".join(report)
