"""Throughput benchmark: env steps per second of a task on MJX and on native MuJoCo at several batch sizes,
beside bare native physics and (optionally) a peer, all measured in one run."""

from __future__ import annotations

import copy
import dataclasses
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from legged import mjx_collisions
from legged.envs.native import NativeEnvs, check_threads
from legged.envs.vector import VectorEnv
from legged.tasks import learner_env, make, task_entry


def time_calls(fn, state, seconds: float) -> tuple[object, int, float]:
    """Call fn repeatedly for about `seconds`; returns the last state, calls made and elapsed time."""
    calls, t0 = 0, time.perf_counter()
    while True:
        state = fn(state)
        calls += 1
        if calls % 4 == 0:
            jax.block_until_ready(state)
            if time.perf_counter() - t0 >= seconds:
                break
    jax.block_until_ready(state)
    return state, calls, time.perf_counter() - t0


PHYSICS_CHOICES = ("mjx", "native", "rollout", "mjx-stock")
"""What `legged bench env --physics` measures: the task on MJX, the task on native MuJoCo, bare native physics of
the same model (no observations, rewards or policy: the physical limit of these cores), and the task on MJX with
MJX's own sphere-height-field collision, which the project replaces (legged.mjx_collisions: what that costs)."""


def _random_actions(env, batch: int, seed: int, count: int = 8) -> list[jax.Array]:
    """A few fixed random action batches in [-1, 1], cycled by the timing loops (no RNG in the loop)."""
    rng = np.random.default_rng(seed)
    return [jnp.asarray(rng.uniform(-1, 1, (batch, env.action_size)), jnp.float32) for _ in range(count)]


def bench_vector(env, physics: str, batch: int, seconds: float, seed: int, threads: int) -> dict:
    """env-steps/s of the auto-resetting vector env on one engine, with random actions."""
    if physics == "mjx-stock":
        env.mjx_model  # built (which installs the project's collision) before MJX's own is put back for this run
        with mjx_collisions.mjx_own():
            return bench_vector(env, "mjx", batch, seconds, seed, threads)
    t0 = time.perf_counter()
    vector = VectorEnv(env, batch, physics, threads)
    actions = _random_actions(env, batch, seed)
    state = vector.reset(jax.random.PRNGKey(seed))
    state, _ = vector.step(state, actions[0])
    jax.block_until_ready(state.state.reward)
    compile_s = time.perf_counter() - t0
    k = [0]

    def advance(b):
        k[0] += 1
        return vector.step(b, actions[k[0] % len(actions)])[0]

    state, calls, elapsed = time_calls(advance, state, seconds)
    diverged = state.state.metrics.get("diverged")
    return {"env_steps_per_s": round(calls * batch / elapsed, 1), "compile_s": round(compile_s, 2),
            "finite": bool(jnp.all(jnp.isfinite(state.state.obs["state"]))),
            "diverged_fraction": None if diverged is None else round(float(jnp.mean(diverged)), 4)}


def random_controls(native: NativeEnvs, seed: int) -> list[np.ndarray]:
    """The servo targets (actuator controls) of a few fixed random action batches for the simulations of `native`,
    reset with `seed`, as the task's servos turn actions into them (a latency schedule: its targets)."""
    state = native.reset(jax.random.split(jax.random.PRNGKey(seed), native.num_envs))
    ctrls = [np.asarray(native.controls(state, a)) for a in _random_actions(native.env, native.num_envs, seed)]
    return [c[:, -1] if c.ndim == 3 else c for c in ctrls]


def step_rate(batch, ctrls: list[np.ndarray], n_substeps: int, seconds: float) -> float:
    """Control steps per second, all simulations counted, of a `mujoco.batch.Batch` stepped `n_substeps` physics
    steps at a time for `seconds`, the `ctrls` cycled over the control steps."""
    ctrl, steps, t0 = batch.bind("ctrl"), 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        ctrl[:] = ctrls[steps % len(ctrls)]
        batch.step(nstep=n_substeps)
        steps += 1
    return steps * batch.nsim / (time.perf_counter() - t0)


def bench_rollout(env, batch: int, seconds: float, seed: int, threads: int) -> dict:
    """Control steps per second of bare native physics: the task's model and spawns, random PD targets,
    `n_substeps` substeps per control step, nothing else."""
    native = NativeEnvs(env, batch, threads)
    ctrls = random_controls(native, seed)
    rate = step_rate(native.physics.batch, ctrls, native.physics.n_substeps, seconds)
    return {"env_steps_per_s": round(rate, 1), "compile_s": 0.0}


def randomized(entry, enabled: bool | None):
    """The task's default config with its domain randomisation on or off (None: as the task has it)."""
    if enabled is None:
        return entry.config
    return dataclasses.replace(entry.config, randomization=dataclasses.replace(entry.config.randomization,
                                                                               enabled=enabled))


def cpu_model() -> str:
    """The CPU's model name (from /proc/cpuinfo where there is one)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine() -> dict:
    """The CPU model and the cores this process may use, for a benchmark's record."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return {"cpu": cpu_model(), "cores": cores}


