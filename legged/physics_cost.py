"""What each physics setting costs: a task's native model stepped as it trains and with one setting changed at a
time (solver, iterations, friction cone, contact dimensions, joint friction, damping, Jacobian), side by side in
one process, from the same states under the same controls.

The figures are costs only: a cheaper setting is worth keeping where the trained policies still meet their
reference-robot figures under it, which this benchmark does not measure (`legged eval --compare-robots`,
`legged bench navigate` do).
"""

from __future__ import annotations

import copy
import dataclasses
import statistics
from typing import Callable

import mujoco
import numpy as np
from mujoco.batch import Batch

from legged.bench import machine, mid_episode_states, physics_profile, random_controls, randomized, step_rate
from legged.envs.native import NativeEnvs, check_threads
from legged.tasks import learner_env, make, task_entry


def _set_opt(**fields) -> Callable[[mujoco.MjModel], None]:
    def edit(model: mujoco.MjModel) -> None:
        for name, value in fields.items():
            setattr(model.opt, name, value)
    return edit


def _other_cone(model: mujoco.MjModel) -> None:
    pyramidal = model.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL
    model.opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC if pyramidal else mujoco.mjtCone.mjCONE_PYRAMIDAL


def _condim_3(model: mujoco.MjModel) -> None:
    model.geom_condim[model.geom_condim > 3] = 3
    if model.npair:
        model.pair_dim[model.pair_dim > 3] = 3


def _no_frictionloss(model: mujoco.MjModel) -> None:
    model.dof_frictionloss[:] = 0.0


def _no_eulerdamp(model: mujoco.MjModel) -> None:
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP)


def _other_ccd(model: mujoco.MjModel) -> None:
    model.opt.disableflags ^= int(mujoco.mjtDisableBit.mjDSBL_NATIVECCD)


def _skip_pairs(named: Callable[[str, str], bool]) -> Callable[[mujoco.MjModel], None]:
    """Contact pairs whose geoms' names satisfy `named` never reach the narrow phase: a margin far below zero fails
    their bounding-volume test (a diagnostic of what those pairs cost; the task needs them)."""
    def edit(model: mujoco.MjModel) -> None:
        for i in range(model.npair):
            g1, g2 = (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(g)) or ""
                      for g in (model.pair_geom1[i], model.pair_geom2[i]))
            if named(g1, g2):
                model.pair_margin[i] = -1e3
    return edit


@dataclasses.dataclass(frozen=True)
class Variant:
    """One change of a model's physics settings."""

    name: str
    """Short name (the command line's --variants)."""
    description: str
    """What it changes, in a few words."""
    edit: Callable[[mujoco.MjModel], None]
    """Applies the change to a copy of the model, in place."""


AS_TRAINED = Variant("as-trained", "the task's model as it trains (nominal: no randomisation draws)", lambda m: None)
VARIANTS = (
    AS_TRAINED,
    Variant("cg", "conjugate-gradient solver instead of the model's", _set_opt(solver=mujoco.mjtSolver.mjSOL_CG)),
    Variant("pgs", "projected Gauss-Seidel solver instead of the model's", _set_opt(solver=mujoco.mjtSolver.mjSOL_PGS)),
    Variant("iterations-1", "one solver iteration and one line-search iteration at most",
            _set_opt(iterations=1, ls_iterations=1)),
    Variant("other-cone", "the other friction cone (pyramidal <-> elliptic)", _other_cone),
    Variant("condim-3", "contacts of at most 3 dimensions: no torsional or rolling friction", _condim_3),
    Variant("no-frictionloss", "no joint dry friction (its constraint rows gone)", _no_frictionloss),
    Variant("no-eulerdamp", "joint damping integrated explicitly (mjDSBL_EULERDAMP)", _no_eulerdamp),
    Variant("sparse-jacobian", "sparse constraint Jacobian (the model's: auto)",
            _set_opt(jacobian=mujoco.mjtJacobian.mjJAC_SPARSE)),
    Variant("other-ccd", "the other convex collider (MuJoCo's native GJK/EPA <-> libccd's MPR; the confined scenes "
                         "use libccd: the native one wedged feet in height fields)", _other_ccd),
    Variant("ccd-loose", "convex collisions to 1 mm in at most 10 iterations (the model's: 1e-6 m, 35)",
            _set_opt(ccd_tolerance=1e-3, ccd_iterations=10)),
    Variant("no-ceiling-pairs", "diagnostic: the ceiling's contact pairs skipped (what they cost)",
            _skip_pairs(lambda a, b: "ceiling" in (a, b))),
    Variant("no-trunk-pairs", "diagnostic: the trunk's contact pairs with the terrain skipped (what they cost)",
            _skip_pairs(lambda a, b: a.startswith("trunk") or b.startswith("trunk"))),
)
"""Every variant the benchmark knows, the model as it trains first."""


def picked(every: tuple, names: list[str] | None, kind: str) -> list:
    """The items of `every` (each with a `name`, the reference first) named in `names` (None: all), the reference
    always first and each once; an unknown name is one clear error naming the `kind` of item."""
    if names is None:
        return list(every)
    known = {item.name: item for item in every}
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"unknown {kind}(s) {', '.join(unknown)}; choose from {', '.join(known)}")
    return [every[0]] + [known[n] for n in dict.fromkeys(names) if n != every[0].name]


