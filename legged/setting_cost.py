"""What a task's settings cost its physics under its own randomisation: the task's native physics as it trains
(default config, randomisation on) and with one setting changed at a time (the friction-cone draws, the feet's
contact dimension, margin and softness, the level worlds, their height-map resolution), stepped side by side in one
process under the same random servo targets, every change of every task in each round, so that a machine's drift
touches them alike.

`legged.physics_cost` changes the solver options of a task's nominal model; this changes the task's config, which
is what a user sets (`--set env...`), and keeps each robot's randomised model fields. Both give costs only: whether a
cheaper setting costs a trained policy anything is measured by evaluating it under the change (`legged eval --set`).
"""

from __future__ import annotations

import dataclasses
import statistics
from typing import Callable

import mujoco
import numpy as np

from legged.bench import machine, physics_profile, random_controls, step_rate
from legged.envs.native import NativeEnvs, check_threads
from legged.physics_cost import picked
from legged.tasks import learner_env, make, task_entry


def _randomization(**fields) -> Callable:
    def edit(config):
        return dataclasses.replace(config, randomization=dataclasses.replace(config.randomization, **fields))
    return edit


def _level_resolution(resolution: float) -> Callable:
    def edit(config):
        levels = config.levels
        return dataclasses.replace(config, levels=dataclasses.replace(
            levels, resolution=resolution, tunnels=dataclasses.replace(levels.tunnels, resolution=resolution)))
    return edit


def _tunnels(config):
    return dataclasses.replace(config, levels=None)


def _has_levels(config) -> bool:
    return getattr(config, "levels", None) is not None


def _drawn(field: str) -> Callable[[object], bool]:
    return lambda config: getattr(config, "randomization", None) is not None and \
        config.randomization.enabled and getattr(config.randomization, field, None) is not None


@dataclasses.dataclass(frozen=True)
class Change:
    """One change of a task's config."""

    name: str
    """Short name (the command line's --changes)."""
    description: str
    """What it changes, in a few words."""
    edit: Callable
    """The task's config with the change (a new config)."""
    applies: Callable[[object], bool] = lambda config: True
    """Whether the change means anything for a task's default config."""


AS_TRAINED = Change("as-trained", "the task's default config, its randomisation on", lambda config: config)
CHANGES = (
    AS_TRAINED,
    Change("no-cone-draws", "every robot on the model's own friction cone and impratio (no elliptic or impratio "
                            "draws)", _randomization(elliptic_share=None, impratio=None), _drawn("elliptic_share")),
    Change("feet-condim-3", "the feet's floor pairs condim 3 (no drawn spin and roll friction, condim 6)",
           _randomization(contact_spin=None), _drawn("contact_spin")),
    Change("no-margin", "the feet's contact margin the model's own (no drawn 0-2 mm)",
           _randomization(contact_margin=None), _drawn("contact_margin")),
    Change("model-softness", "the feet's solimp and time constant the model's own (no drawn softness)",
           _randomization(contact_softness=None, contact_timeconst=None), _drawn("contact_softness")),
    Change("no-randomisation", "the randomisation off: every robot the nominal model",
           _randomization(enabled=False), lambda config: getattr(config, "randomization", None) is not None
           and config.randomization.enabled),
    Change("tunnels", "the pyramid tunnels instead of the level worlds", _tunnels, _has_levels),
    Change("heights-10cm", "the level worlds' height maps sampled every 10 cm instead of 5 cm",
           _level_resolution(0.1), _has_levels),
)
"""Every change the benchmark knows, the config as it trains first."""


def changes_named(names: list[str] | None) -> list[Change]:
    """The changes of `names` (None: all), as-trained always first; an unknown name is one clear error."""
    return picked(CHANGES, names, "setting change")


def _mean_profile(natives: NativeEnvs, sims: int, steps: int) -> dict:
    """MuJoCo's timers and constraint counts (legged.bench.physics_profile) averaged over the first `sims`
    simulations of a batch, each on its own randomised model from its current state."""
    batch = natives.physics.batch
    profiles, elliptic = [], []
    for i in range(min(sims, batch.nsim)):
        model, data = batch.get_model(i), batch.get_data(i)
        mujoco.mj_forward(model, data)
        profiles.append(physics_profile(model, [data], steps))
        elliptic.append(model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC)
    numeric = [k for k, v in profiles[0].items() if isinstance(v, (int, float)) and not isinstance(v, bool)]
    out = {k: round(float(np.mean([p[k] for p in profiles])), 2) for k in numeric}
    return {**out, "elliptic_share": round(float(np.mean(elliptic)), 3), "sims": len(profiles)}