def mid_episode_states(env, count: int = 8, seed: int = 0, steps: int = 50) -> list[mujoco.MjData]:
    """`count` forward-computed MjData of the environment after `steps` control steps of random actions from its
    spawns (contacts made, the robot moving), for MuJoCo's timers."""
    native = NativeEnvs(env, count, threads=1)
    state = native.reset(jax.random.split(jax.random.PRNGKey(seed), count))
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        state = native.step(state, jnp.asarray(rng.uniform(-0.5, 0.5, (count, env.action_size)), jnp.float32))
    return [native.data(i) for i in range(count)]


PROFILE_TIMERS = ("step", "forward", "position", "pos_kinematics", "pos_inertia", "pos_collision", "col_broad",
                  "col_narrow", "pos_make", "pos_project", "velocity", "actuation", "constraint", "advance")
"""MuJoCo's timers (mjData.timer, mjtTimer without its prefix) a physics profile reports, the step first."""


def physics_profile(model: mujoco.MjModel, datas: list[mujoco.MjData], steps: int) -> dict:
    """Where MuJoCo's C engine spends a physics step of `model`, from `steps` steps of each state in `datas` (e.g.
    environments in the middle of their episodes) with their controls held: microseconds per step of each of
    PROFILE_TIMERS on one thread, and the mean contacts, constraint rows and solver iterations per step."""
    totals = dict.fromkeys(PROFILE_TIMERS, 0.0)
    ncon = nefc = niter = count = 0
    for data in datas:
        data = copy.copy(data)
        for i in range(mujoco.mjtTimer.mjNTIMER):
            data.timer[i].duration, data.timer[i].number = 0.0, 0
        for _ in range(steps):
            mujoco.mj_step(model, data)
            ncon, nefc, niter, count = ncon + data.ncon, nefc + data.nefc, niter + int(data.solver_niter[0]), count + 1
        for name in PROFILE_TIMERS:
            totals[name] += data.timer[getattr(mujoco.mjtTimer, f"mjTIMER_{name.upper()}")].duration
    return {"physics_steps": count, **{f"{k}_us": round(1e6 * v / max(count, 1), 2) for k, v in totals.items()},
            "contacts": round(ncon / max(count, 1), 2), "constraint_rows": round(nefc / max(count, 1), 2),
            "solver_iterations": round(niter / max(count, 1), 2), "solver": mujoco.mjtSolver(model.opt.solver).name,
            "iterations_limit": int(model.opt.iterations), "timestep": float(model.opt.timestep)}


def bench_env(task: str, batches: list[int], seconds: float = 3.0, seed: int = 0, physics=("mjx", "native"),
              threads: int | None = None, progress=None, randomize: tuple[str, ...] = ("default",)) -> list[dict]:
    """One record per (randomisation, physics, batch size): env_steps_per_s (the training env: soccer tasks step the
    learner's view against the script), compile_s, and the ratios to MJX and to bare rollout physics measured in
    the same run. `randomize`: the task's default config, or its domain randomisation `on` or `off` (each record
    with it on gets `ratio_vs_off` where both ran)."""
    entry = task_entry(task)
    for p in physics:
        if p not in PHYSICS_CHOICES:
            raise ValueError(f"unknown physics {p!r}; choose from {', '.join(PHYSICS_CHOICES)}")
        if p != "rollout":
            entry.check(physics="mjx" if p == "mjx-stock" else p)
    for r in randomize:
        if r not in ("default", "on", "off"):
            raise ValueError(f"--randomize takes default, on or off, not {r!r}")
    threads = check_threads(threads)
    records, runs = [], {}
    for setting in randomize:
        env = learner_env(entry, make(task, randomized(entry, None if setting == "default" else setting == "on")))
        for batch in batches:
            by_physics = {}
            for p in physics:
                if progress:
                    progress(f"{task}: randomisation {setting}, {p}, batch {batch}: compiling and timing for "
                             f"{seconds:.0f} s")
                r = bench_rollout(env, batch, seconds, seed, threads) if p == "rollout" else \
                    bench_vector(env, p, batch, seconds, seed, threads)
                by_physics[p] = r = {"task": task, "batch": batch, "physics": p, **r,
                                     "threads": None if p.startswith("mjx") else threads, "ctrl_dt": env.dt,
                                     "backend": jax.default_backend(), "randomize": setting}
                records.append(r)
                runs[(setting, p, batch)] = r
            for p, r in by_physics.items():
                for base in ("mjx", "rollout"):
                    if base in by_physics and base != p:
                        r[f"ratio_vs_{base}"] = round(r["env_steps_per_s"] / by_physics[base]["env_steps_per_s"], 3)
    for (setting, p, batch), r in runs.items():
        if setting == "on" and ("off", p, batch) in runs:
            r["ratio_vs_off"] = round(r["env_steps_per_s"] / runs[("off", p, batch)]["env_steps_per_s"], 3)
    return records