def variants_named(names: list[str] | None) -> list[Variant]:
    """The variants of `names` (None: all), as-trained always first; an unknown name is one clear error."""
    return picked(VARIANTS, names, "physics variant")


def variant_model(model: mujoco.MjModel, variant: Variant) -> mujoco.MjModel:
    """A copy of `model` with `variant`'s change."""
    out = copy.deepcopy(model)
    variant.edit(out)
    return out


def _time_variant(model, starts: list[mujoco.MjData], ctrls: list[np.ndarray], n_substeps: int, threads: int,
                  seconds: float) -> dict:
    """Control steps per second of `model` in a batch started from `starts` (cycled over the batch) under the
    `ctrls` (cycled over the steps; legged.bench.step_rate), and whether every simulation stayed finite."""
    batch = Batch(model, len(ctrls[0]), nthread=threads)
    rows = np.arange(batch.nsim) % len(starts)
    batch.bind("qpos")[:] = np.stack([d.qpos for d in starts])[rows]
    batch.bind("qvel")[:] = np.stack([d.qvel for d in starts])[rows]
    batch.forward()
    rate = step_rate(batch, ctrls, n_substeps, seconds)
    return {"env_steps_per_s": rate, "finite": bool(np.isfinite(batch.bind("qpos")).all())}


def physics_cost(env, batch: int = 1024, threads: int = 2, seconds: float = 5.0, repeats: int = 3, seed: int = 0,
                 variants: list[Variant] | None = None, profile_steps: int = 200, progress=None) -> list[dict]:
    """One record per variant of `env`'s native model (nominal, randomisation off): control steps per second at
    `batch` simulations and `threads` threads (median of `repeats` rounds, the variants interleaved in each round so
    that a machine's drift touches them alike), the ratio to the model as it trains, MuJoCo's timers and constraint
    counts of a physics step (legged.bench.physics_profile), and whether it stayed finite."""
    variants = variants_named(None) if variants is None else variants
    if variants[0] is not AS_TRAINED:
        raise ValueError("the first variant must be as-trained: the others are measured against it")
    if repeats < 1 or seconds <= 0:
        raise ValueError(f"need repeats >= 1 and seconds > 0, got {repeats} and {seconds}")
    threads = check_threads(threads)
    say = progress or (lambda msg: None)
    base = env.native_model()
    starts = mid_episode_states(env, 8, seed)
    ctrls = random_controls(NativeEnvs(env, batch, threads=1), seed)
    models = [variant_model(base, v) for v in variants]
    speeds = {v.name: [] for v in variants}
    finite = {v.name: True for v in variants}
    for r in range(repeats):
        for v, model in zip(variants, models):
            say(f"round {r + 1}/{repeats}: {v.name}, {seconds:.0f} s at batch {batch}")
            out = _time_variant(model, starts, ctrls, env.config.n_substeps, threads, seconds)
            speeds[v.name].append(out["env_steps_per_s"])
            finite[v.name] &= out["finite"]
    reference = statistics.median(speeds[AS_TRAINED.name])
    records = []
    for v, model in zip(variants, models):
        datas = []
        for d in starts:
            data = mujoco.MjData(model)
            data.qpos[:], data.qvel[:], data.ctrl[:] = d.qpos, d.qvel, d.ctrl
            mujoco.mj_forward(model, data)
            datas.append(data)
        median = statistics.median(speeds[v.name])
        records.append({"variant": v.name, "description": v.description, "batch": batch, "threads": threads,
                        "env_steps_per_s": round(median, 1),
                        "physics_steps_per_s": round(median * env.config.n_substeps, 1),
                        "ratio_vs_as_trained": round(median / reference, 3),
                        "rounds": [round(s, 1) for s in speeds[v.name]], "finite": finite[v.name],
                        "profile": physics_profile(model, datas, profile_steps), **machine()})
    return records


def bench_physics(tasks: list[str], variants: list[Variant] | None = None, progress=None, **kwargs) -> list[dict]:
    """physics_cost of each task's nominal model (randomisation off), one record per task and variant; `kwargs` go
    to physics_cost."""
    records = []
    for task in tasks:
        entry = task_entry(task)
        env = learner_env(entry, make(task, randomized(entry, False)))
        say = progress and (lambda msg, t=task: progress(f"{t}: {msg}"))
        records += [{"task": task, **r} for r in physics_cost(env, variants=variants, progress=say, **kwargs)]
    return records


def print_cost_table(records: list[dict]) -> None:
    """`legged bench physics`'s table: one line per variant."""
    for r in records:
        p = r["profile"]
        print(f"{r.get('task', ''):20s} {r['variant']:16s} {r['env_steps_per_s']:9,.0f} env-steps/s "
              f"{r['ratio_vs_as_trained']:5.2f}x  step {p['step_us']:5.1f} us (constraint {p['constraint_us']:4.1f}, "
              f"collision {p['pos_collision_us']:4.1f})  rows {p['constraint_rows']:5.1f}  "
              f"iterations {p['solver_iterations']:4.2f}" + ("" if r["finite"] else "  NOT FINITE"))