def setting_cost(tasks: list[str], changes: list[Change] | None = None, batch: int = 256, threads: int = 2,
                 seconds: float = 5.0, repeats: int = 3, seed: int = 0, profile_sims: int = 8,
                 profile_steps: int = 100, progress=None) -> list[dict]:
    """One record per task and change that applies to it: control steps per second of its native physics at `batch`
    simulations and `threads` threads under random servo targets (median of `repeats` rounds, every task's changes
    interleaved in each), the ratio to the task as it trains, and MuJoCo's timers and constraint counts per physics
    step averaged over `profile_sims` randomised simulations."""
    changes = changes_named(None) if changes is None else changes
    if changes[0] is not AS_TRAINED:
        raise ValueError("the first change must be as-trained: the others are measured against it")
    if repeats < 1 or seconds <= 0 or batch < 1:
        raise ValueError(f"need repeats >= 1, seconds > 0 and batch >= 1, got {repeats}, {seconds} and {batch}")
    threads = check_threads(threads)
    say = progress or (lambda msg: None)
    runs = []
    for task in tasks:
        entry = task_entry(task)
        for change in changes:
            if not change.applies(entry.config):
                continue
            say(f"{task}: building {change.name}")
            env = learner_env(entry, make(task, change.edit(entry.config)))
            natives = NativeEnvs(env, batch, threads)
            runs.append((task, change, natives, random_controls(natives, seed)))
    speeds: dict[tuple[str, str], list[float]] = {(t, c.name): [] for t, c, _, _ in runs}
    for r in range(repeats):
        for task, change, natives, ctrls in runs:
            say(f"round {r + 1}/{repeats}: {task} {change.name}, {seconds:.0f} s at batch {batch}")
            speeds[(task, change.name)].append(step_rate(natives.physics.batch, ctrls, natives.physics.n_substeps,
                                                         seconds))
    records = []
    for task, change, natives, _ in runs:
        median = statistics.median(speeds[(task, change.name)])
        reference = statistics.median(speeds[(task, AS_TRAINED.name)])
        finite = bool(np.isfinite(natives.physics.batch.bind("qpos")).all())
        records.append({"task": task, "change": change.name, "description": change.description, "batch": batch,
                        "threads": threads, "env_steps_per_s": round(median, 1),
                        "ratio_vs_as_trained": round(median / reference, 3),
                        "rounds": [round(s, 1) for s in speeds[(task, change.name)]], "finite": finite,
                        "profile": _mean_profile(natives, profile_sims, profile_steps), **machine()})
    flat = {r["change"]: r["env_steps_per_s"] for r in records if r["task"] == "go1-flat"}
    for r in records:  # the task's pace against go1-flat's under the same change, where both ran
        if r["task"] != "go1-flat" and r["change"] in flat:
            r["ratio_vs_go1_flat"] = round(r["env_steps_per_s"] / flat[r["change"]], 3)
    return records


def print_setting_table(records: list[dict]) -> None:
    """`legged bench settings`'s table: one line per task and change."""
    for r in records:
        p = r["profile"]
        flat = f"  {r['ratio_vs_go1_flat']:4.2f}x go1-flat" if "ratio_vs_go1_flat" in r else ""
        print(f"{r['task']:20s} {r['change']:16s} {r['env_steps_per_s']:9,.0f} env-steps/s "
              f"{r['ratio_vs_as_trained']:5.2f}x  step {p['step_us']:5.1f} us (constraint {p['constraint_us']:4.1f}, "
              f"collision {p['pos_collision_us']:4.1f})  contacts {p['contacts']:5.1f}  "
              f"rows {p['constraint_rows']:5.1f}"
              f"  iterations {p['solver_iterations']:4.2f}{flat}" + ("" if r["finite"] else "  NOT FINITE"))