PEER_ENVS = {"go1-flat": "Go1JoystickFlatTerrain", "go1-rough": "Go1JoystickRoughTerrain"}
"""The MuJoCo Playground environment each task is measured beside; other tasks (the confined ones) beside the rough
joystick, the nearest Playground has."""


def peer_env(task: str) -> str:
    """The Playground environment `task` is compared with (PEER_ENVS)."""
    return PEER_ENVS.get(task, "Go1JoystickRoughTerrain")


def bench_peer(python: str, script: str | None, batches: list[int], seconds: float,
               envs: tuple[str, ...] = ("Go1JoystickRoughTerrain",)) -> dict[tuple[str, int], dict]:
    """Run MuJoCo Playground's Go1 environments `envs` (legged/peers/playground.py, with the peer's `python`) and
    index them by (environment, batch)."""
    script = script or str(Path(__file__).with_name("peers") / "playground.py")
    if not Path(python).is_file():
        raise FileNotFoundError(f"peer python not found: {python} (build it with bash "
                                f"{Path(__file__).with_name('peers') / 'setup_playground.sh'})")
    cmd = [python, script, ",".join(map(str, batches)), "--envs", ",".join(dict.fromkeys(envs)),
           "--seconds", str(seconds)]
    out = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if out.returncode != 0:
        raise RuntimeError(f"peer benchmark failed ({' '.join(cmd)}):\n{out.stderr[-2000:]}")
    rows = [json.loads(line) for line in out.stdout.splitlines() if line.startswith("{")]
    return {(r["env"], r["batch"]): r for r in rows}


def attach_peer(records: list[dict], peer: dict[tuple[str, int], dict]) -> None:
    """Add the peer's figure and our/peer ratio to each MJX record whose task's peer environment (peer_env) ran at
    its batch."""
    for r in records:
        p = peer.get((peer_env(r["task"]), r["batch"]))
        if p and r.get("physics") == "mjx":
            r["peer"] = p["env"]
            r["peer_env_steps_per_s"] = p["env_steps_per_s"]
            r["ratio_vs_peer"] = round(r["env_steps_per_s"] / p["env_steps_per_s"], 3)


def print_table(records: list[dict], file=sys.stdout) -> None:
    """Human-readable table of benchmark records."""
    print(f"{'task':20s} {'physics':8s} {'batch':>6s} {'env steps/s':>12s} {'compile s':>10s} {'vs mjx':>7s} "
          f"{'vs rollout':>10s} {'peer/s':>8s}", file=file)
    nan = float("nan")
    for r in records:
        print(f"{r['task']:20s} {r['physics']:8s} {r['batch']:6d} {r['env_steps_per_s']:12.0f} {r['compile_s']:10.1f} "
              f"{r.get('ratio_vs_mjx', nan):7.2f} {r.get('ratio_vs_rollout', nan):10.2f} "
              f"{r.get('peer_env_steps_per_s', nan):8.0f}", file=file)


def soak(task: str, steps: int, batch: int = 256, seed: int = 0, physics: str = "native",
         threads: int | None = None, progress=None) -> dict:
    """Stress a task: `steps` env steps of random actions, half of them extreme (+-action_clip, bang-bang),
    with domain randomisation on where the task has it. Counts the non-finite values that reach a learner
    (observations and rewards after auto-reset), the episodes ended by divergence, and all episodes."""
    entry = task_entry(task)
    entry.check(physics=physics)
    env = learner_env(entry, make(task, randomized(entry, True)))
    vector = VectorEnv(env, batch, physics, threads)
    rng = np.random.default_rng(seed)
    clip = float(env.config.action_clip)
    state = vector.reset(jax.random.PRNGKey(seed))
    non_finite = episodes = diverged = 0
    t0, done_steps, k = time.perf_counter(), 0, 0
    while done_steps < steps:
        if k % 2:
            action = clip * np.sign(rng.uniform(-1, 1, (batch, env.action_size)))
        else:
            action = rng.uniform(-1, 1, (batch, env.action_size))
        state, result = vector.step(state, jnp.asarray(action, jnp.float32))
        leaves = [np.asarray(x) for x in jax.tree_util.tree_leaves((result.obs, result.reward))]
        non_finite += int(sum((~np.isfinite(x)).sum() for x in leaves))
        ended = np.asarray(result.done)
        episodes += int(ended.sum())
        if "diverged" in result.finished:
            diverged += int((np.asarray(result.finished["diverged"]) > 0).sum())
        done_steps += batch
        k += 1
        if progress and k % 200 == 0:
            progress(f"{task}: {done_steps:,} / {steps:,} steps, {episodes} episodes, {diverged} diverged")
    elapsed = time.perf_counter() - t0
    return {"task": task, "physics": physics, "batch": batch, "env_steps": done_steps,
            "randomization": True,
            "non_finite_values": non_finite, "episodes": episodes, "diverged_episodes": diverged,
            "env_steps_per_s": round(done_steps / elapsed, 1), "seed": seed}
